#!/usr/bin/env bash
# Session 11 on the GPU machine, one call: the compute-first frame's shading variants side
# by side (session10_shading / _atrium / _textured sweeps, interleaved: 8×8 per-pixel walk
# shipped, 16×16, and the workgroup's one tile list on 8 and 16), and diag_session10.ron
# (3,072 and 65,536 lights, per-pass times) with the shipped shaders. Results are packed
# after every stage, so a cut-off run still brings back what it finished. Usage from the
# project root after ../shared/gpu/prepare.sh target/release/lightgraph and
# `xz -c .gpu/lightgraph > .gpu/lightgraph.xz && rm .gpu/lightgraph`.
set -u
source "$(dirname "$0")/gpu_env.sh"
sweep() { # name limit_s
    timeout "$2" $lg bench --sweep benches/sweeps/$1.ron --out "$out/$1" > "$out/$1.log" 2>&1
    echo "== $1 (rc $?)"; tail -n 2 "$out/$1.log"
    sed -n '/^| scene | technique | params | lights | size/,/^$/p' "$out/$1/results.md" | cut -c1-230
    grep -A12 '^Per-pass GPU time' "$out/$1/results.md" | grep '^|' | cut -c1-230
    pack
}
sweep session10_shading 240
sweep diag_session10 40
sweep session10_atrium 150
sweep session10_textured 150
nvidia-smi --query-gpu=clocks.sm --format=csv >> "$out/gpu.txt" 2>&1
gpu_pack
