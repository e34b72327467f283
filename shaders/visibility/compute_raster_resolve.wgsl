// The compute rasterizer's resolve in compute (ComputeRaster with an R32Float depth): per
// pixel, the u64 that `compute_raster.wgsl` kept ((depth bits << 32) | ~id) into the
// depth and id textures: the depth's bits unchanged and the id, or 1.0 and NO_TRIANGLE
// where nothing was drawn, as the full-screen draw resolve writes a Depth32Float depth.
// A frame resolved here runs no vertex or fragment work. One invocation a pixel, in 8×8
// tiles (storage textures are tiled in memory). DEPTH_ONLY: the depth alone (the blended
// triangles' transparent depth, whose ids nothing reads). GLASS: also the blended
// triangles' depth the same run kept (glass_depth) into the transparent depth;
// GLASS_FAR, their farthest (the word after each nearest) into transparent_far (1.0
// where none, as the nearest).

#include "common/types.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
// Little-endian: x holds ~id, y the depth bits; all ones where nothing was drawn.
@group(0) @binding(1) var<storage, read> vis: array<vec2<u32>>;
@group(0) @binding(2) var depth: texture_storage_2d<r32float, write>;
#if DEPTH_ONLY
#else
@group(0) @binding(3) var visibility: texture_storage_2d<r32uint, write>;
#endif
#if GLASS
@group(0) @binding(4) var<storage, read> glass_depth: array<u32>;
@group(0) @binding(5) var transparent_depth: texture_storage_2d<r32float, write>;
#endif
#if GLASS_FAR
@group(0) @binding(6) var transparent_far: texture_storage_2d<r32float, write>;
const GLASS_WORDS: u32 = 2u;
#else
const GLASS_WORDS: u32 = 1u;
#endif

const NO_TRIANGLE: u32 = 0xffffffffu;
const EMPTY: u32 = 0xffffffffu;

@compute @workgroup_size(8, 8, 1)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= frame.size)) {
        return;
    }
    let v = vis[id.y * frame.size.x + id.x];
    var z = 1.0;
    var triangle = NO_TRIANGLE;
    if (v.y != EMPTY) {
        z = bitcast<f32>(v.y);
        triangle = ~v.x;
    }
    textureStore(depth, id.xy, vec4<f32>(z, 0.0, 0.0, 0.0));
#if GLASS
    let at = GLASS_WORDS * (id.y * frame.size.x + id.x);
    let g = glass_depth[at];
    textureStore(transparent_depth, id.xy, vec4<f32>(select(bitcast<f32>(g), 1.0, g == EMPTY), 0.0, 0.0, 0.0));
#endif
#if GLASS_FAR
    let f = glass_depth[at + 1u];
    textureStore(transparent_far, id.xy, vec4<f32>(select(bitcast<f32>(f), 1.0, g == EMPTY), 0.0, 0.0, 0.0));
#endif
#if DEPTH_ONLY
#else
    textureStore(visibility, id.xy, vec4<u32>(triangle, 0u, 0u, 0u));
#endif
}
