#!/usr/bin/env bash
# Issue 17 on the GPU machine: the headline, atrium and textured sweeps under the timing
# method of 2026-12-02 and hot-reload latency split by resolution and light count (the Bevy
# peer is scripts/gpu_bench_peer.sh). Usage from the project root after
# ../shared/gpu/prepare.sh target/release/lightgraph:
#   scripts/gpu_bench_method.sh
set -u
source "$(dirname "$0")/gpu_env.sh"
for s in method_headline method_atrium method_textured; do
    $lg bench --sweep benches/sweeps/$s.ron --out "$out/$s" > "$out/$s.log" 2>&1
    echo "== $s"; tail -n 4 "$out/$s.log"
done
# Pipeline builds took 100-200 ms at 1920x1080 / 3,072 lights and 4-12 ms at 160x90 /
# 1,024 lights: these runs tell resolution from light count.
for cfg in "1920 1080 3072" "1920 1080 1024" "160 90 3072" "160 90 1024"; do
    set -- $cfg
    $lg reload-bench --out "$out/reload_${1}x${2}_$3" --width "$1" --height "$2" --lights "$3" --repeats 10 > "$out/reload_${1}x${2}_$3.log" 2>&1
done
for s in method_headline method_atrium method_textured; do cat "$out/$s/results.md" | head -n 30; done
for d in "$out"/reload_*/; do echo "== $d"; sed -n 5,20p "$d/reload_latency.md"; done
gpu_pack
