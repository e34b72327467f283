#!/usr/bin/env bash
# Issue 17's compute-first frame on the GPU machine: the visibility buffer (hardware
# prepass and compute rasterizer) against Forward+ and tiled deferred on harada, atrium_amd
# and the textured Cornell box, timing method of 2026-12-02, plus one render per graph at
# 3,072 lights for the per-pass split. Usage from the project root after
# ../shared/gpu/prepare.sh target/release/lightgraph:
#   scripts/gpu_bench_visibility.sh
set -u
source "$(dirname "$0")/gpu_env.sh"
$lg info > "$out/info.txt" 2>&1 || true
for g in graphs/visibility_buffer.ron graphs/visibility_compute_raster.ron graphs/tiled_deferred_prepass.ron; do
    n=$(basename "$g" .ron)
    $lg render --scene scenes/harada.ron --graph "$g" --width 1920 --height 1080 --out "$out/$n.exr" > "$out/render_$n.txt" 2>&1
    echo "== $n"; cat "$out/render_$n.txt" | head -n 12
done
for s in visibility_headline visibility_atrium visibility_textured; do
    timeout 300 $lg bench --sweep benches/sweeps/$s.ron --out "$out/$s" > "$out/$s.log" 2>&1
    echo "== $s"; tail -n 3 "$out/$s.log"; head -n 40 "$out/$s/results.md"
done
gpu_pack
