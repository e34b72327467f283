#!/usr/bin/env bash
# The benchmarks the docs quote, on the GPU machine (see docs/benchmarks.md). Stages
# (STAGES, default all, in this order):
#   frames    every frame kind on harada, AMD's atrium and the Cornell box glTF
#             (frame_kinds_*.ron), Forward+'s tile tests (forward_plus_culling.ron), and
#             visibility shading's material classification (material_classification.ron)
#             and light walk (light_walk.ron);
#   features  ray-cast shadows, the shadow atlas, transparency, MSAA, VPL indirect light, VPL visibility
#             and the light linked list (their sweeps);
#   stochastic (only when named) stochastic direct lighting's time against error with the
#             spread over seeds, one sweep a scene (stochastic_seeds_*.ron);
#   extras    the VPL bounce against its path-traced reference (vpl-error: Forward+ and the
#             compute-first frame at 256 rays; default.ron with and without visibility, and
#             the cheaper VPLs, each on one time-vs-error plot at 1,024 rays) and hot-reload
#             latency (reload-bench).
# Each sweep's CSV, Markdown and plots go to $OUT/r/<sweep>/ (or results/r/), packed into
# results.tar.gz after every sweep, so a cut-off run still brings back what it finished.
# Usage from the project root, after `../shared/gpu/prepare.sh target/release/lightgraph`
# and `xz -T2 -c .gpu/lightgraph > .gpu/lightgraph.xz && rm .gpu/lightgraph`:
#   STAGES=frames scripts/gpu_bench.sh
# then copy the CSVs into bench/results/ and regenerate the docs' tables:
#   LIGHTGRAPH_BLESS=1 cargo test --release --test docs_tables
set -u
source "$(dirname "$0")/gpu_env.sh"
stages=" ${STAGES:-frames features extras} "
if [[ $stages == *" frames "* ]]; then
    run_sweep frame_kinds_harada frame_kinds_harada 300
    run_sweep frame_kinds_atrium frame_kinds_atrium 120
    run_sweep frame_kinds_cornell frame_kinds_cornell 120
    run_sweep forward_plus_culling forward_plus_culling 150
    run_sweep material_classification material_classification 200
    run_sweep light_walk light_walk 200
fi
if [[ $stages == *" features "* ]]; then
    for s in raycast_shadows shadow_atlas transparency msaa indirect_vpl vpl_visibility vpl_cheaper light_linked_list; do
        run_sweep $s $s 150
    done
fi
if [[ $stages == *" stochastic "* ]]; then
    for s in harada gallery chairs harada_65536; do
        run_sweep stochastic_seeds_$s stochastic_seeds_$s 300
        awk '/^Spread over seeds/{f=1} f&&/^\|/{t=1;print;next} t{exit}' \
            "$out/stochastic_seeds_$s/results.md" 2>/dev/null | cut -c1-200
    done
fi
if [[ $stages == *" extras "* ]]; then
    timeout 330 $lg vpl-error --scene scenes/cornell_indirect.ron scenes/atrium_indirect.ron \
        --width 1920 --height 1080 --samples 256 --frames 10 --out "$out/vpl_error" > "$out/vpl_error.log" 2>&1
    echo "== vpl_error (rc $?)"; cat "$out/vpl_error/results.md" 2>/dev/null | head -20
    # The same bounce in the compute-first frame, with VPL visibility (8×8-pixel blocks).
    timeout 330 $lg vpl-error --scene scenes/cornell_indirect.ron scenes/atrium_indirect.ron \
        --width 1920 --height 1080 --samples 256 --frames 10 --graph graphs/visibility_indirect_vpl.ron \
        --error-graph benches/graphs/visibility_indirect_vpl_all_lights.ron \
        --direct graphs/visibility_compute_raster.ron --out "$out/vpl_error_visibility" > "$out/vpl_error_visibility.log" 2>&1
    echo "== vpl_error_visibility (rc $?)"; cat "$out/vpl_error_visibility/results.md" 2>/dev/null | head -20
    # vpl_error_1080p LABEL LIMIT_S VARIANT...: the bounce on the Cornell box and the atrium
    # at 1920x1080 against the path-traced one with 1,024 reference rays a pixel (the
    # reference is deterministic: every call traces the same), the variants (each a
    # --variant text) on one time-vs-error plot.
    vpl_error_1080p() {
        local label=$1 limit=$2 v variants=()
        shift 2
        for v in "$@"; do variants+=(--variant "$v"); done
        timeout "$limit" $lg vpl-error --scene scenes/cornell_indirect.ron scenes/atrium_indirect.ron \
            --width 1920 --height 1080 --n 4,8,16 --samples 1024 --no-noise --frames 10 \
            --direct graphs/visibility_compute_raster.ron "${variants[@]}" \
            --out "$out/$label" > "$out/$label.log" 2>&1
        echo "== $label (rc $?)"; sed -n '/^| variant/,/^$/p' "$out/$label/results.md"
        pack
    }
    # default.ron without visibility, as shipped (8x8 blocks) and with 16x16 blocks
    # (docs/indirect_light.md, "Measured cost (GPU)").
    vpl_error_1080p vpl_error_1080p 400 \
        "label=no visibility;graph=benches/graphs/default_no_visibility.ron;error_graph=benches/graphs/default_all_lights_no_visibility.ron" \
        "label=8x8 blocks (default.ron);graph=graphs/default.ron;error_graph=benches/graphs/default_all_lights.ron" \
        "label=16x16 blocks;graph=benches/graphs/default_block16.ron;error_graph=benches/graphs/default_all_lights_block16.ron"
    # The cheaper VPLs (docs/indirect_light.md, "Cheaper VPLs"): every VPL as spawned, the
    # disc falloff, min_flux, merging, both of default.ron's.
    vis="graph=graphs/visibility_indirect_vpl.ron;error_graph=benches/graphs/visibility_indirect_vpl_all_lights.ron"
    vpl_error_1080p vpl_cheaper_1080p 560 \
        "label=clamp;$vis" \
        "label=disc;$vis;spawn=falloff: Disc" \
        "label=min_flux 1e-4;$vis;spawn=min_flux: 0.0001" \
        "label=merge 2;$vis;spawn=merge: 2" \
        "label=disc and min_flux (default.ron);$vis;spawn=min_flux: 0.0001, falloff: Disc"
    timeout 150 $lg reload-bench --out "$out/reload_latency" --width 1920 --height 1080 \
        --lights 3072 --repeats 20 > "$out/reload_latency.log" 2>&1
    echo "== reload_latency (rc $?)"; cat "$out/reload_latency/reload_latency.md" 2>/dev/null | head -20
    pack
fi
nvidia-smi --query-gpu=clocks.sm --format=csv >> "$out/gpu.txt" 2>&1
# The commit the binary was built from (written by the caller: git has no copy here).
cp .gpu/commit.txt "$out/" 2>/dev/null || true
gpu_pack
