#!/usr/bin/env bash
# Issue 17, lists that never overflow, on the GPU machine: benches/sweeps/compact_lists.ron
# (harada at 1920x1080, 3,072 and 65,536 lights: fixed lists of 256 / 1,024 against the
# shipped graphs' compact lists, in Forward+, clustered Forward+, tiled deferred after a
# prepass and the packed G-buffer; error against brute force of each shading path), then
# one render of the atrium through forward_plus.ron for the list report `render` prints.
# Results are packed into $OUT/results.tar.gz; the list table is printed.
# Usage from the project root after ../shared/gpu/prepare.sh target/release/lightgraph:
#   scripts/gpu_bench_compact.sh
set -u
source "$(dirname "$0")/gpu_env.sh"
timeout 520 $lg bench --sweep benches/sweeps/compact_lists.ron --out "$out/compact_lists" > "$out/compact_lists.log" 2>&1
echo "bench exit: $?"
timeout 30 $lg render --graph graphs/forward_plus.ron --width 1920 --height 1080 --out "$out/atrium_forward_plus.png" > "$out/render_atrium.txt" 2>&1
nvidia-smi --query-gpu=clocks.sm --format=csv >> "$out/gpu.txt" 2>&1
cat "$out"/gpu.txt
grep -h "light_culling\|WARNING" "$out"/render_atrium.txt
grep -h "^\[" "$out/compact_lists.log"
grep -A25 "Tile light lists" "$out/compact_lists/results.md"
gpu_pack
