// Visibility-buffer shading in a compute shader: one dispatch per material over the whole
// frame; each invocation whose pixel holds a triangle of this material (its id in
// `material_triangles[MATERIAL_INDEX]`) fetches the triangle's three vertices, rebuilds
// the surface at the pixel centre and shades it with the same material code and light
// loop as forward shading. Ids: src/render/visibility_geometry.rs (NO_TRIANGLE where
// nothing was drawn).
// Defines: SHADING_GROUP (the workgroup's side in pixels; 8 with STAGED_LIGHTS),
// MATERIAL_INDEX, CLEARS (this dispatch stores black where nothing was drawn),
// LIGHT_LISTS (tile lists) or LINKED_LISTS (a light linked list), and the light loop:
// STAGED_LIGHTS (the workgroup's one tile list staged in workgroup memory, in
// visibility/staged_lights.wgsl), RANGE_FIRST (the per-pixel cursor with the range test
// before the light's properties; with UNIFORM_LIST the workgroup's one tile list, found
// from the workgroup id, so the compiler sees the walk as uniform), or neither
// (common/light_loop.wgsl's shade_surface, as forward shading runs it).

#include "common/types.wgsl"
#include "common/lighting.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
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
@group(0) @binding(5) var visibility: texture_2d<u32>;
@group(0) @binding(6) var<storage, read> vertices: array<f32>;
@group(0) @binding(7) var<storage, read> triangles: array<u32>;
@group(0) @binding(8) var<storage, read> material_triangles: array<vec2<u32>>;
@group(0) @binding(9) var hdr: texture_storage_2d<rgba32float, write>;

#include "common/light_lists.wgsl"

struct ShadingPoint {
    position: vec3<f32>,
    normal: vec3<f32>,
    tangent: vec4<f32>,
    uv: vec2<f32>,
    view: vec3<f32>,
};

// Material code generated with WgslOptions::sample_grad when it has textures: it samples
// with material_uv_ddx / material_uv_ddy, set below before material_setup.
#include <material>
#include "common/light_loop.wgsl"
#include "visibility/staged_lights.wgsl"

const NO_TRIANGLE: u32 = 0xffffffffu;
const VERTEX_FLOATS: u32 = 12u;

struct Vertex {
    position: vec3<f32>,
    normal: vec3<f32>,
    uv: vec2<f32>,
    tangent: vec4<f32>,
};

fn fetch(v: u32) -> Vertex {
    let b = v * VERTEX_FLOATS;
    var out: Vertex;
    out.position = vec3<f32>(vertices[b], vertices[b + 1u], vertices[b + 2u]);
    out.normal = vec3<f32>(vertices[b + 3u], vertices[b + 4u], vertices[b + 5u]);
    out.uv = vec2<f32>(vertices[b + 6u], vertices[b + 7u]);
    out.tangent = vec4<f32>(vertices[b + 8u], vertices[b + 9u], vertices[b + 10u], vertices[b + 11u]);
    return out;
}

// Perspective-correct barycentrics by 2D homogeneous rasterization (Olano & Greer 1997):
// the surface point b0 p0 + b1 p1 + b2 p2 projects to the NDC point q where its clip
// position (x, y, w), linear in b, is a multiple of (q, 1): b = s H⁻¹ (q, 1) with H's
// columns the vertices' clip (x, y, w), H⁻¹'s rows the cross products of pairs. No
// division by w, so it holds for triangles crossing the camera plane too.
struct Edges {
    e0: vec3<f32>,
    e1: vec3<f32>,
    e2: vec3<f32>,
};

fn bary_at(e: Edges, q: vec2<f32>) -> vec3<f32> {
    let h = vec3<f32>(q, 1.0);
    let b = vec3<f32>(dot(e.e0, h), dot(e.e1, h), dot(e.e2, h));
    return b / (b.x + b.y + b.z);
}

// A pixel's surface, rebuilt from its triangle, with what the light loop takes.
struct Surface {
    p: ShadingPoint,
    m: MaterialSample,
    pixel: vec2<f32>,
    view_z: f32,
};

fn rebuild(id: vec2<u32>, tri: u32) -> Surface {
    let a = fetch(triangles[3u * tri]);
    let b = fetch(triangles[3u * tri + 1u]);
    let c = fetch(triangles[3u * tri + 2u]);
    let ca = frame.view_proj * vec4<f32>(a.position, 1.0);
    let cb = frame.view_proj * vec4<f32>(b.position, 1.0);
    let cc = frame.view_proj * vec4<f32>(c.position, 1.0);
    let h0 = ca.xyw;
    let h1 = cb.xyw;
    let h2 = cc.xyw;
    let e = Edges(cross(h1, h2), cross(h2, h0), cross(h0, h1));
    // The pixel centre in NDC, and one pixel's step along x and y (NDC y points up).
    let size = vec2<f32>(frame.size);
    let pixel = vec2<f32>(id) + 0.5;
    let q = vec2<f32>(pixel.x / size.x * 2.0 - 1.0, 1.0 - pixel.y / size.y * 2.0);
    let step = vec2<f32>(2.0 / size.x, -2.0 / size.y);
    let w = bary_at(e, q);

    var p: ShadingPoint;
    p.position = w.x * a.position + w.y * b.position + w.z * c.position;
    p.view = normalize(frame.camera_pos.xyz - p.position);
    // Front faces wind counter-clockwise in NDC (the pipelines' FrontFace::Ccw): the
    // sign of det(H); back faces (double-sided materials) flip the normal as
    // forward.wgsl's shading_point does.
    let front = dot(h0, e.e0) > 0.0;
    var n = normalize(w.x * a.normal + w.y * b.normal + w.z * c.normal);
    if (!front) {
        n = -n;
    }
    p.normal = n;
    p.tangent = w.x * a.tangent + w.y * b.tangent + w.z * c.tangent;
    let uv = mat3x2<f32>(a.uv, b.uv, c.uv);
    p.uv = uv * w;
#if MATERIAL_TEXTURED
    // The footprint textureSampleGrad filters over (its mip level): the uv one pixel
    // right and one down, taken as the rasterizer's coarse derivatives are, across the
    // pixel's 2×2 quad from its top-left pixel (the triangle's plane extended there, as
    // helper invocations do), so the level matches textureSample in forward shading.
    let corner = vec2<f32>(id & vec2<u32>(~1u)) + 0.5;
    let q0 = vec2<f32>(corner.x / size.x * 2.0 - 1.0, 1.0 - corner.y / size.y * 2.0);
    let uv0 = uv * bary_at(e, q0);
    material_uv_ddx = uv * bary_at(e, q0 + vec2<f32>(step.x, 0.0)) - uv0;
    material_uv_ddy = uv * bary_at(e, q0 + vec2<f32>(0.0, step.y)) - uv0;
#endif
    let m = material_setup(p);
    let view_z = -(frame.view * vec4<f32>(p.position, 1.0)).z;
    return Surface(p, m, pixel, view_z);
}

#if STAGED_LIGHTS
// Whether any pixel of the workgroup is this material's (zeroed at workgroup start).
var<workgroup> group_shades: atomic<u32>;

// Every invocation, its pixel in the frame or not, takes part in staging the lights: the
// barriers need all of them. A workgroup none of whose pixels is this material's leaves
// before loading anything.
@compute @workgroup_size(8, 8, 1)
fn main(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(workgroup_id) group: vec3<u32>,
) {
    let inside = all(id.xy < frame.size);
    var tri = NO_TRIANGLE;
    if (inside) {
        tri = textureLoad(visibility, id.xy, 0).x;
    }
#if CLEARS
    if (inside && tri == NO_TRIANGLE) {
        textureStore(hdr, id.xy, vec4<f32>(0.0));
    }
#endif
    let range = material_triangles[MATERIAL_INDEX];
    let shades = tri != NO_TRIANGLE && tri >= range.x && tri < range.y;
    if (shades) {
        atomicOr(&group_shades, 1u);
    }
    if (workgroupUniformLoad(&group_shades) == 0u) {
        return;
    }
    // Every invocation rebuilds a surface (one of this material's triangles where its
    // pixel has none of them) and the light loop skips those that do not shade: a
    // surface rebuilt in a branch and shaded after it came out one ulp off in a few
    // pixels on lavapipe (the compiler fuses the arithmetic differently). A warp with
    // any pixel of this material pays for the rebuild anyway.
    let s = rebuild(id.xy, select(range.x, tri, shades));
    let color = staged_lights(surface_unlit(s.p, s.m), shades, s.p, s.m, lane, group_list(group.xy));
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

@compute @workgroup_size(SHADING_GROUP, SHADING_GROUP, 1)
fn main(@builtin(local_invocation_index) lane: u32, @builtin(workgroup_id) group: vec3<u32>) {
    let id = group.xy * SHADING_GROUP + block_pixel(lane);
    if (any(id.xy >= frame.size)) {
        return;
    }
    let tri = textureLoad(visibility, id.xy, 0).x;
    let range = material_triangles[MATERIAL_INDEX];
    if (tri == NO_TRIANGLE) {
#if CLEARS
        textureStore(hdr, id.xy, vec4<f32>(0.0));
#endif
        return;
    }
    if (tri < range.x || tri >= range.y) {
        return;
    }
    let s = rebuild(id.xy, tri);
#if RANGE_FIRST
#if UNIFORM_LIST
    let color = shade_list(s.p, s.m, group_list(group.xy));
#else
    let color = shade_range_first(s.p, s.m, s.pixel, s.view_z);
#endif
#else
    let color = shade_surface(s.p, s.m, s.pixel, s.view_z);
#endif
    textureStore(hdr, id.xy, vec4<f32>(color, material_alpha(s.m)));
}
#endif
