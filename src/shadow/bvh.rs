//! A BVH over every shadow-casting scene triangle (blended meshes only where they opt in)
//! for any-hit shadow rays, built with `obvhs` (PLOC, single-threaded: the crate's
//! `parallel` feature is off) and flattened into two GPU-ready arrays:
//!
//! * [`BvhNode`], 32 bytes, in depth-first pre-order. The left child of an inner node is
//!   the next node; `a` is the right child; `b` is the first node after the subtree (the
//!   "skip" link the stackless fallback follows). A leaf has `b = LEAF_BIT | count` and its
//!   triangles are `triangles[a .. a + count]`.
//! * [`BvhTriangle`], 48 bytes: `v0`, `e1 = v1 - v0`, `e2 = v2 - v0` (Möller–Trumbore
//!   form) and the triangle's index in the scene.
//!
//! [`ShadowBvh::occluded`] is a line-by-line twin of `bvh_occluded` in
//! `shaders/shadow/bvh.wgsl`: the same f32 slab and triangle tests, the same 32-entry
//! stack and the same exact fallback when that stack would overflow.

use super::alpha::{AlphaBuilder, AlphaTable};
use crate::scene::{Mesh, Scene};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::time::{Duration, Instant};
use thiserror::Error;

/// Set in [`BvhNode::b`] of a leaf; the low bits are its triangle count.
pub const LEAF_BIT: u32 = 0x8000_0000;
/// Direction components smaller than this are replaced by ±this before the reciprocal,
/// so the slab test never computes `0 * inf`.
pub const MIN_DIR: f32 = 1e-20;
/// `t_far` of a slab test is scaled by this, so rounding never culls a box the ray
/// touches (1 + 2γ₃, Ize, "Robust BVH Ray Traversal").
pub const SLAB_SLACK: f32 = 1.000_000_4;
/// Below this |det| a ray counts as parallel to a triangle (miss).
pub const MIN_DET: f32 = 1e-30;

/// A BVH node as the GPU reads it (`BvhNode` in `shaders/shadow/bvh.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    /// Low corner of the node's bounding box, world space.
    pub min: [f32; 3],
    /// Inner: index of the right child (the left child is the next node). Leaf: first
    /// triangle.
    pub a: u32,
    /// High corner of the node's bounding box, world space.
    pub max: [f32; 3],
    /// Inner: index of the first node after this subtree. Leaf: `LEAF_BIT | count`.
    pub b: u32,
}

impl BvhNode {
    /// Whether the node is a leaf (`b` has [`LEAF_BIT`]).
    pub fn is_leaf(&self) -> bool {
        self.b & LEAF_BIT != 0
    }
    /// Triangles in a leaf (0 for inner nodes).
    pub fn count(&self) -> u32 {
        if self.is_leaf() {
            self.b & !LEAF_BIT
        } else {
            0
        }
    }
}

/// A triangle as the GPU reads it (`BvhTriangle` in `shaders/shadow/bvh.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhTriangle {
    /// First vertex, world space.
    pub v0: [f32; 3],
    /// Index of the triangle in the scene: meshes in order, triangles in index order,
    /// skipped triangles counted too (so it maps back to mesh and triangle).
    pub id: u32,
    /// Edge from `v0` to the second vertex (v1 − v0), precomputed for the ray–triangle test.
    pub e1: [f32; 3],
    /// 0 for a triangle that blocks every ray it meets; 1 + its record in
    /// [`ShadowBvh::alpha`] for an alpha-masked one, which blocks only where its
    /// material's alpha reaches the cutoff.
    pub alpha: u32,
    /// Edge from `v0` to the third vertex (v2 − v0).
    pub e2: [f32; 3],
    /// Padding to the WGSL struct's 16-byte alignment.
    pub _pad1: u32,
}

/// Why a shadow BVH could not be built: the GPU addresses triangles and nodes with 31 bits.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum ShadowError {
    /// More triangles than 31-bit indices address.
    #[error("{count} shadow-casting triangles do not fit the 31-bit GPU indices")]
    TooManyTriangles {
        /// Shadow-casting triangles in the scene.
        count: usize,
    },
    /// More nodes than 31-bit indices address.
    #[error("the shadow BVH has {count} nodes, more than 31-bit GPU indices address")]
    TooManyNodes {
        /// Nodes the tree would have.
        count: usize,
    },
}

/// How hard the builder works; a scene file's choice, so it lives with the scene.
pub use crate::scene::BuildQuality;

/// How the shadow BVH is built ([`ShadowBvh::build_with`]); the default is what scenes get.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildOptions {
    /// How hard the PLOC builder works (a scene file's `shadow_bvh`).
    pub quality: BuildQuality,
    /// Most triangles in a leaf (1..=255). Subtrees up to this size become leaves where
    /// the surface area heuristic says a leaf is cheaper.
    pub max_leaf_triangles: u32,
    /// Cost of visiting an inner node relative to testing one triangle, for that
    /// leaf-collapse decision.
    pub traversal_cost: f32,
    /// Most bytes the alpha data of masked casters may take ([`ShadowBvh::alpha`]: the
    /// device's storage binding limit).
    pub max_alpha_bytes: u64,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self {
            quality: BuildQuality::default(),
            max_leaf_triangles: 8,
            traversal_cost: 2.0,
            // wgpu's default storage binding limit.
            max_alpha_bytes: 128 << 20,
        }
    }
}

impl BuildOptions {
    /// (PLOC search distance, depth below which it drops to 1, reinsertion batch ratio).
    fn ploc(&self) -> (obvhs::ploc::PlocSearchDistance, usize, f32) {
        use obvhs::ploc::PlocSearchDistance::*;
        match self.quality {
            BuildQuality::Fastest => (Minimum, 0, 0.0),
            BuildQuality::VeryFast => (Minimum, 0, 0.01),
            BuildQuality::Fast => (Low, 2, 0.02),
            BuildQuality::Medium => (Medium, 3, 0.05),
        }
    }
}

/// What a build did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BuildStats {
    /// Triangles in the BVH.
    pub triangles: usize,
    /// Triangles the scene's index lists name (whole triples).
    pub input_triangles: usize,
    /// Skipped: zero area (collinear or repeated vertices).
    pub skipped_degenerate: usize,
    /// Skipped: a NaN or infinite coordinate.
    pub skipped_non_finite: usize,
    /// Skipped: an index past the mesh's vertices (plus trailing indices that make no
    /// whole triangle).
    pub skipped_bad_index: usize,
    /// Left out: triangles of meshes that cast no shadow (blended meshes that did not opt
    /// in, see [`Scene::casts_shadow`]). Counted in `input_triangles` too.
    pub left_out_non_casting: usize,
    /// Nodes in the flattened tree, inner and leaf.
    pub nodes: usize,
    /// Leaf nodes.
    pub leaves: usize,
    /// Longest root-to-leaf path, in nodes (a lone root leaf is depth 1).
    pub max_depth: usize,
    /// Everything: gathering triangles, the obvhs build, flattening.
    pub build_time: Duration,
    /// Reading the scene's triangles (and skipping the bad ones) and their boxes.
    pub(crate) gather_time: Duration,
    /// The obvhs PLOC build and reinsertion alone.
    pub core_build_time: Duration,
    /// SAH leaf collapse and flattening into [`ShadowBvh::nodes`] / `triangles`.
    pub(crate) flatten_time: Duration,
    /// Surface-area-heuristic cost of the tree: expected triangle tests plus
    /// `traversal_cost` × inner-node visits for a random ray through the root box.
    pub(crate) sah_cost: f32,
}

/// The flattened BVH: what the GPU uploads, and its CPU twin traversal.
#[derive(Clone, Debug, Default)]
pub struct ShadowBvh {
    /// Never empty: an empty scene has one empty leaf.
    pub nodes: Vec<BvhNode>,
    /// Never empty (storage bindings may not be): an empty scene has one zeroed
    /// triangle no leaf names. [`BuildStats::triangles`] is the real count.
    pub triangles: Vec<BvhTriangle>,
    /// What the build did and how long it took.
    pub stats: BuildStats,
    /// What alpha-tested rays read where they hit a masked caster (`bvh_alpha`).
    pub alpha: AlphaTable,
}

struct Gathered {
    tris: Vec<[Vec3; 3]>,
    ids: Vec<u32>,
    /// Each triangle's [`BvhTriangle::alpha`].
    alpha: Vec<u32>,
    stats: BuildStats,
}

/// One mesh for [`gather`]: its positions, its indices, whether it casts shadows, and
/// the scene mesh where its material may alpha-test rays.
type GatherMesh<'a> = (&'a [Vec3], &'a [u32], bool, Option<&'a Mesh>);

/// Every drawable triangle of the casting meshes, in world space exactly as the renderer
/// draws it (`Mesh::positions` are already world space; no transforms), with the skips
/// counted. Ids count the triangles of every mesh, casting or not, so they stay scene
/// triangle indices.
fn gather<'a>(
    meshes: impl Iterator<Item = GatherMesh<'a>>,
    mut alpha: Option<&mut AlphaBuilder>,
) -> Gathered {
    let mut g = Gathered {
        tris: Vec::new(),
        ids: Vec::new(),
        alpha: Vec::new(),
        stats: BuildStats::default(),
    };
    let mut id: u64 = 0;
    for (positions, indices, casts, mesh) in meshes {
        let masked = mesh.filter(|m| alpha.as_ref().is_some_and(|a| a.tests(m.material)));
        if !casts {
            let count = indices.len() / 3;
            g.stats.input_triangles += count;
            g.stats.left_out_non_casting += count;
            id += count as u64;
            continue;
        }
        g.stats.skipped_bad_index += usize::from(indices.len() % 3 != 0);
        for t in indices.chunks_exact(3) {
            g.stats.input_triangles += 1;
            let this = id;
            id += 1;
            let fetch = |i: u32| positions.get(i as usize).copied();
            let (Some(p0), Some(p1), Some(p2)) = (fetch(t[0]), fetch(t[1]), fetch(t[2])) else {
                g.stats.skipped_bad_index += 1;
                continue;
            };
            if !(p0.is_finite() && p1.is_finite() && p2.is_finite()) {
                g.stats.skipped_non_finite += 1;
                continue;
            }
            // Area in f64 from the f32 inputs (products of f32 are exact in f64), so only
            // truly flat triangles count as degenerate.
            let (d0, d1, d2) = (p0.as_dvec3(), p1.as_dvec3(), p2.as_dvec3());
            if (d1 - d0).cross(d2 - d0).length_squared() == 0.0 {
                g.stats.skipped_degenerate += 1;
                continue;
            }
            g.tris.push([p0, p1, p2]);
            g.ids.push(this.min(u32::MAX as u64) as u32);
            g.alpha.push(match (masked, alpha.as_deref_mut()) {
                (Some(m), Some(a)) => a.push_triangle(m, [t[0], t[1], t[2]]),
                _ => 0,
            });
        }
    }
    g
}

/// An empty leaf no ray enters (what an empty scene's BVH is).
const EMPTY_LEAF: BvhNode = BvhNode {
    min: [f32::MAX; 3],
    a: 0,
    max: [f32::MIN; 3],
    b: LEAF_BIT,
};

fn to_obvhs(v: Vec3) -> glam_obvhs::Vec3A {
    glam_obvhs::Vec3A::new(v.x, v.y, v.z)
}

impl ShadowBvh {
    /// Builds over every triangle of every mesh in the scene that casts shadows
    /// ([`Scene::casts_shadow`]: not blended ones, unless they opt in) with
    /// [`BuildOptions::default`].
    pub fn build(scene: &Scene) -> Result<Self, ShadowError> {
        Self::build_with(scene, &BuildOptions::default())
    }

    /// Builds over every triangle of every mesh in the scene with the given options.
    pub fn build_with(scene: &Scene, options: &BuildOptions) -> Result<Self, ShadowError> {
        let start = Instant::now();
        let mut alpha = AlphaTable::builder(scene, options.max_alpha_bytes);
        let g = gather(
            scene.meshes.iter().map(|m| {
                (
                    m.positions.as_slice(),
                    m.indices.as_slice(),
                    scene.casts_shadow(m),
                    Some(m),
                )
            }),
            Some(&mut alpha),
        );
        let mut bvh = Self::finish(g, options, start)?;
        bvh.alpha = alpha.finish();
        Ok(bvh)
    }

    /// Builds over a triangle soup (ids are the positions in `tris`).
    pub fn from_triangles(tris: &[[Vec3; 3]], options: &BuildOptions) -> Result<Self, ShadowError> {
        let start = Instant::now();
        let positions: Vec<Vec3> = tris.iter().flatten().copied().collect();
        let indices: Vec<u32> = (0..positions.len() as u32).collect();
        let g = gather(
            std::iter::once((positions.as_slice(), indices.as_slice(), true, None)),
            None,
        );
        Self::finish(g, options, start)
    }

    fn finish(g: Gathered, options: &BuildOptions, start: Instant) -> Result<Self, ShadowError> {
        let Gathered {
            tris,
            ids,
            alpha,
            mut stats,
        } = g;
        if tris.len() >= LEAF_BIT as usize {
            return Err(ShadowError::TooManyTriangles { count: tris.len() });
        }
        stats.triangles = tris.len();
        let mut out = ShadowBvh {
            nodes: Vec::new(),
            triangles: Vec::with_capacity(tris.len().max(1)),
            stats,
            alpha: AlphaTable::default(),
        };
        if tris.is_empty() {
            out.nodes.push(EMPTY_LEAF);
            out.triangles.push(BvhTriangle::zeroed());
            out.stats.nodes = 1;
            out.stats.leaves = 1;
            out.stats.max_depth = 1;
            out.stats.build_time = start.elapsed();
            return Ok(out);
        }
        let aabbs: Vec<obvhs::aabb::Aabb> = tris
            .iter()
            .map(|t| {
                obvhs::aabb::Aabb::from_points(&[to_obvhs(t[0]), to_obvhs(t[1]), to_obvhs(t[2])])
            })
            .collect();
        out.stats.gather_time = start.elapsed();
        let core = Instant::now();
        let (distance, depth_threshold, reinsertion) = options.ploc();
        let mut bvh = obvhs::ploc::PlocBuilder::with_capacity(aabbs.len()).build(
            distance,
            &aabbs,
            (0..aabbs.len() as u32).collect(),
            obvhs::ploc::SortPrecision::U64,
            depth_threshold,
        );
        if reinsertion > 0.0 {
            obvhs::bvh2::reinsertion::ReinsertionOptimizer::default().run(
                &mut bvh,
                reinsertion,
                None,
            );
        }
        out.stats.core_build_time = core.elapsed();
        if bvh.nodes.len() >= LEAF_BIT as usize {
            return Err(ShadowError::TooManyNodes {
                count: bvh.nodes.len(),
            });
        }
        let flatten = Instant::now();
        out.flatten(&bvh, &tris, &ids, &alpha, options);
        out.stats.flatten_time = flatten.elapsed();
        out.stats.nodes = out.nodes.len();
        out.stats.build_time = start.elapsed();
        Ok(out)
    }

    /// Pre-order flattening with an SAH leaf collapse (obvhs's own collapse pass costs
    /// more than this, so leaves come out of PLOC with one triangle each and are merged
    /// here).
    fn flatten(
        &mut self,
        bvh: &obvhs::bvh2::Bvh2,
        tris: &[[Vec3; 3]],
        ids: &[u32],
        alpha: &[u32],
        options: &BuildOptions,
    ) {
        let src = &bvh.nodes;
        let half_area = |i: u32| src.get(i as usize).map_or(0.0, |n| n.aabb().half_area());
        // Bottom up: triangles under each node, its best area-weighted cost, and whether
        // it becomes a leaf. Children must come before parents: PLOC's own node order
        // does that in reverse (it says so), reinsertion may not, then a pre-order does.
        let order: Vec<u32> = if bvh.children_are_ordered_after_parents {
            Vec::new()
        } else {
            let mut order = Vec::with_capacity(src.len());
            let mut stack = vec![0u32];
            while let Some(i) = stack.pop() {
                let Some(n) = src.get(i as usize) else {
                    continue;
                };
                order.push(i);
                if !n.is_leaf() {
                    stack.push(n.first_index + 1);
                    stack.push(n.first_index);
                }
            }
            order
        };
        let max_leaf = options.max_leaf_triangles.clamp(1, 255);
        let mut count = vec![0u32; src.len()];
        let mut cost = vec![0f32; src.len()];
        let mut leaf = vec![false; src.len()];
        let mut visit = |i: u32| {
            let n = &src[i as usize];
            let area = half_area(i);
            let k = i as usize;
            if n.is_leaf() {
                count[k] = n.prim_count;
                cost[k] = area * n.prim_count as f32;
                leaf[k] = true;
                return;
            }
            let (l, r) = (n.first_index as usize, n.first_index as usize + 1);
            let get = |v: &[u32], j: usize| v.get(j).copied().unwrap_or(0);
            let c = get(&count, l) + get(&count, r);
            let inner = area * options.traversal_cost
                + cost.get(l).copied().unwrap_or(0.0)
                + cost.get(r).copied().unwrap_or(0.0);
            let as_leaf = area * c as f32;
            count[k] = c;
            if c <= max_leaf && as_leaf <= inner {
                leaf[k] = true;
                cost[k] = as_leaf;
            } else {
                cost[k] = inner;
            }
        };
        if bvh.children_are_ordered_after_parents {
            (0..src.len() as u32).rev().for_each(&mut visit);
        } else {
            order.iter().rev().for_each(|&i| visit(i));
        }
        let root_area = half_area(0);
        self.stats.sah_cost = if root_area > 0.0 {
            cost.first().copied().unwrap_or(0.0) / root_area
        } else {
            0.0
        };

        // Emit. `Visit` writes a node (patching its parent's right-child link when it is a
        // right child); `Close` writes an inner node's skip link.
        enum Task {
            Visit {
                src: u32,
                depth: usize,
                right_of: Option<usize>,
            },
            Close(usize),
        }
        let mut tasks = vec![Task::Visit {
            src: 0,
            depth: 1,
            right_of: None,
        }];
        let mut under = Vec::new();
        let mut perm: Vec<u32> = Vec::with_capacity(tris.len());
        while let Some(task) = tasks.pop() {
            let (i, depth, right_of) = match task {
                Task::Close(at) => {
                    self.nodes[at].b = self.nodes.len() as u32;
                    continue;
                }
                Task::Visit {
                    src,
                    depth,
                    right_of,
                } => (src, depth, right_of),
            };
            let at = self.nodes.len();
            if let Some(parent) = right_of {
                self.nodes[parent].a = at as u32;
            }
            self.stats.max_depth = self.stats.max_depth.max(depth);
            let Some(n) = src.get(i as usize) else {
                // Not expected from obvhs; keep the tree well formed regardless.
                self.nodes.push(EMPTY_LEAF);
                continue;
            };
            let aabb = n.aabb();
            let mut node = BvhNode {
                min: aabb.min.to_array(),
                a: 0,
                max: aabb.max.to_array(),
                b: 0,
            };
            if !leaf[i as usize] {
                self.nodes.push(node);
                tasks.push(Task::Close(at));
                tasks.push(Task::Visit {
                    src: n.first_index + 1,
                    depth: depth + 1,
                    right_of: Some(at),
                });
                tasks.push(Task::Visit {
                    src: n.first_index,
                    depth: depth + 1,
                    right_of: None,
                });
                continue;
            }
            // A leaf: every triangle of the source subtree (indices now, the triangles
            // themselves in one tight gather loop below, which overlaps the cache misses).
            node.a = perm.len() as u32;
            under.clear();
            under.push(i);
            while let Some(j) = under.pop() {
                let Some(m) = src.get(j as usize) else {
                    continue;
                };
                if !m.is_leaf() {
                    under.push(m.first_index + 1);
                    under.push(m.first_index);
                    continue;
                }
                let first = m.first_index as usize;
                let prims = bvh
                    .primitive_indices
                    .get(first..first + m.prim_count as usize)
                    .unwrap_or(&[]);
                perm.extend(prims.iter().filter(|&&p| (p as usize) < tris.len()));
            }
            node.b = LEAF_BIT | (perm.len() as u32 - node.a);
            self.stats.leaves += 1;
            self.nodes.push(node);
        }
        self.triangles = perm
            .iter()
            .map(|&p| {
                let [p0, p1, p2] = tris[p as usize];
                BvhTriangle {
                    v0: p0.to_array(),
                    id: ids[p as usize],
                    e1: (p1 - p0).to_array(),
                    alpha: alpha.get(p as usize).copied().unwrap_or(0),
                    e2: (p2 - p0).to_array(),
                    _pad1: 0,
                }
            })
            .collect();
    }

    /// The bytes to upload into `bvh_nodes` and `bvh_triangles`.
    pub fn gpu_bytes(&self) -> (&[u8], &[u8]) {
        (
            bytemuck::cast_slice(&self.nodes),
            bytemuck::cast_slice(&self.triangles),
        )
    }

    /// The bytes to upload into `bvh_alpha`, or None when no triangle alpha-tests.
    pub fn alpha_bytes(&self) -> Option<&[u8]> {
        (self.alpha.records() > 0).then(|| bytemuck::cast_slice(&self.alpha.words[..]))
    }
}
