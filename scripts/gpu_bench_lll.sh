#!/usr/bin/env bash
# Light linked list benchmarks on the GPU machine (see ../shared/gpu/README.md): single
# renders of the atrium (1,024 lights) at 1920x1080 through Forward+, tiled deferred and
# the linked-list graphs at 1/1, 1/4 and 1/8 (`render` prints each pass's GPU time and
# the list's memory and overflow), then the light_linked_list sweep (harada at
# 1920x1080 with 1,024, 4,096 and 16,384 lights; error against brute force: RMSE, worst
# pixel, FLIP; time-vs-error plot). Results are packed into $OUT/results.tar.gz.
# Usage from the project root after ../shared/gpu/prepare.sh target/release/lightgraph:
#   scripts/gpu_bench_lll.sh
set -u
source "$(dirname "$0")/gpu_env.sh"
for g in graphs/forward_plus.ron graphs/tiled_deferred.ron \
         benches/graphs/lll_forward_1.ron benches/graphs/lll_forward_4.ron benches/graphs/lll_forward_8.ron \
         benches/graphs/lll_forward_8_all_lights.ron \
         benches/graphs/lll_deferred_1.ron benches/graphs/lll_deferred_4.ron benches/graphs/lll_deferred_8.ron; do
    n=$(basename "$g" .ron)
    timeout 60 $lg render --graph "$g" --width 1920 --height 1080 --out "$out/atrium_$n.png" > "$out/render_atrium_$n.txt" 2>&1
done
timeout 450 $lg bench --sweep benches/sweeps/light_linked_list.ron --out "$out/light_linked_list" > "$out/light_linked_list.log" 2>&1
nvidia-smi --query-gpu=clocks.sm --format=csv >> "$out/gpu.txt" 2>&1
cat "$out"/gpu.txt
grep -h "scene:\|ms$\|list pixels\|WARNING" "$out"/render_*.txt
grep -A40 "Light linked lists" "$out/light_linked_list/results.md"
gpu_pack
