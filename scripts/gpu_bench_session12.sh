#!/usr/bin/env bash
# Session 12 on the GPU machine, one call. First culling's new coarse stage against the
# old one (.gpu/light_culling_old.wgsl, `git show a16f740:shaders/cull/light_culling.wgsl`,
# as a shader root over the shipped shaders): session12_culling.ron alternating new, old,
# new, old, then the coarse dispatch alone (LIGHTGRAPH_TIME_DISPATCH=1) with each. Then
# the README's headline sweeps with the shipped code: visibility_headline (harada, every
# frame kind, 1,024 to 65,536 lights), session10_atrium and session10_textured. Results
# are packed after every stage, so a cut-off run still brings back what it finished.
# Usage from the project root after ../shared/gpu/prepare.sh target/release/lightgraph
# and copying the old shader to .gpu/light_culling_old.wgsl.
set -u
source "$(dirname "$0")/gpu_env.sh"
roots=/tmp/lg_roots
CULL=shaders/cull/light_culling.wgsl
mkdir -p $roots/new/shaders/cull $roots/old/shaders/cull
cp .gpu/light_culling_old.wgsl $roots/old/$CULL
run() { run_sweep "$1" "$2" "$3" "$roots/$4" "${5:-}"; }
run a1_new session12_culling 80 new
run a2_old session12_culling 80 old
run a3_new session12_culling 80 new
run a4_old session12_culling 80 old
run d1_new diag_session10 30 new LIGHTGRAPH_TIME_DISPATCH=1
run d2_old diag_session10 30 old LIGHTGRAPH_TIME_DISPATCH=1
run visibility_headline visibility_headline 200 new
# Without a root: their graphs (../benches/graphs/...) are found from the graphs/ folder,
# which a root moves.
for s in session10_atrium session10_textured; do
    run_sweep $s $s 80
done
nvidia-smi --query-gpu=clocks.sm --format=csv >> "$out/gpu.txt" 2>&1
gpu_pack
