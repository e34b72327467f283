#!/usr/bin/env bash
# Hot-reload latency on the GPU machine (see ../shared/gpu/README.md): reload-bench at
# 1920x1080 with 3,072 lights and at 160x90 with 1,024 lights, each twice: first with an
# empty pipeline cache, then again with the cache the first run saved and the same edits
# (--salt: the same values), so every pipeline can come from it. 160x90 runs first: the
# 2026-11-28 and 2026-12-02 runs suggest the 4-12 ms builds at 160x90 were the driver's
# own shader cache answering edits an earlier 1080p run had compiled (the edits were the
# same values in every run), not the resolution. NVIDIA's shader disk cache is off here
# (__GL_SHADER_DISK_CACHE=0), so a cold run is cold and a warm run shows lightgraph's
# pipeline cache alone. Then three more 1080p runs with new edits: pipelines built one
# after another (the old way), with 30 frames in flight at each edit, and with 30 frames
# rendered (each waited for) right before each edit, as a viewer keeps the GPU busy.
# The GPU's clocks are logged every 200 ms through all runs (clocks.csv; runs.txt says
# when each run began and ended): in the 2026-12-02 cold runs the frame's GPU time rose
# from 8 to 37 ms about 3 s into the run, at whichever edit that was, as if an idle GPU
# lowered its clocks.
# Usage from the project root after ../shared/gpu/prepare.sh target/release/lightgraph:
#   scripts/gpu_bench_reload.sh        (about 4 minutes; every run has a timeout)
set -u
source "$(dirname "$0")/gpu_env.sh"
export __GL_SHADER_DISK_CACHE=0
export LIGHTGRAPH_PIPELINE_CACHE_DIR="$out/pipeline_cache"
nvidia-smi --query-gpu=timestamp,clocks.sm,clocks.mem,pstate,utilization.gpu,power.draw \
    --format=csv -lms 200 > "$out/clocks.csv" 2>&1 &
clock_log=$!
rb() { # name width height lights salt [flags...]
    local name=$1 w=$2 h=$3 n=$4 salt=$5
    shift 5
    echo "$name begins $(date +%Y/%m/%d\ %H:%M:%S.%3N)" >> "$out/runs.txt"
    timeout 150 $lg reload-bench --out "$out/$name" --width "$w" --height "$h" --lights "$n" \
        --repeats 10 --salt "$salt" "$@" > "$out/$name.log" 2>&1
    echo "== $name (exit $?)"
    echo "$name ends $(date +%Y/%m/%d\ %H:%M:%S.%3N)" >> "$out/runs.txt"
    sed -n '/^| edit | \*\*edit/,/^$/p' "$out/$name/reload_latency.md" 2>/dev/null
}
rm -rf "$LIGHTGRAPH_PIPELINE_CACHE_DIR"
rb reload_160x90_cold 160 90 1024 101
rb reload_160x90_warm 160 90 1024 101
rm -rf "$LIGHTGRAPH_PIPELINE_CACHE_DIR"
rb reload_1080p_cold 1920 1080 3072 102
rb reload_1080p_warm 1920 1080 3072 102
rb reload_1080p_sequential 1920 1080 3072 103 --sequential-builds
rb reload_1080p_in_flight 1920 1080 3072 104 --frames-in-flight 30
rb reload_1080p_viewer 1920 1080 3072 105 --viewer-frames 30
kill "$clock_log"
ls -l "$LIGHTGRAPH_PIPELINE_CACHE_DIR" >> "$out/gpu.txt" 2>&1
nvidia-smi --query-gpu=clocks.sm --format=csv >> "$out/gpu.txt" 2>&1
cat "$out/gpu.txt"
for d in "$out"/reload_*/; do
    echo "== $d"
    grep -E "^Session start" "$d/reload_latency.md"
    sed -n '/^| edit | compose + build, wall/,/^$/p;/^| edit | pipeline |/,/^$/p' "$d/reload_latency.md"
done
gpu_pack
