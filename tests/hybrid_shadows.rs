//! Hybrid shadows in the compute-first frame (graphs/visibility_hybrid_shadows.ron): the
//! shadow atlas for the casters its policy picks, ray-cast shadows for the rest and for
//! any the atlas drops. On the real adapter (lavapipe on CI):
//! - the lights left to rays get exactly the ray-cast frame's jobs and mask bits
//!   (graphs/visibility_raycast_shadows.ron, caster numbers kept), and no mapped light
//!   gets a job;
//! - the image is the ray-cast frame's for the ray lights plus the atlas frame's
//!   (graphs/visibility_shadow_atlas.ron) for the mapped lights, each rendered with the
//!   other lights dark, within the rounding of regrouping the light sums;
//! - lights an atlas too small for all drops are ray-cast, and every ray's bit equals the
//!   CPU twin's ray from the surface rebuilt in f64 (rays within 1e-4 of an edge counted);
//! - the policy picks the lights it names (the nearest, here), and follows lights that
//!   move (a frame after `update_lights` is the frame prepared for the moved lights);
//! - Forward+ and tiled deferred take the hybrid alike, against their own ray-cast and
//!   atlas frames.

mod common;

use common::shadow_jobs::{compare_with_cpu_twin, pixel_jobs, Surfaces};
use common::{graph_text, lambert, max_rel_diff, prepare_text, renderer, shadow_room, Rng};
use glam::Vec3;
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{AtlasReport, FrameResult, PreparedFrame, Renderer, SceneGpu};
use lightgraph::scene::{light_flags, Camera, Light, LightShape, Scene};
use lightgraph::shader::ShaderLibrary;
use lightgraph::shadow::atlas::DropReason;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

const W: u32 = 96;
const H: u32 = 64;
/// Shaders' SHADOW_NORMAL_OFFSET default (ShadowRayCast's normal_offset).
const OFFSET: f32 = 1e-4;

fn run(r: &mut Renderer, text: &str, scene: &Scene) -> (PreparedFrame, FrameResult) {
    let prepared = prepare_text(r, text, scene, W, H, false).expect("prepare");
    let result = prepared.render(r).expect("render");
    assert_eq!(result.image.len(), (W * H) as usize);
    (prepared, result)
}

/// The shadow room (floor, boxes, a slab, a column) under `n` shadow-casting lights at
/// spread distances from the camera (every third a spot), and two lights that cast none.
fn scene(n: usize, seed: u64) -> Scene {
    let mut rng = Rng(seed);
    let meshes = shadow_room(&mut rng);
    let mut lights: Vec<Light> = (0..n)
        .map(|i| {
            let p = rng.vec3(Vec3::new(-6.0, 0.8, -10.0), Vec3::new(6.0, 4.5, 2.0));
            let mut l = Light::point(p, rng.range(5.0, 12.0), Vec3::ONE, rng.range(2.0, 6.0));
            l.flags |= light_flags::CASTS_SHADOW;
            if i % 3 == 2 {
                let direction =
                    (rng.vec3(Vec3::splat(-0.5), Vec3::splat(0.5)) - Vec3::Y).normalize();
                l.shape = LightShape::Spot {
                    direction,
                    inner_angle: 0.3,
                    outer_angle: rng.range(0.5, 0.9),
                };
            }
            l
        })
        .collect();
    for k in 0..2 {
        let p = Vec3::new(-3.0 + 6.0 * k as f32, 3.0, -4.0);
        lights.push(Light::point(p, 8.0, Vec3::new(0.4, 0.5, 0.6), 1.0));
    }
    Scene {
        name: "hybrid shadow test".into(),
        meshes,
        materials: vec![
            lambert("floor", Vec3::splat(0.7)),
            lambert("boxes", Vec3::new(0.8, 0.5, 0.3)),
        ],
        lights,
        camera: Camera {
            eye: Vec3::new(0.0, 6.0, 7.0),
            target: Vec3::new(0.0, 0.0, -4.0),
            ..Default::default()
        },
        ..Default::default()
    }
}

/// The scene with the lights `dark` giving no light; with `casting: false` they cast no
/// shadow either (so an atlas gives them no tile).
fn darkened(scene: &Scene, dark: &BTreeSet<u32>, casting: bool) -> Scene {
    let mut s = scene.clone();
    for &i in dark {
        let l = &mut s.lights[i as usize];
        l.intensity = 0.0;
        if !casting {
            l.flags &= !light_flags::CASTS_SHADOW;
        }
    }
    s
}

/// The compute-first frame's ray-cast and atlas graphs, which its hybrid combines.
const VISIBILITY_PARTS: Parts = Parts {
    rays: "visibility_raycast_shadows.ron",
    atlas: "visibility_shadow_atlas.ron",
};

/// The graphs of one frame kind that shadow one way each: all rays, all atlas.
struct Parts {
    rays: &'static str,
    atlas: &'static str,
}

/// Runs the hybrid graph `text` on `scene` and checks it against the compute-first
/// frame's ray-cast and atlas frames (see the module doc); returns its atlas report and
/// its jobs.
fn check_hybrid(
    r: &mut Renderer,
    text: &str,
    scene: &Scene,
) -> (AtlasReport, Vec<BTreeMap<u32, bool>>) {
    check_hybrid_against(r, text, scene, &VISIBILITY_PARTS)
}

/// `check_hybrid` against the ray-cast and atlas frames of `parts` (its frame kind's);
/// the rays against the CPU twin where the frame has a visibility buffer to rebuild
/// surfaces from.
fn check_hybrid_against(
    r: &mut Renderer,
    text: &str,
    scene: &Scene,
    parts: &Parts,
) -> (AtlasReport, Vec<BTreeMap<u32, bool>>) {
    let (prepared, result) = run(r, text, scene);
    let atlas = result.atlases[0].clone();
    assert!(atlas.rays_for_the_rest, "{atlas:?}");
    let mapped: BTreeSet<u32> = atlas.shadowed.iter().map(|l| l.light).collect();
    let casters: BTreeSet<u32> = (0..scene.lights.len() as u32)
        .filter(|&i| scene.lights[i as usize].flags & light_flags::CASTS_SHADOW != 0)
        .collect();
    let rays: BTreeSet<u32> = casters.difference(&mapped).copied().collect();
    assert!(!mapped.is_empty() && rays.len() >= 3, "{atlas:?}");
    let hybrid = pixel_jobs(r, &prepared, W * H);
    let hybrid_mask: Vec<u32> =
        bytemuck::cast_slice(&prepared.read_buffer(r, "shadow_mask").unwrap()).to_vec();

    // Rays: the ray-cast frame's jobs and bits, less the mapped lights'.
    let (ray_prepared, _) = run(r, &graph_text(parts.rays), scene);
    let all_rays = pixel_jobs(r, &ray_prepared, W * H);
    let ray_mask: Vec<u32> =
        bytemuck::cast_slice(&ray_prepared.read_buffer(r, "shadow_mask").unwrap()).to_vec();
    let (mut jobs, mut hidden) = (0, 0);
    for (pixel, (h, all)) in hybrid.iter().zip(&all_rays).enumerate() {
        let expected: BTreeMap<u32, bool> = all
            .iter()
            .filter(|(l, _)| !mapped.contains(l))
            .map(|(&l, &b)| (l, b))
            .collect();
        assert_eq!(
            h, &expected,
            "pixel {pixel}: hybrid jobs against the ray-cast frame's"
        );
        jobs += h.len();
        hidden += h.values().filter(|&&b| b).count();
    }
    // Caster numbers are kept: the hybrid's bits are the ray-cast frame's, less those of
    // mapped lights (never set in the hybrid's mask).
    assert_eq!(hybrid_mask.len(), ray_mask.len());
    for (i, (h, a)) in hybrid_mask.iter().zip(&ray_mask).enumerate() {
        assert_eq!(
            h & !a,
            0,
            "mask word {i}: a bit the ray-cast frame does not set"
        );
    }
    assert!(jobs > 1_000 && hidden > 100, "{jobs} jobs, {hidden} hidden");

    // Every ray against the CPU twin from the surface rebuilt in f64 (the other frame
    // kinds' ray-cast frames are checked against it in tests/raycast_shadows.rs, and
    // their jobs and bits are those frames' here).
    eprintln!(
        "{}: {} mapped, {} to rays; {jobs} jobs, {hidden} hidden",
        parts.rays,
        mapped.len(),
        rays.len()
    );
    if parts.rays == VISIBILITY_PARTS.rays {
        let ids = prepared.read_texture_bits(r, "visibility").unwrap();
        let surfaces = Surfaces::new(r, scene, W, H);
        let (agree, grazing, failures) =
            compare_with_cpu_twin(scene, &surfaces, &ids, &hybrid, OFFSET);
        eprintln!("CPU twin: {agree} agree, {grazing} graze an edge");
        assert!(failures.is_empty(), "{failures:?}");
        assert!(grazing * 100 < agree, "{grazing} grazing of {agree}");
    }

    // The image: ray-cast frame with the mapped lights dark, plus the atlas frame with
    // the others dark and casting none (so its allocation is the hybrid's: the same
    // lights, ranked alike, in the same tiles), less what neither lights.
    let all: BTreeSet<u32> = (0..scene.lights.len() as u32).collect();
    let ray_part = run(r, &graph_text(parts.rays), &darkened(scene, &mapped, true)).1;
    let others: BTreeSet<u32> = all.difference(&mapped).copied().collect();
    let atlas_run = run(
        r,
        &graph_text(parts.atlas),
        &darkened(scene, &others, false),
    )
    .1;
    assert_eq!(
        atlas_run.atlases[0].shadowed, atlas.shadowed,
        "the atlas frame allocates alike"
    );
    let dark = run(r, &graph_text(parts.rays), &darkened(scene, &all, true)).1;
    let sum: Vec<[f32; 4]> = ray_part
        .image
        .iter()
        .zip(&atlas_run.image)
        .zip(&dark.image)
        .map(|((a, b), d)| [0, 1, 2, 3].map(|c| a[c] + b[c] - d[c]))
        .collect();
    // The hybrid sums each pixel's lights in one loop, the parts in two: the same terms
    // regrouped (and the dark frame subtracted), which moves a sum of under 16 fp32 terms
    // by at most 16 ulps (2^-24 relative each, 1e-6) of the peak; 1.3e-7 seen.
    let (worst, at) = max_rel_diff(&result.image, &sum);
    eprintln!(
        "{} dropped; image against rays + atlas: {worst:e} of the peak at worst",
        atlas.dropped.len()
    );
    assert!(
        worst < 1e-6,
        "hybrid against rays + atlas: {worst} at pixel {at}"
    );
    // The mapped lights' maps shadow something (the rays do: `hidden` above).
    let mut open = darkened(scene, &others, false);
    for l in &mut open.lights {
        l.flags &= !light_flags::CASTS_SHADOW;
    }
    let open_part = run(r, &graph_text(parts.atlas), &open).1;
    assert_ne!(
        open_part.image, atlas_run.image,
        "the atlas shadows nothing"
    );
    (atlas, hybrid)
}

#[test]
fn ray_lights_equal_the_ray_cast_frame_and_mapped_lights_the_atlas_frame() {
    let mut r = renderer();
    let scene = scene(14, 7);
    let text = graph_text("visibility_hybrid_shadows.ron")
        .replace("policy: Nearest(16)", "policy: Nearest(4)");
    assert!(text.contains("policy: Nearest(4)"));
    let (atlas, _) = check_hybrid(&mut r, &text, &scene);
    // The policy picks the four nearest casters in view.
    let mut by_distance: Vec<(f32, u32)> = atlas
        .shadowed
        .iter()
        .map(|l| l.light)
        .chain(atlas.left_by_policy.iter().copied())
        .map(|l| {
            (
                scene.lights[l as usize].position.distance(scene.camera.eye),
                l,
            )
        })
        .collect();
    by_distance.sort_by(|a, b| a.0.total_cmp(&b.0));
    let nearest: BTreeSet<u32> = by_distance[..4].iter().map(|d| d.1).collect();
    let mapped: BTreeSet<u32> = atlas.shadowed.iter().map(|l| l.light).collect();
    assert_eq!(mapped, nearest);
    assert!(atlas.dropped.is_empty());

    // Every light loop and the classified dispatch pick the atlas or the mask alike.
    let (_, base) = run(&mut r, &text, &scene);
    for kind in [
        "lights: Culled, light_loop: Forward",
        "lights: Culled, light_loop: Staged",
        "lights: Culled, light_loop: GroupList",
        "lights: Culled, materials: Classified",
    ] {
        let other_text = text.replace(
            "VisibilityShading(lights: Culled)",
            &format!("VisibilityShading({kind})"),
        );
        assert_ne!(other_text, text);
        let (_, other) = run(&mut r, &other_text, &scene);
        let bits = common::pixels_differing_in_bits(&base.image, &other.image);
        assert_eq!(bits, 0, "{kind}: {bits} pixels differ from RangeFirst");
    }
}

#[test]
fn lights_the_atlas_drops_are_ray_cast() {
    let mut r = renderer();
    let mut scene = scene(9, 11);
    // Point lights only: 256² holds 16 tiles of 64², two lights' six faces, not three.
    for l in &mut scene.lights {
        l.shape = LightShape::Point;
    }
    let text = graph_text("visibility_hybrid_shadows.ron")
        .replace("Fixed(4096, 4096)", "Fixed(256, 256)")
        .replace(
            "min_tile: 16, max_tile: 1024, importance: 1.0, policy: Nearest(16)",
            "min_tile: 64, max_tile: 256, importance: 1.0, policy: All",
        );
    assert!(text.contains("policy: All") && text.contains("Fixed(256, 256)"));
    let (atlas, jobs) = check_hybrid(&mut r, &text, &scene);
    assert_eq!(atlas.shadowed.len(), 2, "{atlas:?}");
    assert!(atlas.left_by_policy.is_empty());
    assert!(atlas.dropped.len() >= 3, "{atlas:?}");
    assert!(atlas.dropped.iter().all(|d| d.reason == DropReason::NoRoom));
    // The dropped lights cast rays, and some of them hide something.
    let dropped: BTreeSet<u32> = atlas.dropped.iter().map(|d| d.light).collect();
    let hidden_by_dropped = jobs
        .iter()
        .flat_map(|p| p.iter())
        .filter(|(l, &h)| h && dropped.contains(l))
        .count();
    assert!(hidden_by_dropped > 50, "{hidden_by_dropped}");
}

#[test]
fn the_policy_follows_lights_that_move() {
    let mut r = renderer();
    let scene = scene(14, 7);
    let text = graph_text("visibility_hybrid_shadows.ron")
        .replace("policy: Nearest(16)", "policy: Nearest(4)");
    let checked =
        graph::check_text(Path::new("hybrid.ron"), &text, &ShaderLibrary::builtin()).unwrap();
    let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, &scene).unwrap();
    let size = FrameSize {
        width: W,
        height: H,
        lights: gpu.light_capacity,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    let prepared = r.prepare(compiled, &scene, &gpu, size, false).unwrap();
    let mapped = |f: &FrameResult| -> BTreeSet<u32> {
        f.atlases[0].shadowed.iter().map(|l| l.light).collect()
    };
    let before = prepared.render(&r).unwrap();
    // The farthest caster comes to just in front of the camera: it takes a map.
    let far = (0..14u32)
        .max_by(|&a, &b| {
            let d = |i: u32| scene.lights[i as usize].position.distance(scene.camera.eye);
            d(a).total_cmp(&d(b))
        })
        .unwrap();
    assert!(!mapped(&before).contains(&far));
    let mut moved = scene.clone();
    moved.lights[far as usize].position = Vec3::new(0.5, 2.5, 1.0);
    prepared.update_lights(&r, &gpu, &moved.lights).unwrap();
    let after = prepared.render(&r).unwrap();
    assert!(mapped(&after).contains(&far), "{:?}", after.atlases[0]);
    // The same allocation as a frame prepared for the moved lights, and the same image
    // within an ulp or two of the peak: an updated frame differs from a freshly prepared
    // one by that much in any graph (6e-8 of the peak here, with or without the atlas;
    // visibility_raycast_shadows.ron alike), a light given the wrong method by far more.
    let (_, fresh) = run(&mut r, &text, &moved);
    assert_eq!(after.atlases[0].shadowed, fresh.atlases[0].shadowed);
    let (worst, at) = max_rel_diff(&after.image, &fresh.image);
    assert!(worst < 3e-7, "{worst} of the peak at pixel {at}");
    assert_ne!(after.image, before.image);
}

/// Forward+ (graphs/hybrid_shadows.ron) and tiled deferred
/// (graphs/tiled_deferred_hybrid_shadows.ron) take the hybrid as the compute-first frame
/// does: their own ray-cast frame's jobs and bits for the lights the policy leaves to
/// rays, none for the mapped ones, and an image that is their ray-cast frame's plus their
/// atlas frame's (raycast_shadows.ron and shadow_atlas.ron, and the tiled deferred ones).
#[test]
fn forward_and_deferred_hybrids_equal_their_ray_cast_and_atlas_frames() {
    let mut r = renderer();
    let mut scene = scene(14, 7);
    // A pane of glass over the room: tiled deferred's glass is hybrid too (the atlas for
    // the mapped lights, its own traced rays for the rest), so its parts are the glass of
    // tiled_deferred_raycast_shadows.ron (traced) and tiled_deferred_shadow_atlas.ron
    // (the atlas); Forward+'s graphs have no glass passes and skip it.
    scene.materials.push(common::glass::pale_glass());
    let mut pane = lightgraph::scene::geometry::MeshBuilder::new("pane", 2);
    pane.quad(
        Vec3::new(-5.0, 2.5, -9.0),
        Vec3::new(0.0, 0.0, 8.0),
        Vec3::new(10.0, 0.0, 0.0),
        glam::Vec2::ONE,
    );
    scene.meshes.push(pane.build());
    for (hybrid, parts) in [
        (
            "hybrid_shadows.ron",
            Parts {
                rays: "raycast_shadows.ron",
                atlas: "shadow_atlas.ron",
            },
        ),
        (
            "tiled_deferred_hybrid_shadows.ron",
            Parts {
                rays: "tiled_deferred_raycast_shadows.ron",
                atlas: "tiled_deferred_shadow_atlas.ron",
            },
        ),
    ] {
        let text = graph_text(hybrid).replace("policy: Nearest(16)", "policy: Nearest(4)");
        assert!(text.contains("policy: Nearest(4)"), "{hybrid}");
        let (atlas, _) = check_hybrid_against(&mut r, &text, &scene, &parts);
        assert_eq!(atlas.shadowed.len(), 4, "{hybrid}: {atlas:?}");
    }
    // The pane shows in the tiled deferred frame (so its glass was checked above).
    let text = graph_text("tiled_deferred_hybrid_shadows.ron");
    let with_pane = run(&mut r, &text, &scene).1;
    let mut without = scene.clone();
    without.meshes.pop();
    let no_pane = run(&mut r, &text, &without).1;
    let changed = with_pane
        .image
        .iter()
        .zip(&no_pane.image)
        .filter(|(a, b)| a != b)
        .count();
    // 462 pixels on lavapipe (the room's boxes and column hide part of it).
    assert!(changed > 300, "the pane changes {changed} pixels");
}

/// `policy: RayBudget(rays)`: the lights that could cast the most rays take maps until
/// the rest could cast no more than the budget, so the frame casts at most that many
/// rays (each light's rays are bounded by its range's screen box on the CPU). The budget
/// here is two thirds of the all-rays frame's jobs; the hybrid checks of
/// `check_hybrid` hold with it.
#[test]
fn a_ray_budget_bounds_the_rays_cast() {
    let mut r = renderer();
    let scene = scene(14, 7);
    let (all_rays, _) = run(
        &mut r,
        &graph_text("visibility_raycast_shadows.ron"),
        &scene,
    );
    let all_jobs: usize = pixel_jobs(&r, &all_rays, W * H)
        .iter()
        .map(BTreeMap::len)
        .sum();
    let budget = all_jobs * 2 / 3;
    let text = graph_text("visibility_hybrid_shadows.ron").replace(
        "policy: Nearest(16)",
        &format!("policy: RayBudget({budget}.0)"),
    );
    assert!(text.contains("RayBudget("));
    let (atlas, jobs) = check_hybrid(&mut r, &text, &scene);
    let cast: usize = jobs.iter().map(BTreeMap::len).sum();
    eprintln!(
        "all rays {all_jobs}, budget {budget}: {cast} cast, {} mapped, {} left to rays, {} dropped",
        atlas.shadowed.len(),
        atlas.left_by_policy.len(),
        atlas.dropped.len()
    );
    assert!(atlas.dropped.is_empty(), "{atlas:?}");
    assert!(cast <= budget, "{cast} rays over the budget of {budget}");
    assert!(cast > 0 && !atlas.left_by_policy.is_empty(), "{atlas:?}");
}
