// Any-hit shadow rays against the scene BVH that src/shadow/bvh.rs builds and flattens
// (ShadowBvh::nodes / ShadowBvh::triangles). ShadowBvh::occluded is the CPU twin of
// bvh_occluded below: keep the two in step.
//
// Bindings: the including shader declares
//     var<storage, read> bvh_nodes: array<BvhNode>;
//     var<storage, read> bvh_triangles: array<BvhTriangle>;
// at the group and binding it chooses, before including this file. With the define
// BVH_STANDALONE set, this file declares them itself at @group(0) @binding(0) and (1)
// (for tests and standalone passes).
//
// Ray convention: points origin + t * dir with 0 < t < t_max (open at both ends; dir
// need not be unit length). Offsetting the origin off the surface is the caller's job.

// 32 bytes. Depth-first pre-order: an inner node's left child is the next node.
// Inner: a = right child, b = first node after the subtree (skip link).
// Leaf:  a = first triangle, b = BVH_LEAF_BIT | triangle count.
struct BvhNode {
    min: vec3<f32>,
    a: u32,
    max: vec3<f32>,
    b: u32,
}

// 48 bytes, Möller–Trumbore form: e1 = v1 - v0, e2 = v2 - v0; id = scene triangle index.
struct BvhTriangle {
    v0: vec3<f32>,
    id: u32,
    e1: vec3<f32>,
    _pad0: u32,
    e2: vec3<f32>,
    _pad1: u32,
}

#if BVH_STANDALONE
@group(0) @binding(0) var<storage, read> bvh_nodes: array<BvhNode>;
@group(0) @binding(1) var<storage, read> bvh_triangles: array<BvhTriangle>;
#endif

const BVH_LEAF_BIT: u32 = 0x80000000u;
const BVH_STACK_SIZE: u32 = 32u;
// Direction components below this are replaced by +-this before the reciprocal, so the
// slab test never computes 0 * inf.
const BVH_MIN_DIR: f32 = 1e-20;
// Slab t_far is scaled by this (1 + 2 gamma_3) so rounding never culls a touched box.
const BVH_SLAB_SLACK: f32 = 1.0000004;
// Below this |det| the ray is parallel to the triangle.
const BVH_MIN_DET: f32 = 1e-30;
// Slab result for a missed box.
const BVH_MISS: f32 = -1.0;

fn bvh_is_leaf(n: BvhNode) -> bool {
    return (n.b & BVH_LEAF_BIT) != 0u;
}

fn bvh_safe_inverse(d: vec3<f32>) -> vec3<f32> {
    let tiny = select(vec3<f32>(BVH_MIN_DIR), vec3<f32>(-BVH_MIN_DIR), d < vec3<f32>(0.0));
    return vec3<f32>(1.0) / select(d, tiny, abs(d) < vec3<f32>(BVH_MIN_DIR));
}

// Entry distance (>= 0) if [0, t_max] of the ray overlaps the box, else BVH_MISS.
fn bvh_slab(n: BvhNode, origin: vec3<f32>, inv_dir: vec3<f32>, t_max: f32) -> f32 {
    let t0 = (n.min - origin) * inv_dir;
    let t1 = (n.max - origin) * inv_dir;
    let lo = min(t0, t1);
    let hi = max(t0, t1);
    let near = max(max(max(lo.x, lo.y), lo.z), 0.0);
    let far = min(min(min(hi.x, hi.y), hi.z), t_max) * BVH_SLAB_SLACK;
    return select(BVH_MISS, near, near <= far);
}

// Two-sided Möller–Trumbore, hit for 0 < t < t_max.
fn bvh_triangle_hit(tri: BvhTriangle, origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> bool {
    let p = cross(dir, tri.e2);
    let det = dot(tri.e1, p);
    if (abs(det) < BVH_MIN_DET) {
        return false;
    }
    let inv_det = 1.0 / det;
    let s = origin - tri.v0;
    let u = dot(s, p) * inv_det;
    if (u < 0.0 || u > 1.0) {
        return false;
    }
    let q = cross(s, tri.e1);
    let v = dot(dir, q) * inv_det;
    let t = dot(tri.e2, q) * inv_det;
    return v >= 0.0 && u + v <= 1.0 && t > 0.0 && t < t_max;
}

fn bvh_leaf_hit(n: BvhNode, origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> bool {
    let count = n.b & ~BVH_LEAF_BIT;
    for (var k = 0u; k < count; k++) {
        if (bvh_triangle_hit(bvh_triangles[n.a + k], origin, dir, t_max)) {
            return true;
        }
    }
    return false;
}

// Whether anything blocks origin + t * dir for 0 < t < t_max. Stack pass: both children
// are tested at their parent, the nearer is entered and the farther pushed on a
// BVH_STACK_SIZE-entry private stack. Should that stack overflow, the ray is re-cast from
// the root stackless along the skip links (exact: what the stack pass tested missed).
fn bvh_occluded(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> bool {
    if (!(t_max > 0.0)) {
        return false;
    }
    let inv_dir = bvh_safe_inverse(dir);
    var stack: array<u32, BVH_STACK_SIZE>;
    var sp = 0u;
    var overflow = false;
    var current = 0u;
    var alive = bvh_slab(bvh_nodes[0], origin, inv_dir, t_max) >= 0.0;
    // A well-formed tree visits each node at most once; more means a malformed one, and
    // the fallback (which always terminates) takes over.
    let node_count = arrayLength(&bvh_nodes);
    var steps = 0u;
    while (alive) {
        steps += 1u;
        if (steps > node_count) {
            overflow = true;
            break;
        }
        let node = bvh_nodes[current];
        var has_next = false;
        var next = 0u;
        if (bvh_is_leaf(node)) {
            if (bvh_leaf_hit(node, origin, dir, t_max)) {
                return true;
            }
        } else {
            let left = current + 1u;
            let right = node.a;
            let tl = bvh_slab(bvh_nodes[left], origin, inv_dir, t_max);
            let tr = bvh_slab(bvh_nodes[right], origin, inv_dir, t_max);
            if (tl >= 0.0 && tr >= 0.0) {
                if (sp == BVH_STACK_SIZE) {
                    overflow = true;
                    break;
                }
                let left_first = tl <= tr;
                stack[sp] = select(left, right, left_first);
                sp += 1u;
                next = select(right, left, left_first);
                has_next = true;
            } else if (tl >= 0.0) {
                next = left;
                has_next = true;
            } else if (tr >= 0.0) {
                next = right;
                has_next = true;
            }
        }
        if (has_next) {
            current = next;
        } else if (sp > 0u) {
            sp -= 1u;
            current = stack[sp];
        } else {
            alive = false;
        }
    }
    if (!overflow) {
        return false;
    }
    var i = 0u;
    while (i < node_count) {
        let node = bvh_nodes[i];
        let leaf = bvh_is_leaf(node);
        let skip = select(node.b, i + 1u, leaf);
        if (bvh_slab(node, origin, inv_dir, t_max) < 0.0) {
            i = max(skip, i + 1u);
            continue;
        }
        if (leaf && bvh_leaf_hit(node, origin, dir, t_max)) {
            return true;
        }
        i += 1u;
    }
    return false;
}
