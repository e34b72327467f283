#!/usr/bin/env bash
# Diagnostic: where visibility shading's time goes. Builds shader variants as --root
# folders over the shipped shaders (file by file) and runs benches/sweeps/diag_shading.ron
# with each, plus one render per variant at 3,072 lights compared with the shipped image:
#   base  the shipped shaders
#   B     lg_through returns before the absorption terms when sigma_d is zero (bit-exact)
#   C     B with plain dot and cross for lg_dot and lg_cross (inexact)
#   D     no BRDF per light (radiance times a constant)
#   E     no light loop
# B and C change shaders/material/lobes.wgsl, which was built into the binary when this ran
# (the generated material code carried it as text), so they came as their own binaries:
# .gpu/lg_B.xz and .gpu/lg_C.xz, built from the tree with that file edited as the perl lines
# below edit it. Since the renderer includes the library from the root, the B and C folders
# made below would do on their own.
# Usage from the project root after ../shared/gpu/prepare.sh target/release/lightgraph.
set -u
source "$(dirname "$0")/gpu_env.sh"
roots=/tmp/lg_roots
L=shaders/material/lobes.wgsl
S=shaders/visibility/staged_lights.wgsl
mkdir -p $roots/{base,B,C} $roots/{B,C}/shaders/material $roots/{D,E}/shaders/visibility
perl -0pe 's/(\) -> vec3<f32> \{\n    var pass_ = transmission;\n    if \(ior > 1.0\) \{.*?\n    \}\n)/$1    if (all(sigma_d == vec3<f32>(0.0))) { return vec3<f32>(pass_); }\n/s' $L > $roots/B/$L
perl -0pe 's/(fn lg_dot\(a: vec3<f32>, b: vec3<f32>\) -> f32 \{\n)/$1    return dot(a, b);\n/; s/(fn lg_cross\(a: vec3<f32>, b: vec3<f32>\) -> vec3<f32> \{\n)/$1    return cross(a, b);\n/' $roots/B/$L > $roots/C/$L
perl -0pe 's/return color \+ inc.radiance \* material_eval\(m, inc.dir\);/return color + inc.radiance * 0.3;/' $S > $roots/D/$S
perl -0pe 's/(fn shade_range_first\(.*?\n    var color = surface_unlit\(p, m\);\n)/$1    if (frame.size.x > 0u) { return color; }\n/s' $S > $roots/E/$S
for v in B C; do diff $L $roots/$v/$L; done > "$out/variants.diff"
for v in D E; do diff $S $roots/$v/$S; done >> "$out/variants.diff"
for v in B C; do xz -dc .gpu/lg_$v.xz > /tmp/lg_$v && chmod +x /tmp/lg_$v; done
img=/tmp/lg_images
mkdir -p $img
for v in base B C D E; do
    bin=$lg
    case $v in B|C) bin=/tmp/lg_$v;; esac
    $bin --root $roots/$v render --scene scenes/harada.ron --graph graphs/visibility_compute_raster.ron --width 1920 --height 1080 --out "$img/$v.exr" > "$out/render_$v.txt" 2>&1
    echo "== render $v"; grep -E "ms|error" "$out/render_$v.txt" | head -n 6
    timeout 150 $bin --root $roots/$v bench --sweep benches/sweeps/diag_shading.ron --out "$out/$v" > "$out/$v.log" 2>&1
    echo "== bench $v"; sed -n '/^Per-pass GPU time/,/^$/p' "$out/$v/results.md" | cut -c1-300
done
for v in B C D E; do
    echo "== compare $v vs base"; $lg compare "$img/$v.exr" "$img/base.exr" 2>&1 | tee "$out/compare_$v.txt" | head -n 3
done
gpu_pack
