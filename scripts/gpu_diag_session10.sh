#!/usr/bin/env bash
# Diagnostic (session 10): where visibility shading's time goes after the products'
# conversions. Variants are shader roots over the shipped shaders plus the shading
# workgroup hooks, each a run of benches/sweeps/diag_session10.ron (errors against brute
# force at both counts) and one render at 3,072 lights compared with the first variant's:
#   old     lobes.wgsl as of session 9 (round-and-convert split), 8×8, per-pixel list
#   P8      the shipped lobes (bit split), 8×8
#   P16     P, 16×16 workgroups (8×4 pixel warps)
#   P8U     P, 8×8, the workgroup's list from its id
#   P16U    P, 16×16, the workgroup's list
#   C16U    plain dot and cross, 16×16, list     (inexact: what the products still cost)
#   R16U    P16U with one reciprocal for lg_dirs' divisions (inexact to the last bits)
#   D16U    no BRDF per light, 16×16, list       (what the walk and radiance cost)
# Usage from the project root after ../shared/gpu/prepare.sh target/release/lightgraph;
# .gpu/lobes_old.wgsl is `git show 354a123:shaders/material/lobes.wgsl`.
set -u
source "$(dirname "$0")/gpu_env.sh"
roots=/tmp/lg_roots
L=shaders/material/lobes.wgsl
S=shaders/visibility/staged_lights.wgsl
for v in old P C R D; do mkdir -p $roots/$v/shaders/material $roots/$v/shaders/visibility; done
cp .gpu/lobes_old.wgsl $roots/old/$L
perl -0pe 's/(fn lg_dot\(a: vec3<f32>, b: vec3<f32>\) -> f32 \{\n)/$1    return dot(a, b);\n/; s/(fn lg_cross\(a: vec3<f32>, b: vec3<f32>\) -> vec3<f32> \{\n)/$1    return cross(a, b);\n/' $L > $roots/C/$L
perl -0pe 's|    d.h = hq / len;|    let inv_len = 1.0 / len;\n    d.h = hq * inv_len;|; s|lg_dot\(n, hq\) / len|lg_dot(n, hq) * inv_len|; s|dot\(c, c\) / len2|dot(c, c) * (inv_len * inv_len)|; s|cross\(c, n\) / len;|cross(c, n) * inv_len;|' $L > $roots/R/$L
perl -0pe 's/return color \+ inc.radiance \* material_eval\(m, inc.dir\);/return color + inc.radiance * 0.3;/' $S > $roots/D/$S
{ diff $L $roots/C/$L; diff $L $roots/R/$L; diff $S $roots/D/$S; } > "$out/variants.diff"
img=/tmp/lg_images
mkdir -p $img
run() { # name root group uniform
    local v=$1
    export LIGHTGRAPH_SHADING_GROUP=$3 LIGHTGRAPH_UNIFORM_LIST=$4
    $lg --root $roots/$2 render --scene scenes/harada.ron --graph graphs/visibility_compute_raster.ron --width 1920 --height 1080 --out "$img/$v.exr" > "$out/render_$v.txt" 2>&1
    echo "== render $v"; grep -E "ms|rror" "$out/render_$v.txt" | head -n 8
    timeout 120 $lg --root $roots/$2 bench --sweep benches/sweeps/diag_session10.ron --out "$out/$v" > "$out/$v.log" 2>&1
    echo "== bench $v"; sed -n '/^Per-pass GPU time/,/^$/p' "$out/$v/results.md" | cut -c1-300
    [ "$v" = old ] || $lg compare "$img/$v.exr" "$img/old.exr" 2>&1 | head -n 3
}
run old old 8 0
run P8 P 8 0
run P16 P 16 0
run P8U P 8 1
run P16U P 16 1
run C16U C 16 1
run R16U R 16 1
run D16U D 16 1
run old2 old 8 0
gpu_pack
