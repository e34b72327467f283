// Compute rasterizer (ComputeRaster): the merged opaque triangles into a per-pixel u64,
// (depth bits << 32) | ~id, kept with a 64-bit atomic min. Depths are non-negative
// floats, so their bits order like integers; on equal depth the larger id has the
// smaller ~id and wins, as the render pipelines' LessEqual keeps the later draw.
// Entries: `clear` (the buffer to all ones, the large-triangle dispatch to zero
// workgroups), `raster` (one thread per triangle; a triangle whose clipped bounding box
// is over BIG_PIXELS goes to a list instead), `raster_big` (one workgroup of BIG_GROUP
// threads per listed triangle, sharing its pixels), `resolve_vs`/`resolve_fs` (a
// full-screen draw writing the id and frag_depth).
// Per triangle, as the hardware does: clip space with the vertex shader's own expression
// (frame.view_proj * position), clipped against the near plane z >= 0 and the viewport's
// sides (only where a vertex lies outside them), vertices
// snapped to 1/256 pixel, back faces of single-sided materials culled (front is
// counter-clockwise in NDC), pixel centres tested with exact 64-bit edge functions and
// the top-left rule, depth from the triangle's plane in screen space, pixels past the
// far plane (depth > 1) dropped.
// Defines: GROUP, BIG_GROUP, BIG_PIXELS; ATOMIC (raster entries: the buffer as atomics),
// BIG with it (`raster_big`, which does not bind the dispatch arguments it reads);
// RESOLVE (the resolve draw).

#include "common/types.wgsl"

// Triangle count, large-triangle list capacity, width, height.
@group(0) @binding(1) var<uniform> raster_params: vec4<u32>;
#if RESOLVE
@group(0) @binding(2) var<storage, read> vis: array<vec2<u32>>;
#else
@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(2) var<storage, read> vertices: array<f32>;
@group(0) @binding(3) var<storage, read> triangles: array<u32>;
@group(0) @binding(4) var<storage, read> single_sided: array<u32>;
@group(0) @binding(5) var<storage, read_write> big_list: array<u32>;
#if BIG
#else
// An indirect dispatch's arguments: the large-triangle dispatch reads them, so it binds
// nothing it could write.
@group(0) @binding(6) var<storage, read_write> big_args: array<atomic<u32>, 4>;
#endif
#if ATOMIC
@group(0) @binding(7) var<storage, read_write> vis: array<atomic<u64>>;
#else
@group(0) @binding(7) var<storage, read_write> vis: array<vec2<u32>>;
#endif
#endif

const NO_TRIANGLE: u32 = 0xffffffffu;
// Sub-pixel bits of snapped vertex positions (as lavapipe and most GPUs).
const SUBPIXEL: f32 = 256.0;
const HALF_PIXEL: i32 = 128;
// Where x and y clip: at the viewport's sides. lavapipe clips there too (and against the
// near plane) when a triangle needs clipping: with the planes 2 viewports out instead,
// 4 pixels of atrium_amd's near-clipped balustrade took another depth.
const GUARD: f32 = 1.0;
const MAX_POLY: u32 = 8u;

fn flat_index(wg: vec3<u32>, groups: vec3<u32>, local: u32, size: u32) -> u32 {
    return (wg.y * groups.x + wg.x) * size + local;
}

#if RESOLVE
@vertex
fn resolve_vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

struct Resolved {
    @location(0) id: u32,
    @builtin(frag_depth) depth: f32,
};

@fragment
fn resolve_fs(@builtin(position) pos: vec4<f32>) -> Resolved {
    let p = vec2<u32>(pos.xy);
    // Little-endian: x holds ~id, y the depth bits.
    let v = vis[p.y * raster_params.z + p.x];
    var out: Resolved;
    if (v.y == 0xffffffffu) {
        out.id = NO_TRIANGLE;
        out.depth = 1.0;
    } else {
        out.id = ~v.x;
        out.depth = bitcast<f32>(v.y);
    }
    return out;
}
#else
#if ATOMIC
#else

@compute @workgroup_size(GROUP)
fn clear(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let i = flat_index(wg, groups, local, GROUP);
    if (i == 0u) {
        atomicStore(&big_args[0], 0u);
        atomicStore(&big_args[1], 1u);
        atomicStore(&big_args[2], 1u);
    }
    if (i < raster_params.z * raster_params.w) {
        vis[i] = vec2<u32>(0xffffffffu, 0xffffffffu);
    }
}
#endif
#if ATOMIC

fn clip_position(v: u32) -> vec4<f32> {
    let b = 12u * v;
    let p = vec3<f32>(vertices[b], vertices[b + 1u], vertices[b + 2u]);
    return frame.view_proj * vec4<f32>(p, 1.0);
}

// Signed distance-like value of `c` to clip plane `k`: the near plane (z >= 0) and the
// viewport's four sides.
fn plane_distance(c: vec4<f32>, k: u32) -> f32 {
    if (k == 0u) {
        return c.z;
    }
    let axis = select(c.y, c.x, k < 3u);
    return GUARD * c.w + select(axis, -axis, k % 2u == 1u);
}

// The triangle clipped to a convex polygon (Sutherland-Hodgman), fanned from vertex 0.
struct Polygon {
    v: array<vec4<f32>, MAX_POLY>,
    n: u32,
};

fn clip_triangle(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>) -> Polygon {
    var p: Polygon;
    p.v[0] = a;
    p.v[1] = b;
    p.v[2] = c;
    p.n = 3u;
    for (var k = 0u; k < 5u; k++) {
        var outside = 0u;
        for (var i = 0u; i < p.n; i++) {
            outside += u32(plane_distance(p.v[i], k) < 0.0);
        }
        if (outside == 0u) {
            continue;
        }
        var q: Polygon;
        q.n = 0u;
        for (var i = 0u; i < p.n; i++) {
            let s = p.v[i];
            let e = p.v[(i + 1u) % p.n];
            let ds = plane_distance(s, k);
            let de = plane_distance(e, k);
            if (ds >= 0.0) {
                q.v[q.n] = s;
                q.n++;
            }
            if ((ds >= 0.0) != (de >= 0.0)) {
                // From the outside vertex, so the two triangles sharing an edge get the
                // same point (and as Mesa's clipper computes it).
                if (ds >= 0.0) {
                    q.v[q.n] = e + de / (de - ds) * (s - e);
                } else {
                    q.v[q.n] = s + ds / (ds - de) * (e - s);
                }
                q.n++;
            }
        }
        p = q;
        if (p.n < 3u) {
            p.n = 0u;
            break;
        }
    }
    return p;
}

// Framebuffer position (x right, y down, pixels) and depth, as the viewport transform.
fn to_screen(c: vec4<f32>) -> vec3<f32> {
    let ndc = c.xyz * (1.0 / c.w);
    let half = vec2<f32>(raster_params.zw) * 0.5;
    return vec3<f32>(ndc.x * half.x + half.x, ndc.y * -half.y + half.y, ndc.z);
}

fn snap(p: vec3<f32>) -> vec2<i32> {
    return vec2<i32>(round(p.xy * SUBPIXEL));
}

// Pixels whose centres lie in [lo, hi] (fixed point), clamped to the viewport; empty
// when x > z or y > w.
fn pixel_box(lo: vec2<i32>, hi: vec2<i32>) -> vec4<i32> {
    // ceil((lo - 128) / 256) and floor((hi - 128) / 256), with arithmetic shifts.
    let first = -((vec2<i32>(HALF_PIXEL) - lo) >> vec2<u32>(8u));
    let last = (hi - vec2<i32>(HALF_PIXEL)) >> vec2<u32>(8u);
    let size = vec2<i32>(raster_params.zw);
    return vec4<i32>(max(first, vec2<i32>(0)), min(last, size - 1));
}

fn edge(a: vec2<i32>, b: vec2<i32>, p: vec2<i32>) -> i64 {
    return i64(b.x - a.x) * i64(p.y - a.y) - i64(b.y - a.y) * i64(p.x - a.x);
}

// The top-left rule, for an edge a -> b of a triangle with positive area (clockwise on
// screen, y down): a left edge goes up, a top edge goes right.
fn top_left(a: vec2<i32>, b: vec2<i32>) -> bool {
    let d = b - a;
    return d.y < 0 || (d.y == 0 && d.x > 0);
}

// Pixels of one (clipped) triangle, the ones from `start` in steps of `stride` in
// row-major order of its box.
fn raster_triangle(
    ca: vec4<f32>,
    cb: vec4<f32>,
    cc: vec4<f32>,
    id: u32,
    cull_back: bool,
    start: u32,
    stride: u32,
) {
    let sa = to_screen(ca);
    var sb = to_screen(cb);
    var sc = to_screen(cc);
    let a = snap(sa);
    var b = snap(sb);
    var c = snap(sc);
    var area = edge(a, b, c);
    if (area == 0) {
        return;
    }
    // Positive area is clockwise on screen: clockwise in NDC too, a back face.
    if (area > 0 && cull_back) {
        return;
    }
    if (area < 0) {
        let t = b;
        b = c;
        c = t;
        let s = sb;
        sb = sc;
        sc = s;
        area = -area;
    }
    let box = pixel_box(min(a, min(b, c)), max(a, max(b, c)));
    if (box.x > box.z || box.y > box.w) {
        return;
    }
    // Depth plane from the unsnapped positions.
    let e1 = sb - sa;
    let e2 = sc - sa;
    let det = e1.x * e2.y - e1.y * e2.x;
    let dzdx = (e1.z * e2.y - e2.z * e1.y) / det;
    let dzdy = (e2.z * e1.x - e1.z * e2.x) / det;
    // Edge biases: a centre exactly on an edge counts only on top and left edges.
    let bias0 = select(-1, 0, top_left(b, c));
    let bias1 = select(-1, 0, top_left(c, a));
    let bias2 = select(-1, 0, top_left(a, b));
    let w = u32(box.z - box.x + 1);
    let count = w * u32(box.w - box.y + 1);
    let row = raster_params.z;
    for (var i = start; i < count; i += stride) {
        let px = box.x + i32(i % w);
        let py = box.y + i32(i / w);
        let p = vec2<i32>(px, py) * 256 + vec2<i32>(HALF_PIXEL);
        if (edge(b, c, p) + i64(bias0) < 0 || edge(c, a, p) + i64(bias1) < 0 || edge(a, b, p) + i64(bias2) < 0) {
            continue;
        }
        let centre = vec2<f32>(f32(px) + 0.5, f32(py) + 0.5);
        let z = sa.z + dzdx * (centre.x - sa.x) + dzdy * (centre.y - sa.y);
        if (!(z <= 1.0)) {
            continue;
        }
        let key = (u64(bitcast<u32>(max(z, 0.0))) << 32u) | u64(~id);
        atomicMin(&vis[u32(py) * row + u32(px)], key);
    }
}

// Triangle `id` clipped and rasterized; `defer`: hand it to the large-triangle list if
// its box is large (and the list has room).
fn raster_id(id: u32, start: u32, stride: u32, defer: bool) {
    let t = 3u * id;
    let poly = clip_triangle(
        clip_position(triangles[t]),
        clip_position(triangles[t + 1u]),
        clip_position(triangles[t + 2u]),
    );
    if (poly.n < 3u) {
        return;
    }
#if BIG
#else
    if (defer) {
        var lo = vec2<i32>(2147483647);
        var hi = vec2<i32>(-2147483647);
        for (var i = 0u; i < poly.n; i++) {
            let s = snap(to_screen(poly.v[i]));
            lo = min(lo, s);
            hi = max(hi, s);
        }
        let box = pixel_box(lo, hi);
        let pixels = max(box.z - box.x + 1, 0) * max(box.w - box.y + 1, 0);
        if (pixels > i32(BIG_PIXELS)) {
            let slot = atomicAdd(&big_args[0], 1u);
            if (slot < raster_params.y) {
                big_list[slot] = id;
                return;
            }
            // Full: counted back out, and drawn here.
            atomicSub(&big_args[0], 1u);
        }
    }
#endif
    let cull_back = (single_sided[id / 32u] & (1u << (id % 32u))) != 0u;
    for (var k = 1u; k + 1u < poly.n; k++) {
        raster_triangle(poly.v[0], poly.v[k], poly.v[k + 1u], id, cull_back, start, stride);
    }
}

#if BIG
@compute @workgroup_size(BIG_GROUP)
fn raster_big(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    raster_id(big_list[wg.x], local, BIG_GROUP, false);
}
#else
@compute @workgroup_size(GROUP)
fn raster(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let id = flat_index(wg, groups, local, GROUP);
    if (id < raster_params.x) {
        raster_id(id, 0u, 1u, true);
    }
}

#endif
#endif
#endif
