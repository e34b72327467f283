//! Ray-cast shadows, CPU side: a BVH over every shadow-casting scene triangle, flattened into the
//! GPU buffers `shaders/shadow/bvh.wgsl` traverses, a CPU twin of that traversal, and
//! an f64 brute-force reference to test both against.
//!
//! The pipeline this serves (AMD's Leo demo, tiled ray-cast shadows): G-buffer → light
//! culling → per-pixel ray-cast jobs → one thread per job casting an any-hit ray against
//! this BVH → a per-pixel hit mask the shading pass reads. This module is the part those
//! passes upload ([`ShadowBvh::nodes`], [`ShadowBvh::triangles`]) and test against
//! ([`ShadowBvh::occluded`], [`reference::occluded_reference`]).
//!
//! Ray convention everywhere: points `origin + t * dir` with `0 < t < t_max` (both ends
//! open; `dir` need not be unit length, `t` is in units of `dir`). Offsetting the origin
//! off the surface is the caller's job.

pub mod alpha;
pub mod atlas;
pub(crate) mod atlas_cache;
pub mod bvh;
pub mod chunks;
pub mod policy;
pub mod reference;
mod traverse;
pub(crate) mod view_bounds;

pub use bvh::{BuildOptions, BuildStats, BvhNode, BvhTriangle, ShadowBvh, ShadowError, LEAF_BIT};
pub use reference::{near_edge, occluded_reference, scene_triangles_f64, Triangle64};

/// A shadow ray from a shaded point towards a light, as every tracer casts it (the twin of
/// `shadow_origin` and `shadow_t_max` in `shaders/common/shadows.wgsl`, in the same f32
/// steps): `(origin, dir, t_max)` for `origin + t * dir`, `0 < t < t_max`.
///
/// Both ends stay off surfaces by `offset` times the larger of 1 and the largest coordinate
/// of that end (f32 positions are that much less precise): the origin along the geometric
/// normal `ng`, the end short of the light along the ray. A light lying on a surface, or at
/// an occluder's vertex, is then not hidden by that surface (its triangle would be hit at
/// t ≈ 1 either side of 1 by rounding).
pub fn shadow_ray(
    p: glam::Vec3,
    ng: glam::Vec3,
    light: glam::Vec3,
    offset: f32,
) -> (glam::Vec3, glam::Vec3, f32) {
    let magnitude = |v: glam::Vec3| v.x.abs().max(v.y.abs()).max(v.z.abs().max(1.0));
    let origin = p + ng * (offset * magnitude(p));
    let dir = light - origin;
    let t_max = (1.0 - offset * magnitude(light) / dir.length()).max(0.0);
    (origin, dir, t_max)
}
