#!/usr/bin/env bash
# MSAA and transparency benchmarks on the GPU machine (see ../shared/gpu/README.md):
# Forward+ against tiled deferred, each without MSAA and at 4× (8× where the adapter has
# it), on AMD's atrium at 1920x1080 with 1,024, 2,048 and 4,096 lights
# (benches/sweeps/msaa.ron, msaa_8x.ron; each graph's error against brute force at its
# own sample count), and transparency's cost on the glass scene
# (benches/sweeps/transparency.ron); single renders print per-pass times and the memory
# each technique adds. Results are packed into $OUT/results.tar.gz; the summary is printed.
# Usage from the project root after ../shared/gpu/prepare.sh target/release/lightgraph:
#   scripts/gpu_bench_msaa.sh        (about 8 minutes at most: every step has a timeout)
set -u
source "$(dirname "$0")/gpu_env.sh"
for g in forward_plus tiled_deferred_prepass msaa tiled_deferred_msaa msaa_8x tiled_deferred_msaa_8x; do
    timeout 60 $lg render --scene scenes/atrium_amd.ron --graph graphs/$g.ron --out "$out/atrium_amd_$g.png" \
        > "$out/render_atrium_amd_$g.txt" 2>&1
done
for g in forward_plus transparent transparent_msaa; do
    timeout 60 $lg render --scene scenes/glass.ron --graph graphs/$g.ron --out "$out/glass_$g.png" \
        > "$out/render_glass_$g.txt" 2>&1
done
timeout 240 $lg bench --sweep benches/sweeps/msaa.ron --out "$out/msaa" > "$out/msaa.log" 2>&1
timeout 120 $lg bench --sweep benches/sweeps/msaa_8x.ron --out "$out/msaa_8x" > "$out/msaa_8x.log" 2>&1
timeout 90 $lg bench --sweep benches/sweeps/transparency.ron --out "$out/transparency" > "$out/transparency.log" 2>&1
nvidia-smi --query-gpu=clocks.sm --format=csv >> "$out/gpu.txt" 2>&1
cat "$out"/gpu.txt "$out"/render_*.txt
for s in msaa msaa_8x transparency; do
    echo "== $s"; tail -3 "$out/$s.log"; cat "$out/$s/results.md" 2>/dev/null | head -60
done
gpu_pack
