// What the two compute rasterizers (visibility/compute_raster.wgsl for the frame,
// shadow/atlas_raster.wgsl for the shadow atlas's views) set a triangle up with, as the
// raster pipeline does: near and side clipping in clip space, 1/256-pixel snapping and
// ordering (`snap_triangle`), exact 64-bit edge functions and the top-left fill rule.

// Subpixel steps a pixel (or texel): positions snap to 1/256, as the raster pipeline's.
const SUBPIXEL: f32 = 256.0;
// Most vertices a triangle clipped by five planes can have.
const MAX_POLY: u32 = 8u;

// Signed distance-like value of `c` to clip plane `k`: the near plane (z >= 0) and the
// viewport's (or the atlas tile's) four sides. x and y clip at the sides, with no guard
// band: lavapipe clips there too (and against the near plane) when a triangle needs
// clipping; with the planes 2 viewports out instead, 4 pixels of atrium_amd's
// near-clipped balustrade took another depth in the frame.
fn plane_distance(c: vec4<f32>, k: u32) -> f32 {
    if (k == 0u) {
        return c.z;
    }
    let axis = select(c.y, c.x, k < 3u);
    return c.w + select(axis, -axis, k % 2u == 1u);
}

fn edge(a: vec2<i32>, b: vec2<i32>, p: vec2<i32>) -> i64 {
    return i64(b.x - a.x) * i64(p.y - a.y) - i64(b.y - a.y) * i64(p.x - a.x);
}

fn snap(p: vec3<f32>) -> vec2<i32> {
    return vec2<i32>(round(p.xy * SUBPIXEL));
}

// The top-left rule, for an edge a -> b of a triangle with positive area (clockwise on
// screen, y down): a left edge goes up, a top edge goes right.
fn top_left(a: vec2<i32>, b: vec2<i32>) -> bool {
    let d = b - a;
    return d.y < 0 || (d.y == 0 && d.x > 0);
}

// A screen triangle snapped and ordered for the edge tests: clockwise on screen (positive
// snapped area), its unsnapped vertices (x, y, depth) in the same order. `facing` is the
// snapped area's sign before ordering (0: degenerate, no pixel; positive: clockwise,
// which is clockwise in NDC too, a back face).
struct Snapped {
    a: vec2<i32>,
    b: vec2<i32>,
    c: vec2<i32>,
    sa: vec3<f32>,
    sb: vec3<f32>,
    sc: vec3<f32>,
    facing: i32,
}

fn snap_triangle(sa: vec3<f32>, sb: vec3<f32>, sc: vec3<f32>) -> Snapped {
    var t: Snapped;
    t.a = snap(sa);
    t.b = snap(sb);
    t.c = snap(sc);
    t.sa = sa;
    t.sb = sb;
    t.sc = sc;
    let area = edge(t.a, t.b, t.c);
    t.facing = select(select(-1, 1, area > 0), 0, area == 0);
    if (area < 0) {
        t.b = snap(sc);
        t.c = snap(sb);
        t.sb = sc;
        t.sc = sb;
    }
    return t;
}

// The depth's slopes (per pixel in x and y) of the plane through the unsnapped vertices.
fn depth_slopes(t: Snapped) -> vec2<f32> {
    let e1 = t.sb - t.sa;
    let e2 = t.sc - t.sa;
    let det = e1.x * e2.y - e1.y * e2.x;
    return vec2<f32>((e1.z * e2.y - e2.z * e1.y) / det, (e2.z * e1.x - e1.z * e2.x) / det);
}

// Whether `clip_triangle` would change the triangle: some vertex outside some plane.
// Most triangles are inside: they skip the polygon array (local memory on GPUs).
fn needs_clipping(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>) -> bool {
    for (var k = 0u; k < 5u; k++) {
        if (plane_distance(a, k) < 0.0 || plane_distance(b, k) < 0.0 || plane_distance(c, k) < 0.0) {
            return true;
        }
    }
    return false;
}

// Whether all three vertices lie outside one plane: the triangle is wholly outside,
// and `clip_triangle` would leave nothing of it (cheaply, without the polygon arrays).
fn outside_one_plane(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>) -> bool {
    for (var k = 0u; k < 5u; k++) {
        if (plane_distance(a, k) < 0.0 && plane_distance(b, k) < 0.0 && plane_distance(c, k) < 0.0) {
            return true;
        }
    }
    return false;
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
