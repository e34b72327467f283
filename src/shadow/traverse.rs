//! The CPU twin of `bvh_occluded` in `shaders/shadow/bvh.wgsl`, line by line: the same
//! f32 slab and triangle tests, the same short stack and the same exact stackless
//! fallback, so tests can hold the GPU traversal to the f64 reference through it.

use super::bvh::{
    BvhNode, BvhTriangle, ShadowBvh, TraversalStats, MIN_DET, MIN_DIR, SLAB_SLACK, STACK_SIZE,
};
use glam::Vec3;

impl ShadowBvh {
    /// Whether anything blocks `origin + t * dir` for `0 < t < t_max` (the CPU twin of
    /// `bvh_occluded` in `shaders/shadow/bvh.wgsl`).
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        self.traverse::<STACK_SIZE>(origin, dir, t_max).0
    }

    /// [`Self::occluded`] with a stack of `N` entries (the fallback path is exercised with
    /// small `N`), and what the traversal did.
    pub fn traverse<const N: usize>(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
    ) -> (bool, TraversalStats) {
        let mut stats = TraversalStats::default();
        if !(origin.is_finite() && dir.is_finite() && t_max > 0.0) || self.nodes.is_empty() {
            return (false, stats);
        }
        let inv_dir = safe_inverse(dir);
        let ray = Ray {
            origin,
            dir,
            inv_dir,
            t_max,
        };
        let nodes = &self.nodes;
        let node_at = |i: u32| nodes.get(i as usize).copied().unwrap_or_default();

        // Stack pass: test both children at their parent, go to the nearer, push the other.
        let mut stack = [0u32; N];
        let mut sp = 0usize;
        let mut overflow = false;
        let mut current = 0u32;
        let mut alive = slab(&node_at(0), &ray).is_some();
        // A well-formed tree visits each node at most once; more means a malformed one,
        // and the fallback (which always terminates) takes over.
        let mut steps = 0usize;
        while alive {
            steps += 1;
            if steps > nodes.len() {
                overflow = true;
                break;
            }
            stats.nodes_visited += 1;
            let node = node_at(current);
            let mut next = None;
            if node.is_leaf() {
                if self.leaf_hit(&node, &ray, &mut stats) {
                    return (true, stats);
                }
            } else {
                let left = current + 1;
                let right = node.a;
                let tl = slab(&node_at(left), &ray);
                let tr = slab(&node_at(right), &ray);
                match (tl, tr) {
                    (Some(l), Some(r)) => {
                        let (near, far) = if l <= r { (left, right) } else { (right, left) };
                        if sp == N {
                            overflow = true;
                            break;
                        }
                        stack[sp] = far;
                        sp += 1;
                        next = Some(near);
                    }
                    (Some(_), None) => next = Some(left),
                    (None, Some(_)) => next = Some(right),
                    (None, None) => {}
                }
            }
            match next {
                Some(n) => current = n,
                None if sp > 0 => {
                    sp -= 1;
                    current = stack[sp];
                }
                None => alive = false,
            }
        }
        if !overflow {
            return (false, stats);
        }

        // Fallback: stackless pre-order walk from the root along the skip links. It
        // re-tests what the stack pass already tested (none of which hit), so the answer
        // is exact.
        stats.fell_back = true;
        let mut i = 0u32;
        let end = nodes.len() as u32;
        while i < end {
            stats.nodes_visited += 1;
            let node = node_at(i);
            let skip = if node.is_leaf() { i + 1 } else { node.b };
            if slab(&node, &ray).is_none() {
                i = skip.max(i + 1);
                continue;
            }
            if node.is_leaf() && self.leaf_hit(&node, &ray, &mut stats) {
                return (true, stats);
            }
            i += 1;
        }
        (false, stats)
    }

    fn leaf_hit(&self, node: &BvhNode, ray: &Ray, stats: &mut TraversalStats) -> bool {
        let first = node.a as usize;
        let count = node.count() as usize;
        let tris = self.triangles.get(first..first + count).unwrap_or(&[]);
        tris.iter().any(|t| {
            stats.triangles_tested += 1;
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
