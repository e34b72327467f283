//! Ray-cast shadows, CPU side: a BVH over every scene triangle, flattened into the
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

pub mod atlas;
pub mod bvh;
pub mod chunks;
pub mod reference;
mod traverse;

pub use bvh::{
    BuildOptions, BuildStats, BvhNode, BvhTriangle, ShadowBvh, ShadowError, LEAF_BIT, STACK_SIZE,
};
pub use reference::{near_edge, occluded_reference, scene_triangles_f64, Triangle64};
