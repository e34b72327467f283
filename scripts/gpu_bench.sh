#!/usr/bin/env bash
# Runs the benchmark sweeps on the GPU machine (see ../shared/gpu/README.md); results go
# to $OUT (or results/). Usage from the project root after ../shared/gpu/prepare.sh:
#   scripts/gpu_bench.sh
set -u
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
final="${OUT:-results}"
out="$final/r"
mkdir -p "$out"
export XDG_RUNTIME_DIR=/tmp
nvidia-smi --query-gpu=name,driver_version --format=csv > "$out/gpu.txt" 2>&1
./.gpu/lightgraph render --out "$out/atrium.png" --heatmap "$out/atrium_heat.png" > "$out/render_atrium.txt" 2>&1
./.gpu/lightgraph render --scene scenes/depth_discontinuity.ron --graph graphs/forward_plus.ron > "$out/dd_frustum.txt" 2>&1
./.gpu/lightgraph render --scene scenes/depth_discontinuity.ron --graph graphs/forward_plus_depth_mask.ron > "$out/dd_depth_mask.txt" 2>&1
./.gpu/lightgraph render --scene scenes/depth_discontinuity.ron --graph graphs/forward_plus_half_z.ron > "$out/dd_half_z.txt" 2>&1
./.gpu/lightgraph render --scene scenes/depth_discontinuity.ron --graph graphs/forward_plus_clustered.ron > "$out/dd_clustered.txt" 2>&1
./.gpu/lightgraph bench --sweep benches/sweeps/seeds.ron --out "$out/seeds" > "$out/seeds.log" 2>&1
./.gpu/lightgraph bench --sweep benches/sweeps/headline.ron --out "$out/headline" > "$out/headline.log" 2>&1
cat "$out"/render_atrium.txt "$out"/seeds/results.md "$out"/headline/results.md
# The device tool brings back few files: pack everything into one archive.
tar -czf "$final/results.tar.gz" -C "$final" r && rm -rf "$out"
