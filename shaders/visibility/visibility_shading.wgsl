// Visibility-buffer shading in a compute shader: one dispatch per group of materials that
// share their code (src/render/materials.rs's shared_wgsl: the same code but for the
// constants, which it reads from `material_constants`), over the whole frame or
// (CLASSIFIED) over the tiles visibility/classify_materials.wgsl listed for the group;
// each invocation whose pixel holds a triangle of one of the group's materials (found in
// `shading_members`) fetches the triangle's three vertices, rebuilds the surface at the
// pixel centre and shades it with the same material code and light loop as forward
// shading. Ids: src/render/visibility_geometry.rs (NO_TRIANGLE where nothing was drawn).
// Defines: SHADING_GROUP (the workgroup's side in pixels; 8 with STAGED_LIGHTS),
// MEMBERS_FIRST and MEMBERS_COUNT (the group's entries in `shading_members`), SHARED_CODE
// (the group's code reads its constants from a buffer), CLEARS
// (this dispatch stores black where nothing was drawn), CLASSIFIED with MATERIAL_SLOT and
// TILES (the group's tiles are the workgroups: `material_tiles[MATERIAL_SLOT * TILES + n]`,
// n from the workgroup id, folded into y past 65,535),
// LIGHT_LISTS (tile lists) or LINKED_LISTS (a light linked list), and the light loop:
// STAGED_LIGHTS (the workgroup's one tile list staged in workgroup memory, in
// visibility/staged_lights.wgsl), RANGE_FIRST (the per-pixel cursor with the range test
// before the light's properties; with UNIFORM_LIST the workgroup's one tile list, found
// from the workgroup id, so the compiler sees the walk as uniform, and with SUBGROUP_LIST
// as well that list walked a subgroup of lights at a time), or neither
// (common/light_loop.wgsl's shade_surface, as forward shading runs it). SHADOWS with
// SHADOW_MASK: each shadow-casting light is looked up in a ray-cast mask
// (shadow/shadow_ray_cast.wgsl), casters numbered as job creation numbers them; or with
// SHADOW_ATLAS (and SHADOW_PCF5): sampled from a ShadowAtlas pass's maps, filtered as
// forward shading filters them (common/shadows.wgsl). VPL_VISIBILITY (with VPL_BLOCK,
// VPL_WORDS): VPLs hidden from the pixel's block by a VplVisibility pass add nothing
// (indirect/vpl_lookup.wgsl). LIGHT_SAMPLES (with SAMPLE_EXACT, SAMPLE_COUNT,
// SAMPLE_REGION; the Forward loop only): a LightSampling pass's exact lights and samples
// stand for the shadow-casting lights (common/light_loop.wgsl).

#include "common/types.wgsl"
#include "common/lighting.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
#include "common/light_inputs.wgsl"
@group(0) @binding(5) var visibility: texture_2d<u32>;
@group(0) @binding(6) var<storage, read> vertices: array<f32>;
@group(0) @binding(7) var<storage, read> triangles: array<u32>;
// Each group's materials, ascending by first triangle: (first triangle, end, first
// constant in material_constants, unused).
@group(0) @binding(8) var<storage, read> shading_members: array<vec4<u32>>;
@group(0) @binding(9) var hdr: texture_storage_2d<rgba32float, write>;
#if SHADOW_MASK
@group(0) @binding(10) var<storage, read> shadow_mask: array<u32>;
#endif
#if SHADOW_TRACE
@group(0) @binding(18) var<storage, read> bvh_nodes: array<BvhNode>;
@group(0) @binding(19) var<storage, read> bvh_triangles: array<BvhTriangle>;
#if BVH_ALPHA_TEST
@group(0) @binding(21) var<storage, read> bvh_alpha: array<u32>;
#endif
#include "shadow/bvh.wgsl"
#endif
#if SHADOW_ATLAS
@group(0) @binding(13) var<storage, read> shadow_views: array<vec4<f32>>;
#if SHADOW_ATLAS_FLOAT
@group(0) @binding(14) var shadow_atlas: texture_2d<f32>;
@group(0) @binding(15) var shadow_gather: sampler;
#else
@group(0) @binding(14) var shadow_atlas: texture_depth_2d;
@group(0) @binding(15) var shadow_sampler: sampler_comparison;
#endif
#endif
#if VPL_VISIBILITY
@group(0) @binding(16) var<storage, read> vpl_visibility: array<u32>;
#include "indirect/vpl_lookup.wgsl"
#endif
#if LIGHT_SAMPLES
@group(0) @binding(17) var<storage, read> light_samples: array<u32>;
#include "common/light_samples.wgsl"
#endif
#if CLASSIFIED
@group(0) @binding(11) var<storage, read> material_tiles: array<u32>;
@group(0) @binding(12) var<storage, read> material_tile_counts: array<u32>;
#endif

#include "visibility/surface.wgsl"
#if SHADOWS
#include "common/shadows.wgsl"
#endif

// Material code generated with WgslOptions::sample_grad when it has textures (it samples
// with material_uv_ddx / material_uv_ddy, set by surface_point before material_setup);
// with SHARED_CODE (a group of several materials) also with constants_binding: its
// per-pixel constants read from material_constants at material_constant_base, set here
// per pixel. A group of one has its constants written into its code.
#include <material>
#include "common/light_loop.wgsl"
#include "visibility/staged_lights.wgsl"

const NO_TRIANGLE: u32 = 0xffffffffu;
// A workgroup past the end of its group's tile list.
const NO_TILE: u32 = 0xffffffffu;
// A triangle of no material of this group.
const NO_MEMBER: u32 = 0xffffffffu;

// The entry of the group's material whose triangles hold `tri`, or NO_MEMBER (another
// group's material, or NO_TRIANGLE): a binary search over the group's ranges.
fn member_of(tri: u32) -> u32 {
    var lo = MEMBERS_FIRST;
    var hi = MEMBERS_FIRST + MEMBERS_COUNT;
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (shading_members[mid].x <= tri) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let r = shading_members[lo];
    return select(NO_MEMBER, lo, tri >= r.x && tri < r.y);
}

#if CLASSIFIED
var<workgroup> listed_tile: u32;

// The tile this workgroup shades, in workgroups across the frame: the n-th of this
// material's list (NO_TILE past its end). Read once and shared, so the result is
// uniform across the workgroup and the staged loop's barriers stay legal.
fn shading_tile(lane: u32, group: vec3<u32>) -> vec2<u32> {
    if (lane == 0u) {
        let n = group.y * 65535u + group.x;
        var t = NO_TILE;
        if (n < material_tile_counts[MATERIAL_SLOT]) {
            t = material_tiles[MATERIAL_SLOT * TILES + n];
        }
        listed_tile = t;
    }
    let t = workgroupUniformLoad(&listed_tile);
    if (t == NO_TILE) {
        return vec2<u32>(NO_TILE);
    }
    let across = (frame.size.x + SHADING_GROUP - 1u) / SHADING_GROUP;
    return vec2<u32>(t % across, t / across);
}
#else
fn shading_tile(lane: u32, group: vec3<u32>) -> vec2<u32> {
    return group.xy;
}
#endif

// A pixel's surface, rebuilt from its triangle, with what the light loop takes.
struct Surface {
    p: ShadingPoint,
    m: MaterialSample,
    pixel: vec2<f32>,
    view_z: f32,
};

fn rebuild(id: vec2<u32>, tri: u32) -> Surface {
    let p = surface_point(id, tri);
    let pixel = vec2<f32>(id) + 0.5;
    let m = material_setup(p);
    let view_z = -(frame.view * vec4<f32>(p.position, 1.0)).z;
    return Surface(p, m, pixel, view_z);
}

// The triangle at pixel `id` (NO_TRIANGLE outside the frame, or where nothing was drawn:
// black stored there by the dispatch that CLEARS), for a walk every invocation joins.
fn triangle_at(id: vec2<u32>) -> u32 {
    let inside = all(id < frame.size);
    var tri = NO_TRIANGLE;
    if (inside) {
        tri = textureLoad(visibility, id, 0).x;
    }
#if CLEARS
    if (inside && tri == NO_TRIANGLE) {
        textureStore(hdr, id, vec4<f32>(0.0));
    }
#endif
    return tri;
}

// The surface an invocation of a walk that every invocation joins (the staged and the
// subgroup loops) takes: its pixel's where it shades (`shades`), else one rebuilt from
// the group's first triangle, with the per-pixel state the light loop reads set.
fn rebuild_for_every_invocation(id: vec2<u32>, tri: u32, member: u32, shades: bool) -> Surface {
    let shown = shading_members[select(MEMBERS_FIRST, member, shades)];
    let surface_tri = select(shown.x, tri, shades);
#if SHARED_CODE
    material_constant_base = shown.z;
#endif
#if SHADOWS
    shadow_pixel = id.y * frame.size.x + id.x;
#endif
#if SHADOW_TRACE
    shadow_ng = surface_geometry(id, surface_tri).ng;
#endif
    let s = rebuild(id, surface_tri);
#if VPL_VISIBILITY
    vpl_select(id, s.p.position, s.p.normal);
#endif
    return s;
}

#if STAGED_LIGHTS
// Whether any pixel of the workgroup is this group's (zeroed at workgroup start).
var<workgroup> group_shades: atomic<u32>;

// Every invocation, its pixel in the frame or not, takes part in staging the lights: the
// barriers need all of them. A workgroup none of whose pixels is this group's leaves
// before loading anything.
@compute @workgroup_size(8, 8, 1)
fn main(
    @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(workgroup_id) group: vec3<u32>,
) {
    let tile = shading_tile(lane, group);
    if (tile.x == NO_TILE) {
        return;
    }
    let id = tile * 8u + local.xy;
    let tri = triangle_at(id);
    let member = member_of(tri);
    let shades = member != NO_MEMBER;
    if (shades) {
        atomicOr(&group_shades, 1u);
    }
    if (workgroupUniformLoad(&group_shades) == 0u) {
        return;
    }
    // Every invocation rebuilds a surface (the group's first triangle where its pixel
    // has none of the group's) and the light loop skips those that do not shade: a
    // surface rebuilt in a branch and shaded after it came out one ulp off in a few
    // pixels on lavapipe (the compiler fuses the arithmetic differently). A warp with
    // any pixel of this group pays for the rebuild anyway.
    let s = rebuild_for_every_invocation(id.xy, tri, member, shades);
    let color = staged_lights(surface_unlit(s.p, s.m), shades, s.p, s.m, lane, group_list(tile));
    if (shades) {
        textureStore(hdr, id.xy, vec4<f32>(color, material_alpha(s.m)));
    }
}
#else
// Invocation `lane`'s pixel in its workgroup: each run of 32 invocations (a warp on
// NVIDIA) covers an 8×4 block, the most compact, so its pixels mostly see the same lights
// in range and take the same branches of the light loop.
fn block_pixel(lane: u32) -> vec2<u32> {
    let block = lane / 32u;
    let across = SHADING_GROUP / 8u;
    return vec2<u32>(lane % 8u + 8u * (block % across), (lane / 8u) % 4u + 4u * (block / across));
}

#if SUBGROUP_LIST
// With SUBGROUP_LIST (GroupList on a device with subgroup operations): the workgroup's
// one tile list walked a subgroup of lights at a time (shade_list_subgroup), which needs
// every invocation of a subgroup in the walk. One-dimensional, as subgroup built-ins
// require; block_pixel maps an invocation to its pixel either way.
@compute @workgroup_size(SHADING_GROUP * SHADING_GROUP, 1, 1)
fn main(
    @builtin(local_invocation_index) lane: u32,
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(subgroup_invocation_id) sg_lane: u32,
    @builtin(subgroup_size) sg_size: u32,
) {
    let tile = shading_tile(lane, group);
    if (tile.x == NO_TILE) {
        return;
    }
    let id = tile * SHADING_GROUP + block_pixel(lane);
    let tri = triangle_at(id);
    let member = member_of(tri);
    let shades = member != NO_MEMBER;
    // A subgroup none of whose pixels is this group's leaves whole; in any other, every
    // invocation rebuilds a surface (the group's first triangle where its pixel has
    // none of the group's, as the staged loop does) and walks the list, adding the
    // lights only where it shades.
    if (subgroupAll(!shades)) {
        return;
    }
    let s = rebuild_for_every_invocation(id.xy, tri, member, shades);
    let color = shade_list_subgroup(s.p, s.m, group_list(tile), shades, sg_lane, sg_size);
    if (shades) {
        textureStore(hdr, id.xy, vec4<f32>(color, material_alpha(s.m)));
    }
}
#else
@compute @workgroup_size(SHADING_GROUP, SHADING_GROUP, 1)
fn main(@builtin(local_invocation_index) lane: u32, @builtin(workgroup_id) group: vec3<u32>) {
    let tile = shading_tile(lane, group);
    if (tile.x == NO_TILE) {
        return;
    }
    let id = tile * SHADING_GROUP + block_pixel(lane);
    if (any(id.xy >= frame.size)) {
        return;
    }
    let tri = textureLoad(visibility, id.xy, 0).x;
    if (tri == NO_TRIANGLE) {
#if CLEARS
        textureStore(hdr, id.xy, vec4<f32>(0.0));
#endif
        return;
    }
    let member = member_of(tri);
    if (member == NO_MEMBER) {
        return;
    }
#if SHARED_CODE
    material_constant_base = shading_members[member].z;
#endif
#if SHADOWS
    shadow_pixel = id.y * frame.size.x + id.x;
#endif
#if SHADOW_TRACE
    shadow_ng = surface_geometry(id.xy, tri).ng;
#endif
    let s = rebuild(id.xy, tri);
#if RANGE_FIRST
#if VPL_VISIBILITY
    // These loops do not go through shade_surface, which selects the block itself.
    vpl_select(id.xy, s.p.position, s.p.normal);
#endif
#if UNIFORM_LIST
    let color = shade_list(s.p, s.m, group_list(tile));
#else
    let color = shade_range_first(s.p, s.m, s.pixel, s.view_z);
#endif
#else
    let color = shade_surface(s.p, s.m, s.pixel, s.view_z);
#endif
    textureStore(hdr, id.xy, vec4<f32>(color, material_alpha(s.m)));
}
#endif
#endif
