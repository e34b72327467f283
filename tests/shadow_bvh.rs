//! The shadow BVH (src/shadow), CPU only: the flattened BVH's any-hit traversal (the twin
//! of `bvh_occluded` in shaders/shadow/bvh.wgsl) against the f64 brute-force reference
//! on triangle soups, a box room, the atrium and the chairs scene; rays within 1e-4 of an
//! edge (or starting/ending on a surface, or grazing one) are excluded and counted.
//! Degenerate, non-finite and badly indexed triangles are skipped and counted; an empty
//! scene is never occluded; a malformed tree ends; the WGSL structs have the Rust
//! layouts.

use glam::{DVec3, Vec2, Vec3};
use lightgraph::scene::geometry::MeshBuilder;
use lightgraph::scene::lights::Pcg32;
use lightgraph::scene::{builtin, light_flags, Mesh, Scene};
use lightgraph::shadow::bvh::{BuildOptions, BuildQuality, ShadowBvh, LEAF_BIT};
use lightgraph::shadow::reference::{
    ambiguity, occluded_reference, scene_triangles_f64, Ambiguity, Triangle64,
};
use proptest::prelude::*;
use std::mem::{offset_of, size_of};
use std::path::Path;

const EPS: f64 = 1e-4;

/// One shadow ray.
#[derive(Clone, Copy, Debug)]
struct Ray {
    origin: Vec3,
    dir: Vec3,
    t_max: f32,
}

#[derive(Debug, Default)]
struct Tally {
    rays: usize,
    occluded: usize,
    near_edge: usize,
    near_endpoint: usize,
    grazing: usize,
    mismatches: Vec<(Ray, bool, bool)>,
}

impl Tally {
    fn excluded(&self) -> usize {
        self.near_edge + self.near_endpoint + self.grazing
    }
}

/// Compares the BVH with the reference on every ray.
fn compare(bvh: &ShadowBvh, tris: &[Triangle64], rays: &[Ray]) -> Tally {
    let mut tally = Tally::default();
    for r in rays {
        let (o, d, t) = (r.origin.as_dvec3(), r.dir.as_dvec3(), r.t_max as f64);
        tally.rays += 1;
        let got = bvh.occluded(r.origin, r.dir, r.t_max);
        let want = occluded_reference(tris, o, d, t);
        tally.occluded += usize::from(want);
        match ambiguity(tris, o, d, t, EPS) {
            Some(Ambiguity::NearEdge) => tally.near_edge += 1,
            Some(Ambiguity::NearEndpoint) => tally.near_endpoint += 1,
            Some(Ambiguity::Grazing) => tally.grazing += 1,
            None if got != want => tally.mismatches.push((*r, got, want)),
            None => {}
        }
    }
    tally
}

fn assert_agrees(name: &str, tally: &Tally, max_excluded: f64) {
    println!(
        "{name}: {} rays, {} occluded, excluded {} (near edge {}, endpoint {}, grazing {}), {} mismatches",
        tally.rays,
        tally.occluded,
        tally.excluded(),
        tally.near_edge,
        tally.near_endpoint,
        tally.grazing,
        tally.mismatches.len()
    );
    assert!(
        tally.mismatches.is_empty(),
        "{name}: {} of {} rays disagree with the reference, first: {:?}",
        tally.mismatches.len(),
        tally.rays,
        &tally.mismatches[..tally.mismatches.len().min(5)]
    );
    let frac = tally.excluded() as f64 / tally.rays as f64;
    assert!(
        frac <= max_excluded,
        "{name}: {:.3} % of rays excluded as ambiguous (allowed {:.3} %)",
        100.0 * frac,
        100.0 * max_excluded
    );
    // Both answers must occur, or the comparison says little.
    assert!(
        tally.occluded > tally.rays / 20 && tally.occluded < tally.rays - tally.rays / 20,
        "{name}: {} of {} rays occluded: not a useful mix",
        tally.occluded,
        tally.rays
    );
}

fn mesh(positions: Vec<Vec3>, indices: Vec<u32>) -> Mesh {
    Mesh {
        name: "test".into(),
        positions,
        indices,
        ..Default::default()
    }
}

fn scene_of(meshes: Vec<Mesh>) -> Scene {
    Scene {
        name: "test".into(),
        meshes,
        ..Default::default()
    }
}

/// `n` random triangles in the box `[-s, s]^3`, edge lengths up to `size`.
fn soup(rng: &mut Pcg32, n: usize, s: f32, size: f32) -> Vec<[Vec3; 3]> {
    (0..n)
        .map(|_| {
            let c = rng.vec3_in(Vec3::splat(-s), Vec3::splat(s));
            let k = rng.range(0.05, 1.0) * size;
            [
                c + rng.unit_vector() * k,
                c + rng.unit_vector() * k,
                c + rng.unit_vector() * k,
            ]
        })
        .collect()
}

fn soup_scene(tris: &[[Vec3; 3]]) -> Scene {
    let positions: Vec<Vec3> = tris.iter().flatten().copied().collect();
    let indices = (0..positions.len() as u32).collect();
    scene_of(vec![mesh(positions, indices)])
}

/// Random segments between two random points of the box (shadow-ray-like, t_max = 1),
/// and random directions with random t_max; a few axis-aligned ones.
fn random_rays(rng: &mut Pcg32, n: usize, lo: Vec3, hi: Vec3) -> Vec<Ray> {
    (0..n)
        .map(|i| {
            let origin = rng.vec3_in(lo, hi);
            match i % 4 {
                0 | 1 => {
                    let to = rng.vec3_in(lo, hi);
                    Ray {
                        origin,
                        dir: to - origin,
                        t_max: 1.0,
                    }
                }
                2 => Ray {
                    origin,
                    dir: rng.unit_vector() * rng.range(0.5, 2.0),
                    t_max: rng.range(0.1, 1.0) * (hi - lo).length(),
                },
                _ => {
                    // Axis-aligned and axis-plane directions: zero components.
                    let mut d = rng.unit_vector();
                    match rng.next_u32() % 3 {
                        0 => d.x = 0.0,
                        1 => d = Vec3::new(0.0, d.y, 0.0),
                        _ => d.z = 0.0,
                    }
                    let d = if d.length() < 1e-3 { Vec3::Y } else { d };
                    Ray {
                        origin,
                        dir: d,
                        t_max: rng.range(0.1, 1.0) * (hi - lo).length(),
                    }
                }
            }
        })
        .collect()
}

fn check_scene(name: &str, scene: &Scene, rays: &[Ray], max_excluded: f64) -> ShadowBvh {
    let bvh = ShadowBvh::build(scene).unwrap();
    let tris = scene_triangles_f64(scene);
    let tally = compare(&bvh, &tris, rays);
    println!(
        "{name}: {} triangles, {} nodes, depth {}, built in {:?}",
        bvh.stats.triangles, bvh.stats.nodes, bvh.stats.max_depth, bvh.stats.build_time
    );
    assert_agrees(name, &tally, max_excluded);
    bvh
}

#[test]
fn bvh_matches_reference_on_random_soups() {
    for (seed, n, size) in [
        (1u64, 50, 2.0f32),
        (2, 400, 1.5),
        (3, 2000, 0.8),
        (4, 5000, 0.3),
    ] {
        let mut rng = Pcg32::new(seed);
        let tris = soup(&mut rng, n, 5.0, size);
        let scene = soup_scene(&tris);
        let rays = random_rays(&mut rng, 3000, Vec3::splat(-6.0), Vec3::splat(6.0));
        let bvh = check_scene(&format!("soup {n}"), &scene, &rays, 0.01);
        assert_eq!(bvh.stats.triangles, n);
        // Every quality preset and leaf size must give the same answers.
        for quality in [
            BuildQuality::Fastest,
            BuildQuality::Fast,
            BuildQuality::Medium,
        ] {
            for leaf in [1, 8] {
                let other = ShadowBvh::build_with(
                    &scene,
                    &BuildOptions {
                        quality,
                        max_leaf_triangles: leaf,
                        ..Default::default()
                    },
                )
                .unwrap();
                let tally = compare(&other, &scene_triangles_f64(&scene), &rays[..500]);
                assert!(tally.mismatches.is_empty(), "{quality:?}/{leaf}: {tally:?}");
            }
        }
    }
}

/// A closed 10 × 4 × 8 room (walls facing in) with boxes and pillars in it.
fn box_room() -> Scene {
    let mut b = MeshBuilder::new("room", 0);
    let (lo, hi) = (Vec3::new(-5.0, 0.0, -4.0), Vec3::new(5.0, 4.0, 4.0));
    let s = hi - lo;
    b.quad(lo, Vec3::X * s.x, Vec3::Z * s.z, Vec2::ONE) // floor
        .quad(lo + Vec3::Y * s.y, Vec3::Z * s.z, Vec3::X * s.x, Vec2::ONE) // ceiling
        .quad(lo, Vec3::Y * s.y, Vec3::X * s.x, Vec2::ONE)
        .quad(lo + Vec3::Z * s.z, Vec3::X * s.x, Vec3::Y * s.y, Vec2::ONE)
        .quad(lo, Vec3::Z * s.z, Vec3::Y * s.y, Vec2::ONE)
        .quad(lo + Vec3::X * s.x, Vec3::Y * s.y, Vec3::Z * s.z, Vec2::ONE);
    let mut rng = Pcg32::new(77);
    for _ in 0..12 {
        let c = rng.vec3_in(Vec3::new(-4.0, 0.0, -3.0), Vec3::new(4.0, 0.0, 3.0));
        let h = rng.vec3_in(Vec3::new(0.2, 0.3, 0.2), Vec3::new(0.8, 2.5, 0.8));
        b.cuboid(c - Vec3::new(h.x, 0.0, h.z), c + Vec3::new(h.x, h.y, h.z));
    }
    for x in [-2.5f32, 0.0, 2.5] {
        b.cylinder(Vec3::new(x, 0.0, 2.0), 0.3, 4.0, 24, 4);
    }
    scene_of(vec![b.build()])
}

#[test]
fn bvh_matches_reference_in_box_room() {
    let scene = box_room();
    let mut rng = Pcg32::new(5);
    let rays = random_rays(
        &mut rng,
        6000,
        Vec3::new(-4.9, 0.1, -3.9),
        Vec3::new(4.9, 3.9, 3.9),
    );
    check_scene("box room", &scene, &rays, 0.01);
}

/// Shadow rays from random points in the scene's bounds to its lights.
fn light_rays(scene: &Scene, rng: &mut Pcg32, n: usize) -> Vec<Ray> {
    let (lo, hi) = scene.bounds().unwrap();
    (0..n)
        .map(|_| {
            let p = rng.vec3_in(lo, hi);
            let l = scene.lights[rng.next_u32() as usize % scene.lights.len()].position;
            Ray {
                origin: p,
                dir: l - p,
                t_max: 1.0,
            }
        })
        .collect()
}

#[test]
fn bvh_matches_reference_in_atrium() {
    let scene = builtin::atrium();
    let mut rng = Pcg32::new(6);
    let mut rays = light_rays(&scene, &mut rng, 1500);
    let (lo, hi) = scene.bounds().unwrap();
    rays.extend(random_rays(&mut rng, 1500, lo, hi));
    let bvh = check_scene("atrium", &scene, &rays, 0.02);
    assert_eq!(bvh.stats.triangles, scene.triangle_count());
}

#[test]
fn chairs_scene_is_big_shadowed_and_named() {
    let scene = builtin::by_name("chairs").expect("chairs is a built-in");
    assert!(builtin::NAMES.contains(&"chairs"));
    let tris = scene.triangle_count();
    assert!(tris >= 250_000, "{tris} triangles");
    assert_eq!(scene.lights.len(), 512);
    assert!(scene
        .lights
        .iter()
        .all(|l| l.flags & light_flags::CASTS_SHADOW != 0));
    assert!(scene.features().has_shadow_casters);
    assert_eq!(scene.output_size, Some((1280, 720)));
    let (lo, hi) = scene.bounds().unwrap();
    for l in &scene.lights {
        assert!(l.position.cmpgt(lo).all() && l.position.cmplt(hi).all());
    }
    let c = scene.camera;
    assert!(
        c.eye.cmpgt(lo).all() && c.eye.cmplt(hi).all(),
        "camera inside the room"
    );

    // The scene file names it the way harada.ron names harada.
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/chairs.ron");
    let loaded = lightgraph::scene::load(&file).unwrap().scene;
    assert_eq!(loaded.triangle_count(), tris);

    let bvh = ShadowBvh::build(&scene).unwrap();
    println!(
        "chairs: {} triangles, {} nodes, {} leaves, depth {}, built in {:?} (obvhs core {:?})",
        bvh.stats.triangles,
        bvh.stats.nodes,
        bvh.stats.leaves,
        bvh.stats.max_depth,
        bvh.stats.build_time,
        bvh.stats.core_build_time
    );
    assert_eq!(bvh.stats.triangles, tris);
    assert_eq!(
        bvh.stats.skipped_degenerate + bvh.stats.skipped_non_finite,
        0
    );
    let mut rng = Pcg32::new(7);
    let rays = light_rays(&scene, &mut rng, 300);
    let tally = compare(&bvh, &scene_triangles_f64(&scene), &rays);
    assert_agrees("chairs", &tally, 0.02);
}

#[test]
fn degenerate_and_non_finite_triangles_are_skipped_and_counted() {
    let nan = f32::NAN;
    let inf = f32::INFINITY;
    let good = [
        [
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ],
        [
            Vec3::new(-1.0, -1.0, 2.0),
            Vec3::new(1.0, -1.0, 2.0),
            Vec3::new(0.0, 1.0, 2.0),
        ],
    ];
    let degenerate = [
        // Repeated vertex, collinear, all three equal.
        [Vec3::ZERO, Vec3::ZERO, Vec3::X],
        [Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
        [Vec3::ONE; 3],
    ];
    let non_finite = [
        [Vec3::new(nan, 0.0, 0.0), Vec3::X, Vec3::Y],
        [Vec3::ZERO, Vec3::new(0.0, inf, 0.0), Vec3::Y],
        [Vec3::ZERO, Vec3::X, Vec3::new(0.0, 0.0, -inf)],
        [Vec3::splat(nan); 3],
    ];
    let mut all: Vec<[Vec3; 3]> = Vec::new();
    all.extend(good);
    all.extend(degenerate);
    all.extend(non_finite);
    let mut positions: Vec<Vec3> = all.iter().flatten().copied().collect();
    let mut indices: Vec<u32> = (0..positions.len() as u32).collect();
    // One triangle naming a vertex that does not exist, and two stray indices.
    positions.push(Vec3::Z);
    indices.extend([0, 1, 999, 0, 1]);
    let scene = scene_of(vec![mesh(positions, indices)]);

    let bvh = ShadowBvh::build(&scene).unwrap();
    let s = bvh.stats;
    assert_eq!(s.triangles, 2);
    assert_eq!(s.input_triangles, 2 + 3 + 4 + 1);
    assert_eq!(s.skipped_degenerate, 3);
    assert_eq!(s.skipped_non_finite, 4);
    assert_eq!(s.skipped_bad_index, 2, "the bad index and the stray pair");
    let ids: Vec<u32> = bvh.triangles.iter().map(|t| t.id).collect();
    assert!(ids.contains(&0) && ids.contains(&1), "ids {ids:?}");

    // Also from a soup, and with a triangle soup of only bad triangles.
    let soup_bvh = ShadowBvh::from_triangles(&all, &BuildOptions::default()).unwrap();
    assert_eq!(
        (
            soup_bvh.stats.triangles,
            soup_bvh.stats.skipped_degenerate,
            soup_bvh.stats.skipped_non_finite
        ),
        (2, 3, 4)
    );
    let only_bad: Vec<[Vec3; 3]> = degenerate.iter().chain(&non_finite).copied().collect();
    let none = ShadowBvh::from_triangles(&only_bad, &BuildOptions::default()).unwrap();
    assert_eq!(none.stats.triangles, 0);
    assert!(!none.occluded(Vec3::new(0.5, 0.0, -1.0), Vec3::Z, 10.0));

    // The remaining geometry behaves: through both good triangles, between them, beside.
    assert!(bvh.occluded(Vec3::new(0.0, 0.0, -1.0), Vec3::Z, 10.0));
    assert!(bvh.occluded(Vec3::new(0.0, 0.0, 1.0), Vec3::Z, 10.0));
    assert!(!bvh.occluded(Vec3::new(0.0, 0.0, 0.5), Vec3::Z, 1.0));
    assert!(!bvh.occluded(Vec3::new(5.0, 0.0, -1.0), Vec3::Z, 10.0));
    // Rays at the degenerate triangles' place hit nothing there.
    assert!(!bvh.occluded(Vec3::new(0.5, 0.0, -1.0), Vec3::Z, 0.99));
    let tris = scene_triangles_f64(&scene);
    assert_eq!(
        tris.len(),
        2 + 3,
        "the reference keeps degenerate triangles"
    );
    let mut rng = Pcg32::new(8);
    let rays = random_rays(&mut rng, 2000, Vec3::splat(-2.0), Vec3::splat(3.0));
    let tally = compare(&bvh, &tris, &rays);
    assert!(tally.mismatches.is_empty(), "{:?}", tally.mismatches);
    // Non-finite rays are not occluded and do not panic.
    assert!(!bvh.occluded(Vec3::splat(nan), Vec3::Z, 10.0));
    assert!(!bvh.occluded(Vec3::ZERO, Vec3::new(inf, 0.0, 0.0), 10.0));
    assert!(!bvh.occluded(Vec3::ZERO, Vec3::Z, nan));
}

#[test]
fn empty_scene_is_never_occluded() {
    let scenes = [
        Scene::default(),
        scene_of(vec![mesh(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![])]),
        scene_of(vec![Mesh::default(), Mesh::default()]),
    ];
    let mut rng = Pcg32::new(9);
    let rays = random_rays(&mut rng, 500, Vec3::splat(-5.0), Vec3::splat(5.0));
    for scene in &scenes {
        let bvh = ShadowBvh::build(scene).unwrap();
        assert_eq!(bvh.stats.triangles, 0);
        assert_eq!(
            bvh.nodes.len(),
            1,
            "one empty leaf, so the buffer is not empty"
        );
        assert_eq!(bvh.nodes[0].b, LEAF_BIT);
        assert_eq!(bvh.triangles.len(), 1, "one padding triangle");
        let (nodes, tris) = bvh.gpu_bytes();
        assert_eq!((nodes.len(), tris.len()), (32, 48));
        for r in &rays {
            assert!(!bvh.occluded(r.origin, r.dir, r.t_max));
        }
        assert!(!bvh.occluded(Vec3::ZERO, Vec3::X, f32::MAX));
    }
    // A default ShadowBvh (no nodes at all) is not occluded either.
    assert!(!ShadowBvh::default().occluded(Vec3::ZERO, Vec3::X, 1.0));
}

/// A malformed tree (an inner node whose skip link points back at itself) must not hang
/// the traversal: every step moves forward, so a miss still ends.
#[test]
fn malformed_tree_terminates() {
    use lightgraph::shadow::bvh::{BvhNode, BvhTriangle};
    let good = ShadowBvh::from_triangles(
        &[[
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ]],
        &BuildOptions::default(),
    )
    .unwrap();
    let tri: BvhTriangle = good.triangles[0];
    let bounds = |b: u32, a: u32| BvhNode {
        min: [-1.0, -1.0, -0.5],
        a,
        max: [1.0, 1.0, 0.5],
        b,
    };
    let bad = ShadowBvh {
        nodes: vec![bounds(2, 0), bounds(LEAF_BIT | 1, 0)],
        triangles: vec![tri],
        stats: Default::default(),
        alpha: Default::default(),
    };
    assert!(bad.occluded(Vec3::new(0.0, 0.0, -1.0), Vec3::Z, 2.0));
    // A miss that followed the root's skip link as written would cycle for ever.
    let bad = ShadowBvh {
        nodes: vec![bounds(0, 1), bounds(LEAF_BIT | 1, 0)],
        ..bad
    };
    assert!(!bad.occluded(Vec3::new(3.0, 3.0, -1.0), Vec3::Z, 2.0));
    assert!(!bad.occluded(Vec3::new(0.9, 0.9, -1.0), Vec3::Z, 2.0));
}

/// Structure: pre-order, left child next, skip links, leaves cover every triangle once.
#[test]
fn flattened_layout_is_consistent() {
    let mut rng = Pcg32::new(11);
    let tris = soup(&mut rng, 1000, 5.0, 1.0);
    for leaf in [1, 4, 8] {
        let bvh = ShadowBvh::from_triangles(
            &tris,
            &BuildOptions {
                max_leaf_triangles: leaf,
                ..Default::default()
            },
        )
        .unwrap();
        let n = bvh.nodes.len() as u32;
        let mut covered = vec![0u32; bvh.triangles.len()];
        // Walk: every node's subtree is [i, skip), children inside it.
        fn walk(bvh: &ShadowBvh, i: u32, covered: &mut [u32], leaf: u32) -> u32 {
            let node = bvh.nodes[i as usize];
            if node.is_leaf() {
                assert!(node.count() >= 1 && node.count() <= leaf);
                for k in node.a..node.a + node.count() {
                    covered[k as usize] += 1;
                }
                return i + 1;
            }
            let end_left = walk(bvh, i + 1, covered, leaf);
            assert_eq!(end_left, node.a, "right child follows the left subtree");
            let end = walk(bvh, node.a, covered, leaf);
            assert_eq!(end, node.b, "skip link");
            // Children lie inside the parent's box.
            for c in [i + 1, node.a] {
                let ch = bvh.nodes[c as usize];
                for k in 0..3 {
                    assert!(ch.min[k] >= node.min[k] && ch.max[k] <= node.max[k]);
                }
            }
            end
        }
        assert_eq!(walk(&bvh, 0, &mut covered, leaf), n);
        assert!(covered.iter().all(|&c| c == 1));
        let mut ids: Vec<u32> = bvh.triangles.iter().map(|t| t.id).collect();
        ids.sort_unstable();
        assert_eq!(ids, (0..1000).collect::<Vec<u32>>());
        assert_eq!(bvh.stats.nodes, bvh.nodes.len());
    }
}

#[test]
fn wgsl_structs_match_rust_layout() {
    use lightgraph::shader::{struct_layout, ShaderLibrary};
    use lightgraph::shadow::bvh::{BvhNode, BvhTriangle};
    use std::collections::BTreeMap;
    let lib = ShaderLibrary::new(Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders"));
    let defines = BTreeMap::from([("BVH_STANDALONE".to_string(), "1".to_string())]);
    let composed = lib
        .compose("shadow/bvh.wgsl", &defines, &BTreeMap::new())
        .unwrap();
    let module = composed.validate().unwrap_or_else(|e| panic!("{e}"));
    let check = |name: &str, size: usize, rust: &[(&str, usize)]| {
        let (fields, wsize) = struct_layout(&module, name).unwrap();
        assert_eq!(wsize as usize, size, "size of {name}");
        let w: Vec<(&str, usize)> = fields
            .iter()
            .map(|f| (f.0.as_str(), f.1 as usize))
            .collect();
        assert_eq!(w, rust, "{name} members");
    };
    check(
        "BvhNode",
        size_of::<BvhNode>(),
        &[
            ("min", offset_of!(BvhNode, min)),
            ("a", offset_of!(BvhNode, a)),
            ("max", offset_of!(BvhNode, max)),
            ("b", offset_of!(BvhNode, b)),
        ],
    );
    check(
        "BvhTriangle",
        size_of::<BvhTriangle>(),
        &[
            ("v0", offset_of!(BvhTriangle, v0)),
            ("id", offset_of!(BvhTriangle, id)),
            ("e1", offset_of!(BvhTriangle, e1)),
            ("alpha", offset_of!(BvhTriangle, alpha)),
            ("e2", offset_of!(BvhTriangle, e2)),
            ("_pad1", offset_of!(BvhTriangle, _pad1)),
        ],
    );
    assert_eq!((size_of::<BvhNode>(), size_of::<BvhTriangle>()), (32, 48));
    // The constants the twins share.
    let text = &composed.text;
    assert!(text.contains(&format!("const BVH_LEAF_BIT: u32 = 0x{LEAF_BIT:08x}u;")));
    assert!(module
        .functions
        .iter()
        .any(|(_, f)| f.name.as_deref() == Some("bvh_occluded") && f.arguments.len() == 3));
    // Without BVH_STANDALONE the includer declares the buffers: the file alone is incomplete.
    let bare = lib
        .compose("shadow/bvh.wgsl", &BTreeMap::new(), &BTreeMap::new())
        .unwrap();
    assert!(bare.validate().is_err());
}

fn arb_vec3(r: f32) -> impl Strategy<Value = Vec3> {
    (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn arb_tri() -> impl Strategy<Value = [Vec3; 3]> {
    (arb_vec3(4.0), arb_vec3(1.5), arb_vec3(1.5)).prop_map(|(c, a, b)| [c, c + a, c + b])
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Any soup, any rays: the BVH answers as the reference does, unless the ray is
    /// ambiguous.
    #[test]
    fn prop_bvh_equals_reference(
        tris in prop::collection::vec(arb_tri(), 0..80),
        rays in prop::collection::vec((arb_vec3(6.0), arb_vec3(6.0), 0.01f32..2.0), 1..40),
        leaf in 1u32..9,
    ) {
        let bvh = ShadowBvh::from_triangles(&tris, &BuildOptions { max_leaf_triangles: leaf, ..Default::default() }).unwrap();
        let scene = soup_scene(&tris);
        let ref_tris = scene_triangles_f64(&scene);
        for (o, to, t_max) in rays {
            let dir = to - o;
            let got = bvh.occluded(o, dir, t_max);
            let (od, dd, td) = (o.as_dvec3(), dir.as_dvec3(), t_max as f64);
            if ambiguity(&ref_tris, od, dd, td, EPS).is_none() {
                prop_assert_eq!(got, occluded_reference(&ref_tris, od, dd, td), "ray {:?} {:?} {}", o, dir, t_max);
            }
        }
    }
}

/// The ambiguity predicate itself: a ray through an edge is flagged, one through the
/// middle or well clear of the triangle is not, and one ending on the surface is.
#[test]
fn ambiguity_predicate() {
    let tri = [[
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
    ]];
    let down = DVec3::new(0.0, 0.0, -2.0);
    let at = |x: f64, y: f64| DVec3::new(x, y, 1.0);
    assert_eq!(
        ambiguity(&tri, at(0.5, 0.0), down, 1.0, EPS),
        Some(Ambiguity::NearEdge)
    );
    assert_eq!(
        ambiguity(&tri, at(0.5, 0.5 + 1e-6), down, 1.0, EPS),
        Some(Ambiguity::NearEdge)
    );
    assert_eq!(ambiguity(&tri, at(0.25, 0.25), down, 1.0, EPS), None);
    assert_eq!(ambiguity(&tri, at(2.0, 2.0), down, 1.0, EPS), None);
    assert_eq!(
        ambiguity(&tri, at(0.25, 0.25), down, 0.5, EPS),
        Some(Ambiguity::NearEndpoint)
    );
    // In the plane across the triangle: flagged. Parallel to it, well above: not.
    let flat = DVec3::new(1.0, 1.0, 1e-7);
    assert!(ambiguity(&tri, DVec3::new(-1.0, -0.8, 0.0), flat, 3.0, EPS).is_some());
    assert_eq!(
        ambiguity(&tri, DVec3::new(-1.0, 0.2, 0.5), DVec3::X, 3.0, EPS),
        None
    );
    assert_eq!(
        ambiguity(
            &tri,
            DVec3::new(0.2, 0.2, 1e-9),
            DVec3::new(0.1, 0.1, 0.0),
            1.0,
            EPS
        ),
        Some(Ambiguity::NearEndpoint)
    );
}
