//! The shadow atlas on the real adapter (lavapipe on CI), against analytic answers:
//! - a quad over a floor under a spot light: where the filtered shadow crosses one half,
//!   the floor point is within two texels (of the light's tile, at the quad) of the quad's
//!   projected edge; fully lit and fully shadowed beyond the filter's reach, both filters;
//! - a point light low over an open floor: the floor spans five cube faces and nothing
//!   occludes it, so every lit pixel keeps all its light (no seams, no acne);
//! - an atlas too small for its casters: the dropped lights are reported with their
//!   reason and light exactly as lights that cast no shadow;
//! - Forward+ and tiled deferred sample the atlas alike.

mod common;

use common::{graph_text, lambert, renderer};
use glam::{Vec2, Vec3};
use lightgraph::render::{FrameResult, Renderer};
use lightgraph::scene::geometry::MeshBuilder;
use lightgraph::scene::{light_flags, Camera, Light, LightShape, Scene};
use lightgraph::shadow::atlas::{DropReason, GUARD_TEXELS};
use std::path::Path;

const W: u32 = 96;
const H: u32 = 64;

fn render(r: &mut Renderer, text: &str, scene: &Scene) -> FrameResult {
    common::render_text(r, text, scene, W, H)
}

/// The same scene with no light casting a shadow: every pixel's unshadowed light.
fn unshadowed(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    for l in &mut s.lights {
        l.flags &= !light_flags::CASTS_SHADOW;
    }
    s
}

fn floor(half: f32) -> MeshBuilder {
    let mut floor = MeshBuilder::new("floor", 0);
    floor.quad(
        Vec3::new(-half, 0.0, half),
        Vec3::new(2.0 * half, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -2.0 * half),
        Vec2::ONE,
    );
    floor
}

/// Where the camera ray through a pixel's centre meets the plane y = `height`.
fn on_plane(camera: &Camera, px: u32, py: u32, height: f32) -> Option<Vec3> {
    let inv = (camera.projection(W as f32 / H as f32) * camera.view()).inverse();
    let ndc = Vec2::new(
        (px as f32 + 0.5) / W as f32 * 2.0 - 1.0,
        1.0 - (py as f32 + 0.5) / H as f32 * 2.0,
    );
    let near = inv.project_point3(ndc.extend(0.0));
    let far = inv.project_point3(ndc.extend(1.0));
    let t = (height - near.y) / (far.y - near.y);
    (t > 0.0).then(|| near + (far - near) * t)
}

const OUTER: f32 = 0.7;
const LIGHT: Vec3 = Vec3::new(0.3, 3.0, 0.2);

fn quad_scene() -> Scene {
    let mut quad = MeshBuilder::new("quad", 1);
    quad.quad(
        Vec3::new(-0.5, 1.0, 0.5),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -1.0),
        Vec2::ONE,
    );
    let spot = Light {
        shape: LightShape::Spot {
            direction: Vec3::NEG_Y,
            inner_angle: 0.6,
            outer_angle: OUTER,
        },
        flags: light_flags::CASTS_SHADOW,
        ..Light::point(LIGHT, 30.0, Vec3::ONE, 5.0)
    };
    Scene {
        name: "quad over floor".into(),
        meshes: vec![floor(4.0).build(), quad.build()],
        materials: vec![
            lambert("floor", Vec3::splat(0.8)),
            lambert("quad", Vec3::ONE),
        ],
        lights: vec![spot],
        camera: Camera {
            eye: Vec3::new(0.0, 5.0, 2.5),
            target: Vec3::ZERO,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// Per floor pixel: (filtered visibility, whether the quad hides the light, the
/// distance of the crossing to the quad's edge in the tile's texels).
fn quad_floor_samples(filter: &str, max_tile: u32) -> (Vec<(f32, bool, f32)>, u32) {
    let mut r = renderer();
    let scene = quad_scene();
    let text = graph_text("shadow_atlas.ron").replace(
        "ShadowAtlas(filter: Pcf5x5, min_tile: 16, max_tile: 1024, importance: 1.0)",
        &format!(
            "ShadowAtlas(filter: {filter}, min_tile: 16, max_tile: {max_tile}, importance: 16.0)"
        ),
    );
    let shadowed = render(&mut r, &text, &scene);
    let open = render(&mut r, &text, &unshadowed(&scene));
    let atlas = &shadowed.atlases[0];
    assert_eq!(atlas.shadowed.len(), 1, "{atlas:?}");
    let tile = atlas.shadowed[0].tile;
    // The tile's texel at the quad's plane, 2 below the light (src/shadow/atlas.rs).
    let inner = (tile - 2 * GUARD_TEXELS) as f32;
    let texel = 2.0 * OUTER.tan() * tile as f32 / inner / tile as f32 * (LIGHT.y - 1.0);
    let mut out = Vec::new();
    for py in 0..H {
        for px in 0..W {
            let i = (py * W + px) as usize;
            let Some(p) = on_plane(&scene.camera, px, py, 0.0) else {
                continue;
            };
            let q_cam = on_plane(&scene.camera, px, py, 1.0).unwrap();
            if q_cam.x.abs() <= 0.5 && q_cam.z.abs() <= 0.5 {
                continue; // the camera sees the quad here
            }
            if open.image[i][0] <= 1e-6 {
                continue; // outside the cone
            }
            let t = (1.0 - p.y) / (LIGHT.y - p.y);
            let q = p + (LIGHT - p) * t;
            let inside = q.x.abs() <= 0.5 && q.z.abs() <= 0.5;
            let edge = (0.5 - q.x.abs()).abs().min((0.5 - q.z.abs()).abs()) / texel;
            out.push((shadowed.image[i][0] / open.image[i][0], inside, edge));
        }
    }
    (out, tile)
}

/// Checks every floor pixel; returns the pixels fully shadowed and fully lit.
fn check_quad(filter: &str, max_tile: u32, reach: f32) -> (u32, u32) {
    let (samples, tile) = quad_floor_samples(filter, max_tile);
    let (mut dark, mut lit, mut crossing) = (0, 0, 0);
    for &(v, inside, edge) in &samples {
        if (v < 0.5) != inside {
            assert!(
                edge <= 2.0,
                "{filter} at {tile}²: visibility {v} {} texels from the edge, inside {inside}",
                edge
            );
            crossing += 1;
        }
        if edge > reach {
            let want = if inside { 0.0 } else { 1.0 };
            assert!(
                (v - want).abs() < 1e-4,
                "{filter}: visibility {v} {edge} texels from the edge, inside {inside}"
            );
            if inside {
                dark += 1;
            } else {
                lit += 1;
            }
        }
    }
    eprintln!("{filter} at {tile}²: {dark} shadowed, {lit} lit, {crossing} across the half");
    (dark, lit)
}

#[test]
fn a_quad_over_a_floor_shadows_within_two_texels_of_its_projection() {
    // 5×5 taps reach 2 texels and their comparisons one more; the normal offset and the
    // floor's slope in the map add under a texel, so beyond 4 the answer is exact.
    // At 64² the quad is 12 texels wide, so few of its shadow's pixels are beyond reach.
    let counts = [
        check_quad("Pcf5x5", 64, 4.0),
        check_quad("Hardware2x2", 64, 2.0),
        check_quad("Pcf5x5", 256, 4.0),
        check_quad("Hardware2x2", 256, 2.0),
    ];
    eprintln!("{counts:?}");
    for (dark, lit) in counts {
        assert!(dark > 20 && lit > 500, "{dark} shadowed, {lit} lit");
    }
}

#[test]
fn a_point_light_over_an_open_floor_keeps_all_its_light_across_cube_faces() {
    let mut r = renderer();
    let light = Light {
        flags: light_flags::CASTS_SHADOW,
        ..Light::point(Vec3::new(0.2, 0.8, -0.1), 6.0, Vec3::ONE, 3.0)
    };
    let scene = Scene {
        name: "open floor".into(),
        meshes: vec![floor(8.0).build()],
        materials: vec![lambert("floor", Vec3::splat(0.8))],
        lights: vec![light],
        camera: Camera {
            eye: Vec3::new(0.0, 7.0, 0.5),
            target: Vec3::ZERO,
            ..Default::default()
        },
        ..Default::default()
    };
    for filter in ["Pcf5x5", "Hardware2x2"] {
        let text =
            graph_text("shadow_atlas.ron").replace("filter: Pcf5x5", &format!("filter: {filter}"));
        let shadowed = render(&mut r, &text, &scene);
        let open = render(&mut r, &text, &unshadowed(&scene));
        assert_eq!(shadowed.atlases[0].views, 6);
        let (mut checked, mut seams) = (0, 0);
        for py in 0..H {
            for px in 0..W {
                let i = (py * W + px) as usize;
                if open.image[i][0] <= 1e-5 {
                    continue;
                }
                let v = shadowed.image[i][0] / open.image[i][0];
                assert!(
                    v > 1.0 - 1e-5,
                    "{filter}: pixel ({px}, {py}) keeps {v} of its light"
                );
                checked += 1;
                // Near a face edge: the two largest components of the direction agree.
                let p = on_plane(&scene.camera, px, py, 0.0).unwrap();
                let d = (p - light.position).abs();
                let mut c = [d.x, d.y, d.z];
                c.sort_by(f32::total_cmp);
                if c[1] > 0.9 * c[2] {
                    seams += 1;
                }
            }
        }
        eprintln!("{filter}: {checked} lit floor pixels, {seams} near a face edge");
        assert!(
            checked > 2000 && seams > 200,
            "{checked} checked, {seams} near seams"
        );
    }
}

#[test]
fn a_point_lights_shadows_across_cube_faces_agree_with_ray_casting() {
    let mut r = renderer();
    let light = Light {
        flags: light_flags::CASTS_SHADOW,
        ..Light::point(Vec3::new(0.2, 0.8, -0.1), 6.0, Vec3::ONE, 3.0)
    };
    // Boxes on every side of the light, some straddling cube-face edges (the diagonals
    // |x| = |z| and the −Y face's rim), casting shadows across them onto the floor.
    let mut boxes = MeshBuilder::new("boxes", 1);
    for (c, h) in [
        (Vec3::new(1.4, 0.35, -0.1), 0.15),
        (Vec3::new(-0.7, 0.4, 0.9), 0.15),
        (Vec3::new(0.2, 0.35, -1.5), 0.2),
        (Vec3::new(1.1, 0.3, 0.9), 0.12),
        (Vec3::new(0.75, 0.3, -0.55), 0.1),
        (Vec3::new(-1.2, 0.25, -1.1), 0.1),
    ] {
        boxes.cuboid(c - Vec3::splat(h), c + Vec3::splat(h));
    }
    let scene = Scene {
        name: "boxes around a point light".into(),
        meshes: vec![floor(8.0).build(), boxes.build()],
        materials: vec![
            lambert("floor", Vec3::splat(0.8)),
            lambert("boxes", Vec3::ONE),
        ],
        lights: vec![light],
        camera: Camera {
            eye: Vec3::new(0.0, 7.0, 0.5),
            target: Vec3::ZERO,
            ..Default::default()
        },
        ..Default::default()
    };
    let bvh = lightgraph::shadow::ShadowBvh::build(&scene).expect("bvh");
    // Tiles of 512² (importance 8 on this 64-pixel-high frame): at 64² the normal offset
    // alone (1.5 texels, 0.25 world units at the far floor) shrinks shadows visibly.
    for (filter, importance) in [("Pcf5x5", 8), ("Hardware2x2", 8)] {
        let text = graph_text("shadow_atlas.ron")
            .replace("filter: Pcf5x5", &format!("filter: {filter}"))
            .replace("importance: 1.0", &format!("importance: {importance}.0"));
        let shadowed = render(&mut r, &text, &scene);
        let open = render(&mut r, &text, &unshadowed(&scene));
        let (mut floor_pixels, mut hidden, mut disagree) = (0, 0, 0);
        for py in 0..H {
            for px in 0..W {
                let i = (py * W + px) as usize;
                let p = on_plane(&scene.camera, px, py, 0.0).unwrap();
                // Floor pixels only: the camera ray meets no box first.
                let eye = scene.camera.eye;
                if bvh.occluded(eye, p - eye, 1.0 - 1e-4) || open.image[i][0] <= 1e-5 {
                    continue;
                }
                let origin = p + Vec3::Y * 1e-4;
                let occluded = bvh.occluded(origin, light.position - origin, 1.0);
                let v = shadowed.image[i][0] / open.image[i][0];
                floor_pixels += 1;
                hidden += occluded as u32;
                disagree += ((v < 0.5) != occluded) as u32;
            }
        }
        let fraction = disagree as f64 / floor_pixels as f64;
        eprintln!(
            "{filter} x{importance}: {floor_pixels} floor pixels, {hidden} hidden, {disagree} disagree ({:.2}%)",
            100.0 * fraction
        );
        assert!(
            hidden > 200,
            "{hidden} hidden pixels: the boxes must cast shadows"
        );
        // Disagreement is left only along the shadows' edges, a pixel or two wide.
        assert!(
            fraction < 0.02,
            "{filter}: {disagree} of {floor_pixels} pixels disagree"
        );
    }
    // The benchmark's measure, on the GPU against the ray-cast mask, every (pixel, light)
    // pair of floor and boxes: as close as the CPU's count on the floor.
    let compare = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/graphs/shadow_atlas_vs_raycast.ron"),
    )
    .unwrap()
    .replace("importance: 1.0", "importance: 8.0");
    let result = render(&mut r, &compare, &scene);
    let c = &result.shadow_compare[0];
    eprintln!("{c:?}");
    assert!(c.pairs > 4000, "{c:?}");
    assert!(c.error_pcf5() < 0.02 && c.error_2x2() < 0.02, "{c:?}");
    assert!(c.disagree_pcf5 > 0 && c.penumbra_pcf5 > 0, "{c:?}");
}

#[test]
fn lights_without_room_are_reported_and_light_unshadowed() {
    let mut r = renderer();
    let mut scene = quad_scene();
    scene.lights = (0..4)
        .map(|i| Light {
            flags: light_flags::CASTS_SHADOW,
            ..Light::point(Vec3::new(i as f32 - 1.5, 2.0, 0.0), 30.0, Vec3::ONE, 2.0)
        })
        .collect();
    // 256² holds 16 tiles of 64²: two point lights' six faces, not three.
    let text = graph_text("shadow_atlas.ron")
        .replace("Fixed(4096, 4096)", "Fixed(256, 256)")
        .replace(
            "min_tile: 16, max_tile: 1024",
            "min_tile: 64, max_tile: 256",
        );
    let result = render(&mut r, &text, &scene);
    let atlas = &result.atlases[0];
    assert_eq!(atlas.shadowed.len(), 2, "{atlas:?}");
    assert_eq!(atlas.dropped.len(), 2, "{atlas:?}");
    assert!(atlas
        .dropped
        .iter()
        .all(|d| d.reason == DropReason::NoRoom && d.wanted == 64));
    // Dropped lights light exactly as lights that cast no shadow.
    let mut without = scene.clone();
    for d in &atlas.dropped {
        without.lights[d.light as usize].flags &= !light_flags::CASTS_SHADOW;
    }
    let reference = render(&mut r, &text, &without);
    assert!(reference.atlases[0].dropped.is_empty());
    assert_eq!(reference.atlases[0].shadowed, atlas.shadowed);
    assert_eq!(result.image.len(), reference.image.len());
    assert_eq!(result.image, reference.image);
    // And the quad still shadows something: the kept lights are shadowed.
    let open = render(&mut r, &text, &unshadowed(&scene));
    assert_ne!(result.image, open.image);
}

#[test]
fn forward_and_deferred_sample_the_atlas_alike() {
    let mut r = renderer();
    let mut scene = quad_scene();
    scene.lights.push(Light {
        flags: light_flags::CASTS_SHADOW,
        ..Light::point(
            Vec3::new(-0.6, 1.8, 0.4),
            8.0,
            Vec3::new(1.0, 0.5, 0.2),
            2.0,
        )
    });
    let forward = render(&mut r, &graph_text("shadow_atlas.ron"), &scene);
    let deferred = render(
        &mut r,
        &graph_text("tiled_deferred_shadow_atlas.ron"),
        &scene,
    );
    assert_eq!(forward.image.len(), (W * H) as usize);
    assert_eq!(forward.image.len(), deferred.image.len());
    // The same light loop and atlas lookups; positions come interpolated (forward) or
    // from the G-buffer (deferred), equal to the last bit on these flat quads bar fp32
    // rounding of the interpolation.
    let (worst, at) = common::max_rel_diff(&deferred.image, &forward.image);
    assert!(
        worst < 1e-4,
        "worst relative difference {worst} at pixel {at}"
    );
    let unshadowed_image =
        render(&mut r, &graph_text("shadow_atlas.ron"), &unshadowed(&scene)).image;
    assert_ne!(forward.image, unshadowed_image);
}
