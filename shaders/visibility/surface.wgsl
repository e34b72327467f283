// A pixel's surface point rebuilt from its triangle in the merged geometry
// (src/render/visibility_geometry.rs): the shading point at the pixel centre and, for
// textured materials (MATERIAL_TEXTURED), the uv derivatives the material samples with.
// Shared by visibility shading, the compute rasterizer's alpha test and the ray-cast
// shadow passes (surface_geometry), so all see the same surface. Needs `frame`,
// `vertices` and `triangles` bound, and with MATERIAL_TEXTURED the material code (which
// declares material_uv_ddx, material_uv_ddy and their TEXCOORD_1 twins) in the module.

#include "common/shading_point.wgsl"

struct Vertex {
    position: vec3<f32>,
    normal: vec3<f32>,
    uv: vec2<f32>,
    tangent: vec4<f32>,
    color: vec4<f32>,
    uv1: vec2<f32>,
};

fn fetch(v: u32) -> Vertex {
    let b = v * VERTEX_FLOATS;
    var out: Vertex;
    out.position = vec3<f32>(vertices[b], vertices[b + 1u], vertices[b + 2u]);
    out.normal = vec3<f32>(vertices[b + 3u], vertices[b + 4u], vertices[b + 5u]);
    out.uv = vec2<f32>(vertices[b + 6u], vertices[b + 7u]);
    out.tangent = vec4<f32>(vertices[b + 8u], vertices[b + 9u], vertices[b + 10u], vertices[b + 11u]);
    out.color = vec4<f32>(vertices[b + 12u], vertices[b + 13u], vertices[b + 14u], vertices[b + 15u]);
    out.uv1 = vec2<f32>(vertices[b + 16u], vertices[b + 17u]);
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

// Triangle `tri` at pixel `id`'s centre: its vertices, the edge functions and the
// centre's barycentrics (the triangle's plane extended where the centre lies outside it).
struct PixelTriangle {
    a: Vertex,
    b: Vertex,
    c: Vertex,
    e: Edges,
    // det(H)'s sign: front faces wind counter-clockwise in NDC.
    front: bool,
    w: vec3<f32>,
};

fn pixel_triangle(id: vec2<u32>, tri: u32) -> PixelTriangle {
    var t: PixelTriangle;
    t.a = fetch(triangles[3u * tri]);
    t.b = fetch(triangles[3u * tri + 1u]);
    t.c = fetch(triangles[3u * tri + 2u]);
    let h0 = (frame.view_proj * vec4<f32>(t.a.position, 1.0)).xyw;
    let h1 = (frame.view_proj * vec4<f32>(t.b.position, 1.0)).xyw;
    let h2 = (frame.view_proj * vec4<f32>(t.c.position, 1.0)).xyw;
    t.e = Edges(cross(h1, h2), cross(h2, h0), cross(h0, h1));
    t.front = dot(h0, t.e.e0) > 0.0;
    // The pixel centre in NDC (NDC y points up).
    let size = vec2<f32>(frame.size);
    let pixel = vec2<f32>(id) + 0.5;
    let q = vec2<f32>(pixel.x / size.x * 2.0 - 1.0, 1.0 - pixel.y / size.y * 2.0);
    t.w = bary_at(t.e, q);
    return t;
}

// The surface point at the pixel centre: where the camera ray through it meets the
// triangle's plane.
fn pixel_position(t: PixelTriangle) -> vec3<f32> {
    return t.w.x * t.a.position + t.w.y * t.b.position + t.w.z * t.c.position;
}

// What a shadow ray starts from (shadow/shadow_ray_jobs.wgsl, shadow_ray_cast.wgsl): the
// point visibility shading shades, and the triangle's normal facing the eye (the
// G-buffer's `g_geometric`).
struct SurfaceGeometry {
    position: vec3<f32>,
    ng: vec3<f32>,
};

fn surface_geometry(id: vec2<u32>, tri: u32) -> SurfaceGeometry {
    let t = pixel_triangle(id, tri);
    let position = pixel_position(t);
    let n = normalize(cross(t.b.position - t.a.position, t.c.position - t.a.position));
    let ng = select(n, -n, dot(n, frame.camera_pos.xyz - position) < 0.0);
    return SurfaceGeometry(position, ng);
}

// Triangle `tri`'s surface at pixel `id`'s centre.
fn surface_point(id: vec2<u32>, tri: u32) -> ShadingPoint {
    let t = pixel_triangle(id, tri);
    let a = t.a;
    let b = t.b;
    let c = t.c;
    let w = t.w;
    var p: ShadingPoint;
    p.position = pixel_position(t);
    p.view = normalize(frame.camera_pos.xyz - p.position);
    // Front faces wind counter-clockwise in NDC (the pipelines' FrontFace::Ccw); back
    // faces (double-sided materials) flip the normal as forward.wgsl's shading_point does.
    var n = normalize(w.x * a.normal + w.y * b.normal + w.z * c.normal);
    if (!t.front) {
        n = -n;
    }
    p.normal = n;
    p.tangent = w.x * a.tangent + w.y * b.tangent + w.z * c.tangent;
    p.color = w.x * a.color + w.y * b.color + w.z * c.color;
    let uv = mat3x2<f32>(a.uv, b.uv, c.uv);
    p.uv = uv * w;
    let uv1 = mat3x2<f32>(a.uv1, b.uv1, c.uv1);
    p.uv1 = uv1 * w;
#if MATERIAL_TEXTURED
    // The footprint textureSampleGrad filters over (its mip level): the uv one pixel
    // right and one down, taken as the rasterizer's coarse derivatives are, across the
    // pixel's 2×2 quad from its top-left pixel (the triangle's plane extended there, as
    // helper invocations do), so the level matches textureSample in forward shading.
    let e = t.e;
    let size = vec2<f32>(frame.size);
    // One pixel's step along x and y in NDC.
    let step = vec2<f32>(2.0 / size.x, -2.0 / size.y);
    let corner = vec2<f32>(id & vec2<u32>(~1u)) + 0.5;
    let q0 = vec2<f32>(corner.x / size.x * 2.0 - 1.0, 1.0 - corner.y / size.y * 2.0);
    let b0 = bary_at(e, q0);
    let bx = bary_at(e, q0 + vec2<f32>(step.x, 0.0));
    let by = bary_at(e, q0 + vec2<f32>(0.0, step.y));
    material_uv_ddx = uv * bx - uv * b0;
    material_uv_ddy = uv * by - uv * b0;
    material_uv1_ddx = uv1 * bx - uv1 * b0;
    material_uv1_ddy = uv1 * by - uv1 * b0;
#endif
    return p;
}
