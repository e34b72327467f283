// ReflectiveShadowMaps with raster: Compute, after its triangles (shadow/atlas_raster.wgsl
// twice: the nearest depth by a 32-bit atomic min, then with IDS the nearest triangle's
// id + 1 where the depth matches; src/kinds/reflective_shadow_maps/raster.rs). Writes
// what the hardware pass's fragment stage writes (indirect/rsm_texel.wgsl) into the same
// textures, from each texel's nearest triangle. A workgroup per STORE_CELL² piece of a
// view's tile (`rsm_pieces`: x, y, side, view), a thread per texel.
// - RESOLVE, one dispatch per material (MATERIAL_INDEX and its code, MATERIAL_TEXTURED):
//   a texel whose triangle is one of this material's is rebuilt as visibility shading
//   rebuilds a pixel (visibility/surface.wgsl: the triangle's plane at the texel centre
//   through the view's view-projection, perspective-correct barycentrics, the uv
//   footprint of the texel's 2×2 quad), with the view's tile as the frame.
// - STORE, last: the depth into `rsm_depth` (1.0 where nothing was drawn), zero normal,
//   flux and position where nothing was drawn (the hardware pass's clear), and the
//   buffers back to far and no triangle, so they are clear for the next frame.

#include "common/types.wgsl"

// (pieces, workgroups per dispatch dimension, texels a row of the buffers, tile side).
@group(0) @binding(20) var<uniform> rsm_params: vec4<u32>;
@group(0) @binding(21) var<storage, read> rsm_pieces: array<vec4<u32>>;
@group(0) @binding(14) var rsm_normal: texture_storage_2d<rgba32float, write>;
@group(0) @binding(15) var rsm_flux: texture_storage_2d<rgba32float, write>;
@group(0) @binding(16) var rsm_position: texture_storage_2d<rgba32float, write>;

#if STORE
@group(0) @binding(22) var<storage, read_write> rsm_depth_bits: array<u32>;
@group(0) @binding(23) var<storage, read_write> rsm_ids: array<u32>;
@group(0) @binding(13) var rsm_depth: texture_storage_2d<r32float, write>;
#else
#include "common/lighting.wgsl"
// The view's tile stands for the frame in visibility/surface.wgsl: its view-projection
// and size (set per texel before the rebuild).
var<private> frame: Frame;
#include "common/light_inputs.wgsl"
@group(0) @binding(11) var<storage, read> rsm_views: array<vec4<f32>>;
@group(0) @binding(23) var<storage, read> rsm_ids: array<u32>;
@group(0) @binding(6) var<storage, read> vertices: array<f32>;
@group(0) @binding(7) var<storage, read> triangles: array<u32>;
@group(0) @binding(8) var<storage, read> material_triangles: array<vec2<u32>>;
#include "visibility/surface.wgsl"
#include <material>
#include "indirect/rsm_texel.wgsl"
#endif

const FAR_BITS: u32 = 0x3f800000u;

// The texel (and its piece) of this invocation; `ok` false past the pieces or the
// piece's side.
struct Texel {
    ok: bool,
    p: vec2<u32>,
    at: u32,
    view: u32,
};

fn piece_texel(wg: vec3<u32>, local: vec3<u32>) -> Texel {
    var t: Texel;
    t.ok = false;
    let i = wg.y * rsm_params.y + wg.x;
    if (i >= rsm_params.x) {
        return t;
    }
    let piece = rsm_pieces[i];
    if (any(local.xy >= vec2<u32>(piece.z))) {
        return t;
    }
    t.ok = true;
    t.p = piece.xy + local.xy;
    t.at = t.p.y * rsm_params.z + t.p.x;
    t.view = piece.w;
    return t;
}

#if STORE
@compute @workgroup_size(STORE_CELL, STORE_CELL)
fn store(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let t = piece_texel(wg, local);
    if (!t.ok) {
        return;
    }
    textureStore(rsm_depth, t.p, vec4<f32>(bitcast<f32>(rsm_depth_bits[t.at]), 0.0, 0.0, 0.0));
    if (rsm_ids[t.at] == 0u) {
        textureStore(rsm_normal, t.p, vec4<f32>(0.0));
        textureStore(rsm_flux, t.p, vec4<f32>(0.0));
        textureStore(rsm_position, t.p, vec4<f32>(0.0));
    }
    rsm_depth_bits[t.at] = FAR_BITS;
    rsm_ids[t.at] = 0u;
}
#else
@compute @workgroup_size(STORE_CELL, STORE_CELL)
fn resolve(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let t = piece_texel(wg, local);
    if (!t.ok) {
        return;
    }
    let id = rsm_ids[t.at];
    let range = material_triangles[MATERIAL_INDEX];
    if (id == 0u || id - 1u < range.x || id - 1u >= range.y) {
        return;
    }
    let b = 1u + RSM_VIEW_VEC4S * t.view;
    let tile = bitcast<vec2<u32>>(rsm_views[b + 4u].xy);
    frame.view_proj = mat4x4<f32>(rsm_views[b], rsm_views[b + 1u], rsm_views[b + 2u], rsm_views[b + 3u]);
    frame.size = vec2<u32>(rsm_params.w);
    let s = surface_point(t.p - tile, id - 1u);
    let texel = rsm_texel(s, t.view);
    textureStore(rsm_normal, t.p, vec4<f32>(texel.normal, 1.0));
    textureStore(rsm_flux, t.p, vec4<f32>(texel.flux, 1.0));
    textureStore(rsm_position, t.p, vec4<f32>(s.position, 1.0));
}
#endif
