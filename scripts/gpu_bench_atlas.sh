#!/usr/bin/env bash
# Shadow atlas benchmarks on the GPU machine (see ../shared/gpu/README.md): the
# shadow_atlas sweep (atrium_amd at 1920x1080 with 24, 100 and 500 casters; atlas sizes
# 2048² to 16384², both filters; ray-cast shadows as the reference and pair-error
# graphs), and single renders of atrium_amd through the atlas graphs with `render`'s
# atlas, pair-error and per-pass lines. Results are packed into $OUT/results.tar.gz.
# Usage from the project root after ../shared/gpu/prepare.sh target/release/lightgraph:
#   scripts/gpu_bench_atlas.sh
set -u
source "$(dirname "$0")/gpu_env.sh"
for s in atrium_amd; do
    for g in graphs/shadow_atlas.ron graphs/tiled_deferred_shadow_atlas.ron graphs/raycast_shadows.ron \
             benches/graphs/shadow_atlas_vs_raycast_4096.ron; do
        n=$(basename "$g" .ron)
        $lg render --scene scenes/$s.ron --graph "$g" --out "$out/${s}_$n.png" > "$out/render_${s}_$n.txt" 2>&1
    done
done
for n in 100 500; do
    $lg render --scene benches/scenes/atrium_amd_casters_$n.ron --graph benches/graphs/shadow_atlas_vs_raycast_4096.ron \
        > "$out/render_atrium_amd_casters_${n}_vs_raycast.txt" 2>&1
done
timeout 470 $lg bench --sweep benches/sweeps/shadow_atlas.ron --out "$out/shadow_atlas" > "$out/shadow_atlas.log" 2>&1
nvidia-smi --query-gpu=clocks.sm --format=csv >> "$out/gpu.txt" 2>&1
cat "$out"/gpu.txt "$out"/render_*.txt
grep -A80 "Shadow atlases" "$out/shadow_atlas/results.md"
gpu_pack
