//! The CPU twin of `bvh_occluded` in `shaders/shadow/bvh.wgsl`, line by line: the same
//! f32 slab and triangle tests in the same stackless walk along the skip links, so tests
//! can hold the GPU traversal to the f64 reference through it.

use super::bvh::{BvhNode, BvhTriangle, ShadowBvh, MIN_DET, MIN_DIR, SLAB_SLACK};
use glam::Vec3;

impl ShadowBvh {
    /// Whether anything blocks `origin + t * dir` for `0 < t < t_max` (the CPU twin of
    /// `bvh_occluded` in `shaders/shadow/bvh.wgsl`): nodes in pre-order, a missed inner
    /// node's subtree skipped along its skip link. Every step moves forward, so even a
    /// malformed tree ends within one pass over the nodes.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        if !(origin.is_finite() && dir.is_finite() && t_max > 0.0) {
            return false;
        }
        let ray = Ray {
            origin,
            dir,
            inv_dir: safe_inverse(dir),
            t_max,
        };
        let mut i = 0usize;
        while let Some(node) = self.nodes.get(i) {
            let next = i + 1;
            if slab(node, &ray).is_none() {
                i = if node.is_leaf() {
                    next
                } else {
                    (node.b as usize).max(next)
                };
                continue;
            }
            if node.is_leaf() && self.leaf_hit(node, &ray) {
                return true;
            }
            i = next;
        }
        false
    }

    fn leaf_hit(&self, node: &BvhNode, ray: &Ray) -> bool {
        let first = node.a as usize;
        let count = node.count() as usize;
        let tris = self.triangles.get(first..first + count).unwrap_or(&[]);
        tris.iter().any(|t| {
            // A masked caster's triangle blocks only where its alpha is not cut out.
            triangle_hit(t, ray)
                .is_some_and(|(u, v)| t.alpha == 0 || !self.alpha.cut_out(t.alpha - 1, u, v))
        })
    }
}

struct Ray {
    origin: Vec3,
    dir: Vec3,
    inv_dir: Vec3,
    t_max: f32,
}

fn safe_inverse(d: Vec3) -> Vec3 {
    let fix = |c: f32| {
        if c.abs() < MIN_DIR {
            if c < 0.0 {
                -MIN_DIR
            } else {
                MIN_DIR
            }
        } else {
            c
        }
    };
    Vec3::ONE / Vec3::new(fix(d.x), fix(d.y), fix(d.z))
}

/// Entry distance if the ray's `[0, t_max]` overlaps the box.
fn slab(node: &BvhNode, ray: &Ray) -> Option<f32> {
    let t0 = (Vec3::from(node.min) - ray.origin) * ray.inv_dir;
    let t1 = (Vec3::from(node.max) - ray.origin) * ray.inv_dir;
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element().min(ray.t_max) * SLAB_SLACK;
    (near <= far).then_some(near)
}

/// Möller–Trumbore in f32, two-sided, hit for `0 < t < t_max`: the barycentrics of the
/// second and third vertex where it is hit.
fn triangle_hit(tri: &BvhTriangle, ray: &Ray) -> Option<(f32, f32)> {
    let (v0, e1, e2) = (Vec3::from(tri.v0), Vec3::from(tri.e1), Vec3::from(tri.e2));
    let p = ray.dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < MIN_DET {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = ray.origin - v0;
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = ray.dir.dot(q) * inv_det;
    let t = e2.dot(q) * inv_det;
    // Every comparison is false for NaN, so NaN misses.
    (v >= 0.0 && u + v <= 1.0 && t > 0.0 && t < ray.t_max).then_some((u, v))
}
