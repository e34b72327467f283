#!/usr/bin/env bash
# lightgraph against Bevy 0.19's clustered forward renderer (../shared/peers/bevy) on the
# same scene, lights and size, in one call: lightgraph's sweep, Bevy without and with its
# depth prepass, then lightgraph's sweep again (the drift between the two tells how far
# the machine moved). Usage from the project root after
#   ../shared/gpu/prepare.sh target/release/lightgraph; xz -9 -c peer_bevy > .gpu/peer_bevy.xz
#   xz -c .gpu/lightgraph > .gpu/lightgraph.xz && rm .gpu/lightgraph   (both fit 64 MiB only so)
#   scripts/gpu_bench_bevy.sh
set -u
source "$(dirname "$0")/gpu_env.sh"
bevy=/tmp/peer_bevy
xz -dc .gpu/peer_bevy.xz > $bevy && chmod +x $bevy
timeout 150 $lg bench --sweep benches/sweeps/peer_bevy.ron --out "$out/lightgraph_1" > "$out/lightgraph_1.log" 2>&1
for n in 1024 3072 16384; do
    # 16,384 lights: 150+ ms a Bevy frame, so fewer frames than the default 60 + 300.
    frames=""
    [ $n -ge 16384 ] && frames="--warmup 10 --frames 40"
    timeout 120 $bevy --light-set sweep --lights $n --width 1920 --height 1080 $frames > "$out/bevy_$n.txt" 2>&1
    timeout 120 $bevy --light-set sweep --lights $n --width 1920 --height 1080 --depth-prepass $frames > "$out/bevy_${n}_prepass.txt" 2>&1
done
timeout 150 $lg bench --sweep benches/sweeps/peer_bevy.ron --out "$out/lightgraph_2" > "$out/lightgraph_2.log" 2>&1
nvidia-smi --query-gpu=clocks.sm --format=csv >> "$out/gpu.txt" 2>&1
cat "$out/gpu.txt"
for f in "$out"/bevy_*.txt; do echo "== $f"; grep -E "WARN|cluster|bevy frame" "$f" | tail -4; done
for s in lightgraph_1 lightgraph_2; do echo "== $s"; head -n 16 "$out/$s/results.md"; done
gpu_pack
