#!/usr/bin/env bash
# Session 10 on the GPU machine, one call: the compute-first frame's shading variants side
# by side (session10_shading / _atrium / _textured sweeps, interleaved), then shader
# variants, each a run of diag_session10.ron (3,072 and 65,536 lights) through a shader
# root over the shipped shaders, between two runs of the shipped shaders:
#   prefetch  light_culling.wgsl with benches/roots/culling_prefetch.patch: the culling
#        loops' loads issued a batch or more ahead of their tests (the shipped loops issue
#        each batch's loads in the batch: list entry → sphere → cone, one after the other);
#        lists bit-equal (tests/culling_exact.rs passed on it, 2026-12-03)
#   old  lobes.wgsl of session 9 (round-and-convert split: ~20 float-integer conversions
#        a light); .gpu/lobes_old.wgsl is `git show 354a123:shaders/material/lobes.wgsl`
#   C    plain dot and cross for the accurate products (inexact: what they still cost)
#   D    no BRDF per light (radiance times a constant: what the walk and radiance cost)
# and culling's coarse dispatch alone (LIGHTGRAPH_TIME_DISPATCH=1), shipped and prefetch. The results are packed after every stage, so a cut-off run still brings back
# what it finished. Usage from the project root after ../shared/gpu/prepare.sh
# target/release/lightgraph.
set -u
source "$(dirname "$0")/gpu_env.sh"
sweep() { # name [root]
    local s=$1 root=${2:-}
    timeout 60 $lg ${root:+--root $root} bench --sweep benches/sweeps/$s.ron --out "$out/$s" > "$out/$s.log" 2>&1
    echo "== $s"; tail -n 1 "$out/$s.log"
    sed -n '/^| scene | technique | params | lights | size/,/^$/p' "$out/$s/results.md" | cut -c1-230
    grep -A12 '^Per-pass GPU time' "$out/$s/results.md" | grep '^|' | cut -c1-230
    pack
}
sweep session10_shading
roots=/tmp/lg_roots
L=shaders/material/lobes.wgsl
S=shaders/visibility/staged_lights.wgsl
for v in shipped old C D prefetch; do mkdir -p $roots/$v/shaders/material $roots/$v/shaders/visibility $roots/$v/shaders/cull; done
cp .gpu/lobes_old.wgsl $roots/old/$L
CULL=shaders/cull/light_culling.wgsl
patch -o $roots/prefetch/$CULL $CULL benches/roots/culling_prefetch.patch > /dev/null ||
    { cp $CULL $roots/prefetch/$CULL && git apply --directory=$roots/prefetch benches/roots/culling_prefetch.patch; }
perl -0pe 's/(fn lg_dot\(a: vec3<f32>, b: vec3<f32>\) -> f32 \{\n)/$1    return dot(a, b);\n/; s/(fn lg_cross\(a: vec3<f32>, b: vec3<f32>\) -> vec3<f32> \{\n)/$1    return cross(a, b);\n/' $L > $roots/C/$L
perl -0pe 's/return color \+ inc.radiance \* material_eval\(m, inc.dir\);/return color + inc.radiance * 0.3;/' $S > $roots/D/$S
{ diff $L $roots/old/$L; diff $L $roots/C/$L; diff $S $roots/D/$S; diff $CULL $roots/prefetch/$CULL; } > "$out/variants.diff"
diag() { # n variant [env]
    local d="diag$1_$2"
    env ${3:-} timeout 25 $lg --root $roots/$2 bench --sweep benches/sweeps/diag_session10.ron --out "$out/$d" > "$out/$d.log" 2>&1
    echo "== $d ${3:-}"; grep -A8 '^Per-pass GPU time' "$out/$d/results.md" | grep '^|' | cut -c1-200
    pack
}
# In order of what matters most: a short device budget may cut the run.
diag 1 shipped
diag 2 prefetch
diag 3 old
sweep session10_atrium
sweep session10_textured
diag 4 shipped LIGHTGRAPH_TIME_DISPATCH=1
diag 5 prefetch LIGHTGRAPH_TIME_DISPATCH=1
diag 6 C
diag 7 D
nvidia-smi --query-gpu=clocks.sm --format=csv >> "$out/gpu.txt" 2>&1
gpu_pack
