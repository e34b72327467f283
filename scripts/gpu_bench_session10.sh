#!/usr/bin/env bash
# Session 10 on the GPU machine, one call: the compute-first frame's shading variants side
# by side (session10_shading / _atrium / _textured sweeps, interleaved), then the accurate
# products' split and two diagnostic shader variants, each a run of diag_session10.ron
# through a shader root over the shipped shaders, between two runs of the shipped shaders:
#   old  lobes.wgsl of session 9 (round-and-convert split: ~20 float-integer conversions
#        a light), .gpu/lobes_old.wgsl = `git show 354a123:shaders/material/lobes.wgsl`
#   C    plain dot and cross for the accurate products (inexact: what they still cost)
#   D    no BRDF per light (radiance times a constant: what the walk and radiance cost)
# Usage from the project root after ../shared/gpu/prepare.sh target/release/lightgraph.
set -u
source "$(dirname "$0")/gpu_env.sh"
for s in session10_shading session10_atrium session10_textured; do
    timeout 150 $lg bench --sweep benches/sweeps/$s.ron --out "$out/$s" > "$out/$s.log" 2>&1
    echo "== $s"; tail -n 1 "$out/$s.log"
    sed -n '/^| scene | technique | params | lights | size/,/^$/p;/^Per-pass GPU time/,/^$/p' "$out/$s/results.md" | cut -c1-260
done
nvidia-smi --query-gpu=clocks.sm --format=csv >> "$out/gpu.txt" 2>&1
roots=/tmp/lg_roots
L=shaders/material/lobes.wgsl
S=shaders/visibility/staged_lights.wgsl
for v in shipped old C D; do mkdir -p $roots/$v/shaders/material $roots/$v/shaders/visibility; done
cp .gpu/lobes_old.wgsl $roots/old/$L
perl -0pe 's/(fn lg_dot\(a: vec3<f32>, b: vec3<f32>\) -> f32 \{\n)/$1    return dot(a, b);\n/; s/(fn lg_cross\(a: vec3<f32>, b: vec3<f32>\) -> vec3<f32> \{\n)/$1    return cross(a, b);\n/' $L > $roots/C/$L
perl -0pe 's/return color \+ inc.radiance \* material_eval\(m, inc.dir\);/return color + inc.radiance * 0.3;/' $S > $roots/D/$S
{ diff $L $roots/old/$L; diff $L $roots/C/$L; diff $S $roots/D/$S; } > "$out/variants.diff"
n=0
for v in shipped old C D shipped; do
    n=$((n + 1)); d="diag${n}_$v"
    timeout 60 $lg --root $roots/$v bench --sweep benches/sweeps/diag_session10.ron --out "$out/$d" > "$out/$d.log" 2>&1
    echo "== $d"; sed -n '/^Per-pass GPU time/,/^$/p' "$out/$d/results.md" | cut -c1-200
done
gpu_pack
