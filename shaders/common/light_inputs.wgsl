// The lights a shading pass reads, at the same bindings in every such pass: the lights'
// geometry and properties at 1 and 2, and with LIGHT_LISTS (tile lists) or LINKED_LISTS
// (a light linked list) the lists and their layout at 3 and 4; then the walk over a
// pixel's lights (common/light_lists.wgsl). The includer binds `frame` at 0.

@group(0) @binding(1) var<storage, read> light_geometry: array<LightGeometry>;
@group(0) @binding(2) var<storage, read> light_properties: array<LightProperties>;
#if LIGHT_LISTS
@group(0) @binding(3) var<storage, read> light_lists: array<u32>;
@group(0) @binding(4) var<uniform> list_params: ListParams;
#endif
#if LINKED_LISTS
@group(0) @binding(3) var<storage, read> light_lists: array<u32>;
@group(0) @binding(4) var<uniform> link_params: LinkParams;
#endif

#include "common/light_lists.wgsl"
