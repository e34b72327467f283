// Mesh draws of one material (src/render/draws/): the depth prepass and the
// transparent one (DEPTH_ONLY), the G-buffer (GBUFFER, GBUFFER_PACKED), forward shading
// of opaque and blended meshes (SHADE, with LIGHT_LISTS for tile lists or LINKED_LISTS for
// a light linked list; blended ones return the material's alpha, blending is pipeline
// state), a shadow atlas's views (DEPTH_ONLY with ATLAS_DEPTH); MSAA at more than one
// sample. The material's generated code is included as <material>; ALPHA_MASK
// discards below the cutoff. Only SHADE binds lights: a pass binds what it declares.
// VISIBILITY writes each fragment's triangle id (the visibility buffer).
// VPL_VISIBILITY (SHADE): VPLs hidden from the pixel's block by a VplVisibility pass add
// nothing (indirect/vpl_lookup.wgsl).
// FLOAT_DEPTH (SHADE, single-sample): the depth to test against is an R32Float texture (a
// compute resolve's) instead of a depth attachment; each fragment loads it at its pixel
// and is discarded where the attachment's LessEqual test would fail.

#if VISIBILITY
enable primitive_index;
#endif
#include "common/types.wgsl"
#include "common/lighting.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
#if SHADE
#include "common/light_inputs.wgsl"

#if SHADOW_MASK
@group(0) @binding(5) var<storage, read> shadow_mask: array<u32>;
#endif
#if SHADOW_TRACE
@group(0) @binding(6) var<storage, read> bvh_nodes: array<BvhNode>;
@group(0) @binding(7) var<storage, read> bvh_triangles: array<BvhTriangle>;
#if BVH_ALPHA_TEST
@group(0) @binding(14) var<storage, read> bvh_alpha: array<u32>;
#endif
#include "shadow/bvh.wgsl"
#endif
#if SHADOW_ATLAS
@group(0) @binding(8) var<storage, read> shadow_views: array<vec4<f32>>;
#if SHADOW_ATLAS_FLOAT
@group(0) @binding(9) var shadow_atlas: texture_2d<f32>;
@group(0) @binding(10) var shadow_gather: sampler;
#else
@group(0) @binding(9) var shadow_atlas: texture_depth_2d;
@group(0) @binding(10) var shadow_sampler: sampler_comparison;
#endif
#endif
#if SHADOWS
#include "common/shadows.wgsl"
#endif
#if FLOAT_DEPTH
@group(0) @binding(12) var depth: texture_2d<f32>;
#endif
#if VPL_VISIBILITY
@group(0) @binding(13) var<storage, read> vpl_visibility: array<u32>;
#include "indirect/vpl_lookup.wgsl"
#endif
#endif
#if ATLAS_DEPTH
// A ShadowAtlas pass: the instance index is the view (see common/shadows.wgsl).
@group(0) @binding(8) var<storage, read> shadow_views: array<vec4<f32>>;
#endif
#if RSM
// A ReflectiveShadowMaps pass: the instance index is the view (src/indirect/rsm_views.rs).
#include "common/light_inputs.wgsl"
@group(0) @binding(11) var<storage, read> rsm_views: array<vec4<f32>>;
#endif

#include "common/shading_point.wgsl"

#include <material>
#if SHADE
#include "common/light_loop.wgsl"
#endif
#if RSM
#include "indirect/rsm_texel.wgsl"
#endif

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) tangent: vec4<f32>,
    @location(4) color: vec4<f32>,
    @location(5) uv1: vec2<f32>,
};

#if MSAA
// At the centroid of the covered samples, not the pixel centre (which may lie off the
// triangle): the shaded point stays on the surface the samples hold, so the culled
// lists, bounded by those samples' depths, cover it.
struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(perspective, centroid) world: vec3<f32>,
    @location(1) @interpolate(perspective, centroid) normal: vec3<f32>,
    @location(2) @interpolate(perspective, centroid) uv: vec2<f32>,
    @location(3) @interpolate(perspective, centroid) tangent: vec4<f32>,
    @location(4) @interpolate(perspective, centroid) color: vec4<f32>,
    @location(5) @interpolate(perspective, centroid) uv1: vec2<f32>,
};
#else
struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) tangent: vec4<f32>,
    @location(4) color: vec4<f32>,
    @location(5) uv1: vec2<f32>,
#if RSM
    @location(6) @interpolate(flat) view: u32,
#endif
#if VISIBILITY
    // The mesh's first triangle id, passed as the instance index.
    @location(6) @interpolate(flat) first_triangle: u32,
#endif
};
#endif

@vertex
fn vs_main(v: VertexIn, @builtin(instance_index) instance: u32) -> VertexOut {
    var out: VertexOut;
#if ATLAS_DEPTH
    let b = 1u + 6u * instance;
    let view_proj = mat4x4<f32>(shadow_views[b], shadow_views[b + 1u], shadow_views[b + 2u], shadow_views[b + 3u]);
    out.clip = view_proj * vec4<f32>(v.position, 1.0);
#else
#if RSM
    let b = 1u + RSM_VIEW_VEC4S * instance;
    let view_proj = mat4x4<f32>(rsm_views[b], rsm_views[b + 1u], rsm_views[b + 2u], rsm_views[b + 3u]);
    out.clip = view_proj * vec4<f32>(v.position, 1.0);
    out.view = instance;
#else
    // The prepass and the shading pass run this same code, so depths match exactly.
    out.clip = frame.view_proj * vec4<f32>(v.position, 1.0);
#endif
#endif
    out.world = v.position;
    out.normal = v.normal;
    out.uv = v.uv;
    out.tangent = v.tangent;
    out.color = v.color;
    out.uv1 = v.uv1;
#if VISIBILITY
    out.first_triangle = instance;
#endif
    return out;
}

// The fragment's triangle normal, facing the eye (exact within a triangle: the world
// position is linear across it). Call in uniform control flow.
fn face_normal(world: vec3<f32>) -> vec3<f32> {
    let n = normalize(cross(dpdx(world), dpdy(world)));
    return select(n, -n, dot(n, frame.camera_pos.xyz - world) < 0.0);
}

fn shading_point(in: VertexOut, front: bool) -> ShadingPoint {
    var p: ShadingPoint;
    p.position = in.world;
    p.view = normalize(frame.camera_pos.xyz - in.world);
    var n = normalize(in.normal);
    if (!front) {
        n = -n;
    }
    p.normal = n;
    p.tangent = in.tangent;
    p.uv = in.uv;
    p.color = in.color;
    p.uv1 = in.uv1;
    return p;
}

#if GBUFFER
// Deferred shading's G-buffer: world position with the material index in w (-1 where
// nothing was drawn), and the shading normal (already facing the viewer). With
// GBUFFER_SURFACE two more targets, last: the surface the material samples
// (deferred/g_surface.wgsl) and the uv's screen derivatives; GBUFFER_UV1 (with it) adds
// the second uv set and its derivatives, for materials that sample with TEXCOORD_1.
#if GBUFFER_SURFACE
#include "deferred/g_surface.wgsl"
#endif
#if GBUFFER_PACKED
// Packed: one texture of view depth, octahedral normal and the material index (or -1).
#include "common/octahedral.wgsl"
struct GBufferOut {
    @location(0) packed: vec4<f32>,
#if GBUFFER_SURFACE
    @location(1) surface: vec4<f32>,
    @location(2) uv_grad: vec4<f32>,
#if GBUFFER_UV1
    @location(3) uv1: vec4<f32>,
    @location(4) uv1_grad: vec4<f32>,
#endif
#endif
};
#else
#if GBUFFER_NORMALS
struct GBufferOut {
    @location(0) position: vec4<f32>,
    @location(1) normal: vec4<f32>,
#if GBUFFER_GEOMETRIC
    // Ray-cast shadows: the triangle's normal, facing the eye.
    @location(2) geometric: vec4<f32>,
#if GBUFFER_SURFACE
    @location(3) surface: vec4<f32>,
    @location(4) uv_grad: vec4<f32>,
#if GBUFFER_UV1
    @location(5) uv1: vec4<f32>,
    @location(6) uv1_grad: vec4<f32>,
#endif
#endif
#else
#if GBUFFER_SURFACE
    @location(2) surface: vec4<f32>,
    @location(3) uv_grad: vec4<f32>,
#if GBUFFER_UV1
    @location(4) uv1: vec4<f32>,
    @location(5) uv1_grad: vec4<f32>,
#endif
#endif
#endif
};
#else
// Positions and geometric normals only (ray-cast shadows for forward shading).
struct GBufferOut {
    @location(0) position: vec4<f32>,
    @location(1) geometric: vec4<f32>,
};
#endif
#endif

@fragment
fn fs_gbuffer(in: VertexOut, @builtin(front_facing) front: bool) -> GBufferOut {
#if GBUFFER_GEOMETRIC
    let ng = face_normal(in.world);
#endif
#if GBUFFER_SURFACE
    // The derivatives forward shading's textureSample takes implicitly, across the 2×2
    // quad as the rasterizer takes them (uniform control flow: before any discard).
    let uv_grad = vec4<f32>(dpdxCoarse(in.uv), dpdyCoarse(in.uv));
#endif
#if GBUFFER_UV1
    let uv1_grad = vec4<f32>(dpdxCoarse(in.uv1), dpdyCoarse(in.uv1));
#endif
    let p = shading_point(in, front);
#if ALPHA_MASK
    let m = material_setup(p);
    if (material_alpha(m) < ALPHA_CUTOFF) {
        discard;
    }
#endif
    var out: GBufferOut;
#if GBUFFER_PACKED
    // Deferred shading rebuilds the position from the pixel's view ray and this depth.
    let view_z = -(frame.view * vec4<f32>(in.world, 1.0)).z;
    let n = oct_encode(p.normal);
    out.packed = vec4<f32>(view_z, n.x, n.y, f32(MATERIAL_INDEX));
#if GBUFFER_SURFACE
    // The tangent about the normal deferred shading decodes, so both build one frame.
    out.surface = encode_surface(oct_decode(n), p.tangent, p.uv, p.color.rgb);
#endif
#else
    out.position = vec4<f32>(in.world, f32(MATERIAL_INDEX));
#if GBUFFER_NORMALS
    out.normal = vec4<f32>(p.normal, 0.0);
#if GBUFFER_SURFACE
    out.surface = encode_surface(p.normal, p.tangent, p.uv, p.color.rgb);
#endif
#endif
#if GBUFFER_GEOMETRIC
    out.geometric = vec4<f32>(ng, 0.0);
#endif
#endif
#if GBUFFER_SURFACE
    out.uv_grad = uv_grad;
#endif
#if GBUFFER_UV1
    out.uv1 = vec4<f32>(p.uv1, 0.0, 0.0);
    out.uv1_grad = uv1_grad;
#endif
    return out;
}
#endif

#if DEPTH_ONLY
@fragment
fn fs_depth(in: VertexOut, @builtin(front_facing) front: bool) {
#if ALPHA_MASK
    let m = material_setup(shading_point(in, front));
    if (material_alpha(m) < ALPHA_CUTOFF) {
        discard;
    }
#endif
}
#endif

#if VISIBILITY
// The visibility buffer: the id of the triangle drawn here, the mesh's first id plus the
// primitive index within the draw (src/render/visibility_geometry.rs).
@fragment
fn fs_visibility(
    in: VertexOut,
    @builtin(front_facing) front: bool,
    @builtin(primitive_index) primitive: u32,
) -> @location(0) u32 {
#if ALPHA_MASK
    let m = material_setup(shading_point(in, front));
    if (material_alpha(m) < ALPHA_CUTOFF) {
        discard;
    }
#endif
    return in.first_triangle + primitive;
}
#endif

#if RSM
// What a texel of an indirect light's map reflects (indirect/rsm_texel.wgsl).
struct RsmOut {
    @location(0) normal: vec4<f32>,
    @location(1) flux: vec4<f32>,
    @location(2) position: vec4<f32>,
};

@fragment
fn fs_rsm(in: VertexOut) -> RsmOut {
    let t = rsm_texel(shading_point(in, true), in.view);
#if ALPHA_MASK
    if (t.alpha < ALPHA_CUTOFF) {
        discard;
    }
#endif
    return RsmOut(vec4<f32>(t.normal, 1.0), vec4<f32>(t.flux, 1.0), vec4<f32>(in.world, 1.0));
}
#endif

#if SHADE
@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
#if SHADOW_TRACE
    shadow_ng = face_normal(in.world);
#endif
    let p = shading_point(in, front);
    let m = material_setup(p);
#if ALPHA_MASK
    // The prepass discarded these fragments; shading must too, or a masked surface
    // nearer than the depth buffer would pass the LessEqual test.
    if (material_alpha(m) < ALPHA_CUTOFF) {
        discard;
    }
#endif
#if FLOAT_DEPTH
    // The depth attachment's test (LessEqual, depths cleared to 1.0), on the fragment's
    // own depth: the position's z is the value that test compares. After the material
    // setup: its texture samples take derivatives, which must not follow a discard.
    if (in.clip.z > textureLoad(depth, vec2<u32>(in.clip.xy), 0).x) {
        discard;
    }
#endif
    let view_z = -(frame.view * vec4<f32>(in.world, 1.0)).z;
    let color = shade_surface(p, m, in.clip.xy, view_z);
    return vec4<f32>(color, material_alpha(m));
}
#endif
