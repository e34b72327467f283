#!/usr/bin/env bash
# Coverage-guided fuzzing of every front end with cargo-fuzz (nightly; CI stays on stable
# and may call this with a short time). Usage: scripts/fuzz.sh [SECONDS] [TARGET...]
#   targets: graph material scene gltf shader (default: all, SECONDS each, default 30)
# Each run fails on a crash, a timeout over 10 s or 2 GiB of memory; the input that did it
# is left in fuzz/artifacts/TARGET/. What coverage grew lands in fuzz/corpus/TARGET/
# (minimise it with `cargo +nightly fuzz cmin TARGET` before committing).
set -euo pipefail
cd "$(dirname "$0")/.."
secs="${1:-30}"
shift || true
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(graph material scene gltf shader)
if ! cargo +nightly fuzz --version >/dev/null 2>&1; then
    cargo +nightly install cargo-fuzz --locked
fi
# Seeds: the shipped files and the bad-input corpus, read in place (not copied).
seeds() {
    case "$1" in
        graph) echo graphs tests/bad/graphs tests/bad/hostile ;;
        material) echo materials tests/bad/materials ;;
        scene) echo scenes tests/bad/hostile ;;
        gltf) echo tests/bad/gltf tests/bad/hostile tests/bad/hostile/models ;;
        shader) echo tests/bad/shaders shaders/common shaders/examples ;;
        *) echo "unknown fuzz target $1" >&2; exit 2 ;;
    esac
}
# The committed corpus (what hours of coverage-guided runs grew, minimised with
# -merge=1, xz-compressed to stay small beside the GPU tool's 64 MiB working-tree limit)
# seeds fuzz/corpus/ the first time; later runs grow fuzz/corpus/ in place.
if [ ! -d fuzz/corpus ] && [ -f fuzz/corpus.tar.xz ]; then
    tar -xJf fuzz/corpus.tar.xz -C fuzz
fi
for t in "${targets[@]}"; do
    mkdir -p "fuzz/corpus/$t"
    echo "== fuzz $t for ${secs}s"
    # shellcheck disable=SC2046
    # No sanitizer: the code is safe Rust, so what is hunted is panics, stack overflows,
    # memory and time (ASan would double the build and slow every run).
    cargo +nightly fuzz run -s none -O "$t" "fuzz/corpus/$t" $(seeds "$t") -- \
        -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1
done
