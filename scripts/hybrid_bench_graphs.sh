#!/usr/bin/env bash
# Writes the hybrid shadow benchmark's graph variants into benches/graphs/ from
# graphs/visibility_hybrid_shadows.ron: the atlas for the 8, 32 or 128 casters nearest
# the camera, for casters at least 540 pixels across (half a 1080p frame's height), or
# for every caster with tiles kept at their asked size and the lowest-ranked lights
# dropped to rays (the atlas's texels as the budget); ray-cast shadows for the rest.
# Run from the repository root.
set -euo pipefail
out=benches/graphs
src=graphs/visibility_hybrid_shadows.ron
variant() {
    local name=$1 params=$2
    sed -e "s/policy: Nearest(16))/$params)/" \
        -e "s/^    name: \"visibility_hybrid_shadows\",/    name: \"$name\",/" \
        "$src" > "$out/$name.ron"
    grep -q "$params" "$out/$name.ron"
}
for n in 8 32 128; do
    variant "hybrid_nearest_$n" "policy: Nearest($n)"
done
variant hybrid_size_540 "policy: ProjectedSize(540.0)"
variant hybrid_drop_4096 "policy: All, fit: DropLights"
