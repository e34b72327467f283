#!/usr/bin/env bash
# Renders every shipped graph x scene at 333x197 with binary $1 into dir $2, for checking
# that a change leaves every image as it was: run it with the binaries built before and
# after into two folders, then `cmp` every EXR pair.
# Runs from the source tree $3 (graphs/scenes/shaders read from there).
bin=$1; out=$2; src=$3
mkdir -p "$out"
cd "$src"
for g in graphs/*.ron; do
  for s in builtin scenes/*.ron scenes/cornell_box/scene.gltf; do
    gn=$(basename "$g" .ron); sn=$(basename "$(dirname "$s")")_$(basename "$s" | sed 's/\..*//')
    [ "$s" = builtin ] && sn=builtin
    case "$sn" in *chairs*) continue;; esac
    args=(render --graph "$g" --width 333 --height 197 --out "$out/${gn}__${sn}.exr")
    [ "$s" != builtin ] && args+=(--scene "$s")
    LIGHTGRAPH_ROOT="$src" timeout 300 "$bin" "${args[@]}" > "$out/${gn}__${sn}.log" 2>&1
    echo "$? ${gn}__${sn}" >> "$out/status.txt"
  done
done
