#!/usr/bin/env bash
# Runs one fuzz target's binary, built before (`cd fuzz && cargo +nightly fuzz build -O -a
# -s none`), for SECONDS on JOBS processes: no cargo, no network. Usage:
#   scripts/fuzz_built.sh TARGET SECONDS JOBS [BIN_DIR]
# BIN_DIR defaults to fuzz/target/x86_64-unknown-linux-gnu/release. libFuzzer's fork mode
# runs JOBS children and goes on past a crash, a timeout (10 s) or an out-of-memory
# (2 GiB), leaving each input in fuzz/artifacts/TARGET/; what coverage grew lands in
# fuzz/corpus/TARGET/. At the end it prints the runs, the crashes, timeouts and
# out-of-memory inputs found, and the peak RSS; it exits 1 if any input was found.
set -euo pipefail
cd "$(dirname "$0")/.."
target="${1:?usage: scripts/fuzz_built.sh TARGET SECONDS JOBS [BIN_DIR]}"
secs="${2:?seconds}"
jobs="${3:?jobs}"
bin_dir="${4:-fuzz/target/x86_64-unknown-linux-gnu/release}"
bin="$bin_dir/$target"
[ -x "$bin" ] || { echo "no fuzz binary $bin (build it: cd fuzz && cargo +nightly fuzz build -O -a -s none)" >&2; exit 2; }
# shellcheck source=scripts/fuzz_seeds.sh
. scripts/fuzz_seeds.sh
seeds=$(fuzz_seeds "$target")
fuzz_unpack_corpus
corpus="fuzz/corpus/$target"
artifacts="fuzz/artifacts/$target"
mkdir -p "$corpus" "$artifacts"
before=$(find "$artifacts" -type f | wc -l)
log="fuzz/artifacts/$target.log"
echo "== $bin for ${secs}s on $jobs processes (log: $log)"
set +e
# Peak RSS over the whole process tree: wait4's rusage keeps the largest of the children.
# shellcheck disable=SC2086
python3 - "$bin" -fork="$jobs" -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1 \
    -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$artifacts/" "$corpus" $seeds >"$log" 2>&1 <<'PY'
import resource, subprocess, sys
code = subprocess.call(sys.argv[1:])
print(f"peak RSS of the fuzzer and its children: {resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss // 1024} MiB")
sys.exit(code)
PY
code=$?
set -e
# Fork mode's status lines: `#RUNS: cov: .. exec/s: .. oom/timeout/crash: O/T/C time: ..`.
runs=$(grep -oE '^#[0-9]+' "$log" | tr -d '#' | sort -n | tail -1 || true)
counts=$(grep -oE 'oom/timeout/crash: [0-9]+/[0-9]+/[0-9]+' "$log" | tail -1 | awk '{print $2}' || true)
rss=$(grep -oE 'peak RSS of the fuzzer and its children: [0-9]+' "$log" | grep -oE '[0-9]+$' || true)
found=$(( $(find "$artifacts" -type f | wc -l) - before ))
echo "target $target: runs ${runs:-0}, oom/timeout/crash ${counts:-0/0/0}, new inputs in $artifacts: $found, peak RSS ${rss:-?} MiB, libFuzzer exit $code"
ls -t "$artifacts" | head -"$found"
[ "$found" -eq 0 ] && [ "$code" -eq 0 ]
