#!/usr/bin/env bash
# The shader roots scripts/gpu_bench_session13.sh compares the shipped lobes with, made
# from git history into .gpu/roots (carried to the GPU machine):
#   split:         every product split (3845e8c, before session 13), under the signatures
#                  the material code now calls (lg_dot_guarded, lg_dirs's fourth argument,
#                  both ignored);
#   guarded_frexp: the guarded products with frexp and ldexp (af36a36), before their
#                  exponent came from the float's bits;
#   spot_divide:   common/lighting.wgsl before spot_scale (the division per pixel);
#                  spot_scale (cd539f4) measured slower and was reverted, so today this
#                  root is the shipped file.
set -euo pipefail
cd "$(dirname "$0")/.."
LOBES=shaders/material/lobes.wgsl
mkdir -p .gpu/roots/split/shaders/material .gpu/roots/guarded_frexp/shaders/material
{
    cat <<'SHIM'
const LG_S2_GUARDED: f32 = 0.0;
const LG_S2_EXACT: f32 = 0.0;
fn lg_dot_guarded(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return lg_dot(a, b);
}
SHIM
    git show 3845e8c:$LOBES | sed 's/^fn lg_dirs(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>) -> LgDirs {/fn lg_dirs(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, s2_plain_min: f32) -> LgDirs {/'
} > .gpu/roots/split/$LOBES
grep -q 's2_plain_min: f32) -> LgDirs' .gpu/roots/split/$LOBES
git show af36a36:$LOBES > .gpu/roots/guarded_frexp/$LOBES
mkdir -p .gpu/roots/spot_divide/shaders/common
git show 580b0b6:shaders/common/lighting.wgsl > .gpu/roots/spot_divide/shaders/common/lighting.wgsl
