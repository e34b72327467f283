#!/usr/bin/env bash
# Issue 17's compute-first frame on the GPU machine: the visibility buffer (hardware
# prepass and compute rasterizer) against Forward+ and tiled deferred on harada, atrium_amd
# and the textured Cornell box, timing method of 2026-12-02; one render per graph at
# 3,072 lights for the per-pass split, and the images compared with brute force and
# with each other (pixels that differ: the compute rasterizer's edge pixels). Usage from
# the project root after ../shared/gpu/prepare.sh target/release/lightgraph:
#   scripts/gpu_bench_visibility.sh
set -u
source "$(dirname "$0")/gpu_env.sh"
img=/tmp/lg_images
mkdir -p $img
for scene in harada atrium_amd; do
    for g in brute_force forward_plus tiled_deferred_prepass visibility_buffer visibility_compute_raster; do
        $lg render --scene scenes/$scene.ron --graph graphs/$g.ron --width 1920 --height 1080 --out "$img/${scene}_$g.exr" > "$out/render_${scene}_$g.txt" 2>&1
        echo "== render $scene $g"; grep -vE "^wrote" "$out/render_${scene}_$g.txt" | head -n 12
    done
    for g in forward_plus visibility_buffer visibility_compute_raster; do
        echo "== compare $scene $g vs brute_force"
        $lg compare "$img/${scene}_$g.exr" "$img/${scene}_brute_force.exr" 2>&1 | tee "$out/compare_${scene}_$g.txt"
    done
    echo "== compare $scene visibility_compute_raster vs visibility_buffer"
    $lg compare "$img/${scene}_visibility_compute_raster.exr" "$img/${scene}_visibility_buffer.exr" 2>&1 | tee "$out/compare_${scene}_raster_vs_hw.txt"
done
rm -rf $img
for s in visibility_headline visibility_atrium visibility_textured visibility_staging; do
    timeout 200 $lg bench --sweep benches/sweeps/$s.ron --out "$out/$s" > "$out/$s.log" 2>&1
    echo "== $s"; tail -n 2 "$out/$s.log"
    sed -n '/^| scene | technique | params | lights | size/,/^$/p;/^Per-pass GPU time/,/^$/p' "$out/$s/results.md" | cut -c1-400
done
gpu_pack
