#!/usr/bin/env bash
# Writes the light linked list benchmark's graph variants into benches/graphs/: forward
# and deferred at 1/1, 1/4 and 1/8 resolution, with pools for 1920x1080 at up to 16,384
# lights: links_per_pixel 64 at 1/1 (1,518.75 MiB of 12-byte links, under a 2 GiB
# binding), 512 at 1/4 (759.38 MiB) and 1024 at 1/8 (379.69 MiB), where a list pixel
# covers 16 and 64 output pixels; and forward at 1/8 testing every light instead of the
# tile lists (the build without culling). A pool that fills is counted and reported.
# Run from the repository root.
set -euo pipefail
out=benches/graphs
links() { case $1 in 1) echo 64 ;; 4) echo 512 ;; 8) echo 1024 ;; esac; }
for scale in 1 4 8; do
    params="LightLinkedList(scale: $scale, links_per_pixel: $(links $scale))"
    sed -e "s/LightLinkedList(scale: 1, links_per_pixel: 32)/$params/" \
        -e "s/^    name: \"light_linked_list\",/    name: \"lll_forward_$scale\",/" \
        graphs/light_linked_list.ron > "$out/lll_forward_$scale.ron"
    sed -e "s/LightLinkedList(scale: 1, links_per_pixel: 32)/$params/" \
        -e "s/^    name: \"light_linked_list_deferred\",/    name: \"lll_deferred_$scale\",/" \
        graphs/light_linked_list_deferred.ron > "$out/lll_deferred_$scale.ron"
done
# Every light a candidate: no culling pass, no tile lists.
python3 - "$out/lll_forward_8_all_lights.ron" <<'PY'
import re, sys
s = open("graphs/light_linked_list.ron").read()
s = s.replace("LightLinkedList(scale: 1, links_per_pixel: 32)", "LightLinkedList(scale: 8, links_per_pixel: 1024)")
s = s.replace('    name: "light_linked_list",', '    name: "lll_forward_8_all_lights",', 1)
s = s.replace('reads: ["depth", "light_geometry", "light_lists"],', 'reads: ["depth", "light_geometry"],')
s = s.replace('        Buffer(name: "light_lists", size: Auto),\n', "")
s = s.replace("Depth prepass, tiled culling, per-pixel", "Depth prepass, every light a candidate, per-pixel")
s = re.sub(r'        Pass\(\n            name: "light_culling",.*?\n        \),\n', "", s, flags=re.S)
open(sys.argv[1], "w").write(s)
PY
