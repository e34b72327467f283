#!/usr/bin/env bash
# One-bounce indirect light (VPL) benchmarks on the GPU machine (see ../shared/gpu/README.md):
#  1. the indirect_vpl sweep: the built-in atrium (1,024 lights) at 1920x1080 with 1, 8
#     and 32 indirect spot lights of 256 VPLs each, per-pass GPU medians of 20 frames for
#     the maps (rsm), the spawn (vpl_spawn), culling and shading, and Forward+ without
#     VPLs on the same scenes; tiled deferred with and without VPLs likewise;
#  2. single renders of those scenes through both VPL graphs (PNG, and render's
#     VPL and culling lines: spawned, dropped, lists overflowed);
#  3. the error sweep `lightgraph vpl-error`: the Cornell box and the atrium at 1920x1080,
#     n = 4, 8, 16, 32 (N² = 16 ... 1024 VPLs a view) against the CPU path-traced bounce
#     (256 rays a pixel, on every core), with the VPL passes' GPU times: time against error
#     (results.md, results.csv, time_vs_error.png).
# Results are packed into $OUT/results.tar.gz (or results/). Usage from the project root
# after ../shared/gpu/prepare.sh target/release/lightgraph:
#   scripts/gpu_bench_vpl.sh          all three
#   scripts/gpu_bench_vpl.sh error    only the error sweep (3.; about 3 minutes on an H200)
set -u
source "$(dirname "$0")/gpu_env.sh"
only_error=false
[ "${1:-}" = error ] && only_error=true
$only_error || for k in 1 8 32; do
    s=benches/scenes/atrium_indirect_$k.ron
    for g in indirect_vpl tiled_deferred_indirect_vpl; do
        $lg render --scene "$s" --graph graphs/$g.ron --out "$out/atrium_indirect_${k}_$g.png" \
            > "$out/render_atrium_indirect_${k}_$g.txt" 2>&1
    done
done
$only_error || timeout 200 $lg bench --sweep benches/sweeps/indirect_vpl.ron --out "$out/indirect_vpl" > "$out/indirect_vpl.log" 2>&1
timeout 330 $lg vpl-error --scene scenes/cornell_indirect.ron scenes/atrium_indirect.ron \
    --width 1920 --height 1080 --samples 256 --frames 10 --out "$out/vpl_error" > "$out/vpl_error.log" 2>&1
nvidia-smi --query-gpu=clocks.sm --format=csv >> "$out/gpu.txt" 2>&1
cat "$out"/gpu.txt "$out"/render_*.txt 2>/dev/null
cat "$out/vpl_error/results.md"
gpu_pack
