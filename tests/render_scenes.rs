//! Whole-scene renders checked by pixel values: the analytic sphere (exact radiance), the
//! Cornell box glTF in scenes/cornell_box (copied from the shared assets) (red and green
//! walls, lit interior), and the default scene (scenes/gallery.ron: textured models, many
//! lights, glass) through the default graph.

mod common;
use common::*;
use glam::{Vec2, Vec3};
use lightgraph::scene::{self, Camera, Light, Mesh, Scene, SurfaceMaterial};
use std::path::{Path, PathBuf};

/// A UV sphere of radius 1 around the origin, normals pointing inward.
fn inside_sphere(segments: u32, rings: u32) -> Mesh {
    let mut m = Mesh {
        name: "sphere".into(),
        ..Default::default()
    };
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = 2.0 * std::f32::consts::PI * s as f32 / segments as f32;
            let p = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            m.positions.push(p);
            m.normals.push(-p);
            m.uvs.push(Vec2::new(
                s as f32 / segments as f32,
                r as f32 / rings as f32,
            ));
            m.tangents
                .push(Vec3::new(-phi.sin(), 0.0, phi.cos()).extend(1.0));
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (
                r * row + s,
                r * row + s + 1,
                (r + 1) * row + s,
                (r + 1) * row + s + 1,
            );
            // Counter-clockwise seen from inside.
            m.indices.extend([a, c, b, b, c, d]);
        }
    }
    m
}

fn analytic_scene(lights: usize, look: Vec3) -> Scene {
    let material_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/lambert_kd05.ron");
    let total = std::f32::consts::PI;
    Scene {
        name: format!("analytic sphere, {lights} light(s)"),
        meshes: vec![inside_sphere(256, 128)],
        materials: vec![SurfaceMaterial {
            name: "sphere".into(),
            double_sided: true,
            ..Default::default()
        }],
        material_overrides: vec![("sphere".into(), material_path)],
        // Range 1e3: the window 1 - (d/range)^4 is exactly 1 in f32 at d = 1.
        lights: (0..lights)
            .map(|_| Light::point(Vec3::ZERO, 1e3, Vec3::ONE, total / lights as f32))
            .collect(),
        camera: Camera {
            eye: Vec3::ZERO,
            target: look,
            up: Vec3::Y,
            fov_y: 90f32.to_radians(),
            near: 0.01,
            far: 10.0,
        },
        ..Default::default()
    }
}

#[test]
fn analytic_sphere_has_radiance_one_half() {
    let mut r = renderer();
    for look in [Vec3::NEG_Z, Vec3::new(1.0, 0.7, 0.2)] {
        let one = render_file(&mut r, "forward_plus.ron", &analytic_scene(1, look), 64, 48);
        let mut worst = 0.0f32;
        for p in &one.image {
            for c in &p[..3] {
                worst = worst.max((c - 0.5).abs());
            }
        }
        // Direct light only: L = Kd/pi * I * cos / d^2 = 0.5 on the unit sphere. The
        // tessellation (256 x 128) moves points inside the sphere by at most
        // 1 - cos(pi/128) = 3e-4, changing d^2 and the cosine by less than that.
        assert!(worst < 1e-3, "max |L - 0.5| = {worst}");
        // Eight co-located lights of pi/8 each: the same image.
        let eight = render_file(&mut r, "forward_plus.ron", &analytic_scene(8, look), 64, 48);
        let (d, at) = max_rel_diff(&eight.image, &one.image);
        // Summing eight equal terms instead of one: a few f32 roundings.
        assert!(d < 1e-6, "8 lights differ by {d} at pixel {at}");
    }
}

fn cornell_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_box/scene.gltf")
}

#[test]
fn cornell_box_has_red_and_green_walls_and_a_lit_interior() {
    let path = cornell_path();
    assert!(path.exists(), "{} is missing", path.display());
    let mut s = scene::load(&path).expect("cornell box imports").scene;
    assert!(
        s.lights.is_empty(),
        "the asset has no lights; the CLI adds one"
    );
    assert!(s.add_headlight_if_unlit().is_some());
    let (w, h) = (96, 96);
    let mut r = renderer();
    let out = render_file(&mut r, "forward_plus.ron", &s, w, h);
    let (mut red, mut green, mut lit) = (Vec::new(), Vec::new(), 0);
    for (i, p) in out.image.iter().enumerate() {
        let x = (i as u32 % w) as f32 / w as f32;
        if p[0] > 2.0 * p[1] && p[0] > 2.0 * p[2] && p[0] > 1e-3 {
            red.push(x);
        }
        if p[1] > 2.0 * p[0] && p[1] > 2.0 * p[2] && p[1] > 1e-3 {
            green.push(x);
        }
        if p[0] + p[1] + p[2] > 1e-3 {
            lit += 1;
        }
    }
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len().max(1) as f32;
    let n = (w * h) as usize;
    assert!(
        red.len() > n / 30 && green.len() > n / 30,
        "red {} green {} of {n}",
        red.len(),
        green.len()
    );
    assert!(
        mean(&red) < 0.4,
        "red wall on the left: mean x {}",
        mean(&red)
    );
    assert!(
        mean(&green) > 0.6,
        "green wall on the right: mean x {}",
        mean(&green)
    );
    assert!(lit > n / 3, "interior lit: {lit} of {n}");
    // The centre (back wall, boxes) is lit by the added light.
    let c = out.image[(h / 2 * w + w / 2) as usize];
    assert!(c[0] > 0.01 && c[1] > 0.01 && c[2] > 0.01, "centre {c:?}");
}

#[test]
fn a_light_lights_only_the_materials_in_its_mask() {
    let mut r = renderer();
    // The analytic material has type bit 1 (the default).
    let mut scene = analytic_scene(2, Vec3::NEG_Z);
    scene.lights[0].material_mask = !1; // every material but this one
    scene.lights[1].material_mask = 1;
    let out = render_file(&mut r, "forward_plus.ron", &scene, 32, 24);
    // Only the second light (pi/2) reaches the surface: radiance 0.25.
    for p in &out.image {
        assert!((p[0] - 0.25).abs() < 1e-3, "{p:?}");
    }
}

#[test]
fn alpha_masked_geometry_is_cut_out_in_prepass_and_shading() {
    let mut r = renderer();
    let mut scene = random_scene(40, 4);
    let reference = render_file(&mut r, "forward_plus.ron", &scene, 96, 64);
    // A masked panel right in front of the camera, alpha 0.2 under a 0.5 cutoff: fully cut out.
    let eye = scene.camera.eye;
    scene.materials.push(SurfaceMaterial {
        name: "masked".into(),
        base_color: glam::Vec4::new(1.0, 1.0, 1.0, 0.2),
        alpha_mode: scene::AlphaMode::Mask(0.5),
        double_sided: true,
        ..Default::default()
    });
    let masked = scene.materials.len() - 1;
    scene.meshes.push(cuboid(
        "panel",
        eye + Vec3::new(-3.0, -3.0, -1.2),
        eye + Vec3::new(3.0, 3.0, -1.0),
        masked,
        false,
    ));
    assert!(scene.features().has_alpha_mask);
    let cut = render_file(&mut r, "forward_plus.ron", &scene, 96, 64);
    let (d, at) = max_rel_diff(&cut.image, &reference.image);
    assert!(d < 1e-6, "the masked panel changed pixel {at} by {d}");
    // With alpha above the cutoff the panel is there.
    scene.materials[masked].base_color.w = 0.9;
    let solid = render_file(&mut r, "forward_plus.ron", &scene, 96, 64);
    let (d, _) = max_rel_diff(&solid.image, &reference.image);
    assert!(d > 0.1, "an opaque-enough panel must show: {d}");
}

/// The default scene (`cargo run --release` in a checkout) shows what lightgraph is for:
/// textured glTF models, many materials and over 250,000 triangles, many coloured lights
/// and blended glass, drawn by the default graph (graphs/default.ron) with its
/// transparency passes, lit across the frame, its key lights casting ray-cast shadows.
#[test]
fn the_default_scene_has_textures_many_lights_and_glass_through_the_default_graph() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/gallery.ron");
    let s = scene::load(&path).expect("the gallery loads").scene;
    let textured = s
        .materials
        .iter()
        .filter(|m| m.base_color_texture.is_some())
        .count();
    assert!(textured >= 2, "{textured} textured materials");
    assert!(
        s.materials.iter().any(|m| m.normal_texture.is_some()),
        "no normal-mapped material"
    );
    assert!(s.materials.len() >= 130, "{} materials", s.materials.len());
    // Real content at the size the benchmarks are about: past a quarter of a million
    // triangles (the spheres and the engine hold most of them).
    assert!(
        s.triangle_count() >= 250_000,
        "{} triangles",
        s.triangle_count()
    );
    assert!(s.lights.len() >= 1024, "{} lights", s.lights.len());
    let features = s.features();
    assert!(features.has_transparent, "no blended meshes");
    let (w, h) = (160, 90);
    let mut r = renderer();
    let frame = render_file(&mut r, "default.ron", &s, w, h);
    let opaque = render_file(&mut r, "visibility_compute_raster.ron", &s, w, h);
    assert_eq!(frame.image.len(), (w * h) as usize);
    assert_eq!(opaque.image.len(), frame.image.len());
    let lit = frame
        .image
        .iter()
        .filter(|p| p[0] + p[1] + p[2] > 1e-3)
        .count();
    assert!(lit * 2 > frame.image.len(), "{lit} lit pixels");
    // The glass shows: the transparency passes change part of the frame.
    let glass = frame
        .image
        .iter()
        .zip(&opaque.image)
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        glass > frame.image.len() / 100,
        "only {glass} pixels show glass"
    );
    // Many lights are culled into the tiles, not a handful.
    let listed: u32 = frame.culling[0].per_tile().iter().sum();
    let tiles = frame.culling[0].per_tile().len() as u32;
    assert!(
        listed > 10 * tiles,
        "{listed} lights listed over {tiles} tiles"
    );
    // Its key lights cast shadows through the default frame's ray-cast passes: without
    // their shadows part of the frame is brighter.
    let casters = s
        .lights
        .iter()
        .filter(|l| l.flags & scene::light_flags::CASTS_SHADOW != 0)
        .count();
    assert!(casters >= 2, "{casters} shadow-casting lights");
    let mut unshadowed = s.clone();
    for l in &mut unshadowed.lights {
        l.flags &= !scene::light_flags::CASTS_SHADOW;
    }
    let bright = render_file(&mut r, "default.ron", &unshadowed, w, h);
    let luma = |p: &[f32; 4]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let shadowed = frame
        .image
        .iter()
        .zip(&bright.image)
        .filter(|(a, b)| luma(a) < 0.8 * luma(b))
        .count();
    println!("{shadowed} pixels over 20% darker for the key lights' shadows");
    // 337 of 14,400 measured on lavapipe (none with every ray unblocked).
    assert!(
        shadowed > frame.image.len() / 100,
        "only {shadowed} pixels shadowed"
    );
}
