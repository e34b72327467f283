//! Brute-force reference for shadow rays: f64 Möller–Trumbore against every triangle, no
//! BVH; and the predicates that say when an f32 answer may honestly differ from it (the
//! ray passes within a tolerance of a triangle edge, starts or ends on a surface, or
//! grazes a triangle's plane), so GPU-vs-CPU comparisons can exclude and count such rays.
//!
//! Same ray convention as the BVH: `origin + t * dir`, `0 < t < t_max`.

use crate::scene::Scene;
use glam::DVec3;

/// A triangle in f64 (its three vertices).
pub type Triangle64 = [DVec3; 3];

/// Every triangle of the scene's shadow-casting meshes ([`Scene::casts_shadow`]) with
/// valid indices and finite coordinates, in f64, degenerate ones included (the reference
/// never hits a zero-area triangle, so keeping them checks that the BVH may skip them).
pub fn scene_triangles_f64(scene: &Scene) -> Vec<Triangle64> {
    let mut out = Vec::with_capacity(scene.triangle_count());
    for m in scene.meshes.iter().filter(|m| scene.casts_shadow(m)) {
        for t in m.indices.chunks_exact(3) {
            let p = |i: u32| m.positions.get(i as usize).copied();
            if let (Some(a), Some(b), Some(c)) = (p(t[0]), p(t[1]), p(t[2])) {
                if a.is_finite() && b.is_finite() && c.is_finite() {
                    out.push([a.as_dvec3(), b.as_dvec3(), c.as_dvec3()]);
                }
            }
        }
    }
    out
}

/// The hit distance, if the ray hits the triangle at `0 < t < t_max` (two-sided;
/// a ray parallel to the plane misses).
pub(crate) fn hit_reference(
    tri: &Triangle64,
    origin: DVec3,
    dir: DVec3,
    t_max: f64,
) -> Option<f64> {
    let e1 = tri[1] - tri[0];
    let e2 = tri[2] - tri[0];
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let s = origin - tri[0];
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = dir.dot(q) / det;
    let t = e2.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 && t < t_max).then_some(t)
}

/// Whether any triangle blocks the ray (f64, every triangle).
pub fn occluded_reference(tris: &[Triangle64], origin: DVec3, dir: DVec3, t_max: f64) -> bool {
    tris.iter()
        .any(|t| hit_reference(t, origin, dir, t_max).is_some())
}

/// Absolute slack for f32 data: f32 places a coordinate of magnitude `m` no finer than
/// `m * 2^-23`, and the f32 traversal rounds `origin - v0` and the edges at that scale.
/// 16 ulps of the largest coordinate involved.
fn f32_slop(tri: &Triangle64, origin: DVec3) -> f64 {
    let m = tri
        .iter()
        .chain(std::iter::once(&origin))
        .map(|v| v.abs().max_element())
        .fold(0.0, f64::max);
    16.0 * f32::EPSILON as f64 * m
}

fn longest_edge(tri: &Triangle64) -> f64 {
    let [a, b, c] = *tri;
    (b - a).length().max((c - b).length()).max((a - c).length())
}

/// The tolerance for one triangle: `eps` × its longest edge plus the f32 slop.
fn tolerance(tri: &Triangle64, origin: DVec3, eps: f64) -> f64 {
    eps * longest_edge(tri) + f32_slop(tri, origin)
}

/// Distance between the ray segment `[origin, origin + t_max * dir]` and the triangle's
/// bounding sphere (0 inside); a cheap reject before the edge tests.
fn segment_to_sphere(tri: &Triangle64, p0: DVec3, p1: DVec3) -> f64 {
    let c = (tri[0] + tri[1] + tri[2]) / 3.0;
    let r = tri.iter().map(|v| (*v - c).length()).fold(0.0, f64::max);
    (segment_point_distance(p0, p1, c) - r).max(0.0)
}

/// Whether the ray segment passes within `eps` (relative to the triangle's longest edge,
/// plus a few f32 ulps of the coordinates) of an edge of any triangle it comes near.
/// Exactly there an f32 traversal and the f64 reference may disagree (the two triangles
/// sharing the edge, or the edge of a silhouette).
pub fn near_edge(tris: &[Triangle64], origin: DVec3, dir: DVec3, t_max: f64, eps: f64) -> bool {
    let end = origin + dir * t_max;
    tris.iter().any(|tri| {
        let tol = tolerance(tri, origin, eps);
        if segment_to_sphere(tri, origin, end) > tol {
            return false;
        }
        (0..3).any(|k| segment_segment_distance(origin, end, tri[k], tri[(k + 1) % 3]) <= tol)
    })
}

/// Whether the ray starts or ends within the tolerance of a triangle (a hit at `t ≈ 0` or
/// `t ≈ t_max` is a coin toss in f32).
pub fn near_endpoint(tris: &[Triangle64], origin: DVec3, dir: DVec3, t_max: f64, eps: f64) -> bool {
    let end = origin + dir * t_max;
    tris.iter().any(|tri| {
        let tol = tolerance(tri, origin, eps);
        point_triangle_distance(origin, tri) <= tol || point_triangle_distance(end, tri) <= tol
    })
}

/// Whether the ray runs (nearly) in the plane of a triangle it passes within the
/// tolerance of: |cos(angle to the normal)| below `eps`. (Such a ray that crosses the
/// triangle is near an edge too; this catches the rest.)
pub fn grazing(tris: &[Triangle64], origin: DVec3, dir: DVec3, t_max: f64, eps: f64) -> bool {
    let end = origin + dir * t_max;
    let d = dir.normalize_or_zero();
    tris.iter().any(|tri| {
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero();
        if n.dot(d).abs() >= eps {
            return false;
        }
        let tol = tolerance(tri, origin, eps);
        segment_to_sphere(tri, origin, end) <= tol
            && segment_triangle_distance(origin, end, tri) <= tol
    })
}

/// Why a ray was excluded from an exact comparison, if it was.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ambiguity {
    /// The ray passes within the tolerance of a triangle edge ([`near_edge`]).
    NearEdge,
    /// The ray starts or ends within the tolerance of a triangle ([`near_endpoint`]).
    NearEndpoint,
    /// The ray runs nearly in the plane of a triangle it passes close to ([`grazing`]).
    Grazing,
}

/// [`near_edge`], then [`near_endpoint`], then [`grazing`]: the first that holds.
pub fn ambiguity(
    tris: &[Triangle64],
    origin: DVec3,
    dir: DVec3,
    t_max: f64,
    eps: f64,
) -> Option<Ambiguity> {
    if near_edge(tris, origin, dir, t_max, eps) {
        Some(Ambiguity::NearEdge)
    } else if near_endpoint(tris, origin, dir, t_max, eps) {
        Some(Ambiguity::NearEndpoint)
    } else if grazing(tris, origin, dir, t_max, eps) {
        Some(Ambiguity::Grazing)
    } else {
        None
    }
}

/// Distance from `p` to the segment `[a, b]`.
pub(crate) fn segment_point_distance(a: DVec3, b: DVec3, p: DVec3) -> f64 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t - p).length()
}

/// Distance between segments `[p0, p1]` and `[q0, q1]`: the closest pair of points,
/// minimising over the interior critical point and the four endpoint cases.
pub(crate) fn segment_segment_distance(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> f64 {
    let d1 = p1 - p0;
    let d2 = q1 - q0;
    let r = p0 - q0;
    let a = d1.length_squared();
    let e = d2.length_squared();
    let b = d1.dot(d2);
    let c = d1.dot(r);
    let f = d2.dot(r);
    let denom = a * e - b * b;
    let mut best = segment_point_distance(q0, q1, p0)
        .min(segment_point_distance(q0, q1, p1))
        .min(segment_point_distance(p0, p1, q0))
        .min(segment_point_distance(p0, p1, q1));
    // Non-parallel: the closest points of the two lines, if both lie inside the segments.
    if denom > 1e-300 * a.max(1.0) * e.max(1.0) {
        let s = (b * f - c * e) / denom;
        let t = (a * f - b * c) / denom;
        if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t) {
            best = best.min((p0 + d1 * s - (q0 + d2 * t)).length());
        }
    }
    best
}

/// Distance from `p` to the (solid) triangle.
pub fn point_triangle_distance(p: DVec3, tri: &Triangle64) -> f64 {
    let [a, b, c] = *tri;
    let n = (b - a).cross(c - a);
    let n2 = n.length_squared();
    let edges = segment_point_distance(a, b, p)
        .min(segment_point_distance(b, c, p))
        .min(segment_point_distance(c, a, p));
    if n2 == 0.0 {
        return edges;
    }
    // Projection onto the plane; inside if on the inner side of all three edges.
    let dist = (p - a).dot(n) / n2.sqrt();
    let proj = p - n * ((p - a).dot(n) / n2);
    let inside = [(a, b), (b, c), (c, a)]
        .iter()
        .all(|&(u, v)| (v - u).cross(proj - u).dot(n) >= 0.0);
    if inside {
        dist.abs()
    } else {
        edges
    }
}

/// Distance between the segment `[p0, p1]` and the (solid) triangle: 0 if the segment
/// crosses it, else the least of the edge-to-segment and endpoint-to-triangle distances.
pub fn segment_triangle_distance(p0: DVec3, p1: DVec3, tri: &Triangle64) -> f64 {
    if hit_reference(tri, p0, p1 - p0, 1.0).is_some() {
        return 0.0;
    }
    let edges = (0..3)
        .map(|k| segment_segment_distance(p0, p1, tri[k], tri[(k + 1) % 3]))
        .fold(f64::INFINITY, f64::min);
    edges
        .min(point_triangle_distance(p0, tri))
        .min(point_triangle_distance(p1, tri))
}
