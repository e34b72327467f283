#!/usr/bin/env bash
# Coverage-guided fuzzing of every front end with cargo-fuzz (nightly; CI stays on stable
# and may call this with a short time). Usage: scripts/fuzz.sh [SECONDS] [TARGET...]
#   targets: graph pass_parameters material scene gltf shader sweep (default: all, SECONDS
#   each, default 30). To run binaries built before, elsewhere: scripts/fuzz_built.sh.
# Each run fails on a crash, a timeout over 10 s or 2 GiB of memory; the input that did it
# is left in fuzz/artifacts/TARGET/. What coverage grew lands in fuzz/corpus/TARGET/
# (minimise it with `cargo +nightly fuzz cmin TARGET` before committing).
set -euo pipefail
cd "$(dirname "$0")/.."
secs="${1:-30}"
shift || true
targets=("$@")
# shellcheck source=scripts/fuzz_seeds.sh
. scripts/fuzz_seeds.sh
[ ${#targets[@]} -eq 0 ] && targets=("${FUZZ_TARGETS[@]}")
if ! cargo +nightly fuzz --version >/dev/null 2>&1; then
    cargo +nightly install cargo-fuzz --locked
fi
# The committed corpus (what hours of coverage-guided runs grew, minimised with
# -merge=1, xz-compressed to stay small beside the GPU tool's 64 MiB working-tree limit)
# seeds fuzz/corpus/ the first time; later runs grow fuzz/corpus/ in place.
fuzz_unpack_corpus
for t in "${targets[@]}"; do
    mkdir -p "fuzz/corpus/$t"
    echo "== fuzz $t for ${secs}s"
    # shellcheck disable=SC2046
    # No sanitizer: the code is safe Rust, so what is hunted is panics, stack overflows,
    # memory and time (ASan would double the build and slow every run). Overflow checks
    # and debug assertions on (-a): a size that wraps is a bug release builds hide.
    cargo +nightly fuzz run -s none -O -a "$t" "fuzz/corpus/$t" $(fuzz_seeds "$t") -- \
        -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1
done
