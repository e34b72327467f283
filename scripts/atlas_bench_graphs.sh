#!/usr/bin/env bash
# Writes the shadow atlas benchmark's graph variants into benches/graphs/: Forward+ with
# the atlas at 2048² to 16384² with each filter, and the ShadowCompare graph at each size.
# The importance grows with the atlas (1 at 2048², 8 at 16384²) and max_tile with it, so a
# larger atlas buys resolution rather than empty room. Run from the repository root.
set -euo pipefail
out=benches/graphs
for size in 2048 4096 8192 16384; do
    importance=$((size / 2048))
    max_tile=$((size / 4 < 4096 ? size / 4 : 4096))
    params="min_tile: 16, max_tile: $max_tile, importance: $importance.0"
    for filter in Pcf5x5 Hardware2x2; do
        sed -e "s/Fixed(4096, 4096)/Fixed($size, $size)/" \
            -e "s/ShadowAtlas(filter: Pcf5x5, min_tile: 16, max_tile: 1024, importance: 1.0)/ShadowAtlas(filter: $filter, $params)/" \
            -e "s/^    name: \"shadow_atlas\",/    name: \"shadow_atlas_${size}_$filter\",/" \
            graphs/shadow_atlas.ron > "$out/shadow_atlas_${size}_$filter.ron"
    done
    sed -e "s/Fixed(4096, 4096)/Fixed($size, $size)/" \
        -e "s/ShadowAtlas(filter: Pcf5x5, min_tile: 16, max_tile: 1024, importance: 1.0)/ShadowAtlas(filter: Pcf5x5, $params)/" \
        -e "s/^    name: \"shadow_atlas_vs_raycast\",/    name: \"shadow_atlas_vs_raycast_$size\",/" \
        $out/shadow_atlas_vs_raycast.ron > "$out/shadow_atlas_vs_raycast_$size.ron"
done
