#!/usr/bin/env bash
# Session 13 on the GPU machine. Stages (STAGES, default all, in this order):
#   products  the lobes' guarded products against every product split and against the
#             guarded products with frexp/ldexp (.gpu/roots from scripts/session13_roots.sh,
#             as shader roots over the shipped shaders): session13_products.ron in rounds
#             of shipped, split, guarded_frexp; then per-pass times (diag_session10,
#             LIGHTGRAPH_TIME_DISPATCH=1) with shipped and split;
#   spot      spot_scale against spot_factor's division per pixel (root spot_divide),
#             diag_session13.ron alternating;
#   loops     session13_loops.ron: RangeFirst and GroupList on workgroups of 8 and 16;
#   headline  the README's headline sweeps with the shipped code: visibility_headline
#             (harada, every frame kind, 1,024 to 65,536 lights), session10_atrium and
#             session10_textured.
# Results are packed after every stage, so a cut-off run still brings back what it
# finished. Usage from the project root after ../shared/gpu/prepare.sh
# target/release/lightgraph (then `xz -T2 -c .gpu/lightgraph > .gpu/lightgraph.xz && rm
# .gpu/lightgraph`) and scripts/session13_roots.sh.
set -u
source "$(dirname "$0")/gpu_env.sh"
roots=/tmp/lg_roots
mkdir -p $roots/shipped
cp -r .gpu/roots/* $roots/
stages=" ${STAGES:-products spot loops headline} "
run() { run_sweep "$1" "$2" "$3" "$roots/$4" "${5:-}"; }
if [[ $stages == *" products "* ]]; then
    for r in 1 2; do
        for v in shipped split guarded_frexp; do
            run a${r}_$v session13_products 90 $v
        done
    done
    run d1_shipped diag_session10 30 shipped LIGHTGRAPH_TIME_DISPATCH=1
    run d2_split diag_session10 30 split LIGHTGRAPH_TIME_DISPATCH=1
fi
if [[ $stages == *" spot "* ]]; then
    for r in 1 2; do
        run spot${r}_shipped diag_session13 40 shipped
        run spot${r}_divide diag_session13 40 spot_divide
    done
fi
if [[ $stages == *" loops "* ]]; then
    run_sweep loops session13_loops 60
fi
if [[ $stages == *" headline "* ]]; then
    run visibility_headline visibility_headline 200 shipped
    # Without a root (see run_sweep).
    run_sweep session10_atrium session10_atrium 80
    run_sweep session10_textured session10_textured 80
fi
nvidia-smi --query-gpu=clocks.sm --format=csv >> "$out/gpu.txt" 2>&1
gpu_pack
