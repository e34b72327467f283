#!/usr/bin/env bash
# Runs the benchmark sweeps and the hot-reload latency benchmark on the GPU machine (see
# ../shared/gpu/README.md); results go to $OUT (or results/). Usage from the project root
# after ../shared/gpu/prepare.sh target/release/lightgraph:
#   scripts/gpu_bench.sh
set -u
source "$(dirname "$0")/gpu_env.sh"
$lg render --out "$out/atrium.png" --heatmap "$out/atrium_heat.png" > "$out/render_atrium.txt" 2>&1
for v in forward_plus forward_plus_depth_mask forward_plus_half_z forward_plus_clustered; do
    $lg render --scene scenes/depth_discontinuity.ron --graph graphs/$v.ron > "$out/dd_$v.txt" 2>&1
done
for s in coarse seeds stress; do
    $lg bench --sweep benches/sweeps/$s.ron --out "$out/$s" > "$out/$s.log" 2>&1
done
$lg reload-bench --out "$out/reload_1080p" --width 1920 --height 1080 --lights 3072 --repeats 20 > "$out/reload_1080p.log" 2>&1
$lg reload-bench --out "$out/reload_160x90" --width 160 --height 90 --lights 1024 --repeats 10 > "$out/reload_160x90.log" 2>&1
cat "$out"/gpu.txt "$out"/coarse/results.md "$out"/reload_1080p/reload_latency.md
gpu_pack
