#!/usr/bin/env bash
# Ray-cast shadow benchmarks on the GPU machine (see ../shared/gpu/README.md), after
# scripts/gpu_bench.sh: the raycast_shadows sweep (chairs at 1280x720 and 1920x1080:
# Forward+ and tiled deferred with jobs + casting passes, the naive light-loop tracer,
# Forward+ unshadowed), single renders of the chairs scene with each shadow graph (PNG and
# EXR, and `render`'s casters / rays / memory / BVH lines), and the default atrium through
# raycast_shadows, which has no casters and must equal forward_plus. Results are packed
# into $OUT/results.tar.gz (or results/). Usage from the project root after
# ../shared/gpu/prepare.sh target/release/lightgraph:
#   scripts/gpu_bench_shadows.sh
set -u
source "$(dirname "$0")/gpu_env.sh"
for g in raycast_shadows tiled_deferred_raycast_shadows raycast_shadows_naive; do
    $lg render --scene scenes/chairs.ron --graph graphs/$g.ron --width 1280 --height 720 \
        --out "$out/chairs_$g.png" > "$out/render_chairs_$g.txt" 2>&1
    $lg render --scene scenes/chairs.ron --graph graphs/$g.ron --width 1280 --height 720 \
        --out "$out/chairs_$g.exr" > /dev/null 2>&1
done
for g in raycast_shadows tiled_deferred_raycast_shadows; do
    $lg compare "$out/chairs_$g.exr" "$out/chairs_raycast_shadows_naive.exr" \
        > "$out/compare_chairs_${g}_vs_naive.txt" 2>&1
done
$lg render --scene scenes/atrium_shadows.ron --graph graphs/raycast_shadows.ron --width 1280 --height 720 \
    --out "$out/atrium_shadows.png" > "$out/render_atrium_shadows.txt" 2>&1
for g in forward_plus raycast_shadows; do
    $lg render --graph graphs/$g.ron --out "$out/atrium_$g.exr" > "$out/render_atrium_$g.txt" 2>&1
done
$lg render --graph graphs/raycast_shadows.ron --out "$out/atrium_raycast_shadows.png" > /dev/null 2>&1
$lg compare "$out/atrium_raycast_shadows.exr" "$out/atrium_forward_plus.exr" \
    > "$out/compare_atrium_raycast_shadows_vs_forward_plus.txt" 2>&1
$lg bench --sweep benches/sweeps/raycast_shadows.ron --out "$out/raycast_shadows" \
    > "$out/raycast_shadows.log" 2>&1
$lg bench --sweep benches/sweeps/bvh_quality.ron --out "$out/bvh_quality" > "$out/bvh_quality.log" 2>&1
# The pass-kinds refactor must not slow the headline frame (1.74 ms packed, 2026-11-28).
$lg bench --sweep benches/sweeps/packed_3072.ron --out "$out/packed_3072" > "$out/packed_3072.log" 2>&1
cat "$out"/gpu.txt "$out"/bvh_quality/results.md "$out"/packed_3072/results.md "$out"/render_chairs_*.txt "$out"/compare_*.txt "$out"/raycast_shadows/results.md
# The device tool brings back few files of at most 16 MiB: pack everything but the
# EXRs (already compared above) into one archive.
rm -f "$out"/*.exr
gpu_pack
