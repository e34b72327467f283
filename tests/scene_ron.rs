//! Scene RON files, built-in scenes, procedural light sets and the AMD generator.

use glam::Vec3;
use lightgraph::scene::lights::{amd_camera, amd_lights, AmdLights, Pcg32, AMD_SPOT_COS};
use lightgraph::scene::{self, builtin, light_flags, LightShape, SceneError};
use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "lightgraph_scene_ron_{}_{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn load_text(dir: &Path, text: &str) -> Result<scene::Loaded, SceneError> {
    let p = dir.join("scene.ron");
    std::fs::write(&p, text).unwrap();
    scene::load(&p)
}

#[test]
fn pcg32_is_stable() {
    // Reference values of PCG32 (pcg32_srandom(42, 54)) from the PCG paper's demo program.
    let mut r = Pcg32::with_stream(42, 54);
    let got: Vec<u32> = (0..6).map(|_| r.next_u32()).collect();
    assert_eq!(
        got,
        [0xa15c02b7, 0x7b47f409, 0xba1d3330, 0x83d2f293, 0xbfa4784b, 0xcbed606e]
    );
}

#[test]
fn builtins_have_what_they_promise() {
    let a = builtin::atrium();
    let tris = a.triangle_count();
    assert!(
        (3_000..60_000).contains(&tris),
        "atrium has {tris} triangles"
    );
    assert_eq!(a.lights.len(), 1024);
    let spots = a
        .lights
        .iter()
        .filter(|l| matches!(l.shape, LightShape::Spot { .. }))
        .count();
    assert_eq!(spots, 512);
    let (lo, hi) = a.bounds().unwrap();
    assert!(hi.y - lo.y > 10.0 && hi.x - lo.x > 30.0);
    for m in &a.meshes {
        assert_eq!(m.normals.len(), m.positions.len());
        assert_eq!(m.tangents.len(), m.positions.len());
        assert_eq!(m.uvs.len(), m.positions.len());
        assert!(m.indices.iter().all(|&i| (i as usize) < m.positions.len()));
        assert!(m.material < a.materials.len());
    }
    let h = builtin::harada();
    assert_eq!(h.lights.len(), 3072);
    assert_eq!(h.output_size, Some((1280, 720)));
    let d = builtin::depth_discontinuity();
    let zs: Vec<f32> = d.lights.iter().map(|l| l.position.z).collect();
    assert!(zs.iter().any(|&z| z < -40.0) && zs.iter().any(|&z| z > -10.0));
    // Deterministic.
    assert_eq!(builtin::atrium().lights, a.lights);
    for s in [&a, &h, &d] {
        for l in &s.lights {
            lightgraph::scene::lights::check_light(l).unwrap();
        }
    }
}

#[test]
fn amd_generator_matches_the_sample_setup() {
    let bounds = (Vec3::new(-10.0, 0.0, -4.0), Vec3::new(10.0, 6.0, 4.0));
    let lights = amd_lights(bounds);
    assert_eq!(lights.len(), 4096);
    let half = Vec3::new(10.0, 3.0, 4.0);
    let r = 0.075 * half.length();
    assert!(lights.iter().all(|l| (l.range - r).abs() < 1e-6));
    assert!(lights[..2048].iter().all(|l| l.shape == LightShape::Point));
    for l in &lights[2048..] {
        let LightShape::Spot {
            direction,
            outer_angle,
            ..
        } = l.shape
        else {
            panic!()
        };
        assert!((outer_angle.cos() - AMD_SPOT_COS).abs() < 1e-5);
        assert!((direction.length() - 1.0).abs() < 1e-4);
    }
    assert!(lights
        .iter()
        .all(|l| l.position.cmpge(bounds.0).all() && l.position.cmple(bounds.1).all()));
    // Roughly uniform: mean near the centre.
    let mean = lights.iter().map(|l| l.position).sum::<Vec3>() / 4096.0;
    assert!(mean.length() < 0.4 + 3.0, "{mean}");
    assert!((mean - Vec3::new(0.0, 3.0, 0.0)).length() < 0.4, "{mean}");
    // Fixed seed: same every time.
    assert_eq!(amd_lights(bounds), lights);
    let cam = amd_camera(bounds);
    assert_eq!(cam.eye, Vec3::new(-4.5, 3.0 - 1.05, 0.0));
    assert_eq!(cam.target, Vec3::new(0.0, 3.0 - 1.05, 0.0));
    let shadowed = AmdLights {
        shadow_casters: 12,
        ..Default::default()
    }
    .generate(bounds);
    let n = shadowed
        .iter()
        .filter(|l| l.flags & light_flags::CASTS_SHADOW != 0)
        .count();
    assert_eq!(n, 24);
}

#[test]
fn committed_scene_files_load() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|e| e == "ron") {
            let l = scene::load(&p).unwrap_or_else(|e| panic!("{e}"));
            assert!(!l.scene.meshes.is_empty(), "{}", p.display());
            n += 1;
        }
    }
    assert!(n >= 3);
    let h = scene::load(&dir.join("harada.ron")).unwrap().scene;
    assert_eq!((h.lights.len(), h.output_size), (3072, Some((1280, 720))));
    let amd = scene::load(&dir.join("atrium_amd.ron")).unwrap().scene;
    assert_eq!(amd.lights.len(), 4096);
    assert_eq!(amd.camera, amd_camera(amd.bounds().unwrap()));
    let f = amd.features();
    assert!(f.has_shadow_casters && f.has_spot_lights && !f.has_indirect_lights);
    let show = scene::load(&dir.join("atrium_showcase.ron")).unwrap();
    let s = &show.scene;
    assert_eq!(s.lights.len(), 2 + 512);
    assert!(s.features().has_indirect_lights);
    assert_eq!(
        s.material_overrides,
        vec![(
            "atrium_bronze".to_string(),
            PathBuf::from("materials/brushed_metal.ron")
        )]
    );
    assert!(show.warnings.is_empty(), "{:?}", show.warnings);
    assert_eq!(s.ambient, Vec3::new(0.01, 0.01, 0.012));
}

#[test]
fn ron_with_gltf_model_transform_and_light_sets() {
    use lightgraph::scene::gltf_writer::{BufferStorage, GltfWriter, NodeDesc};
    let d = tmp("model");
    std::fs::create_dir_all(d.join("models")).unwrap();
    let mut w = GltfWriter::new();
    let (p, n, uv, idx) = lightgraph::scene::gltf_writer::grid(2, 2.0);
    let m = w.add_simple_mesh("floor", &p, Some(&n), Some(&uv), Some(&idx), None);
    let light = w.add_light("lamp", Vec3::ONE, 1.0, Some(2.0), None);
    let a = w.add_node(&NodeDesc {
        mesh: Some(m),
        ..Default::default()
    });
    let b = w.add_node(&NodeDesc {
        light: Some(light),
        translation: Some(Vec3::Y),
        ..Default::default()
    });
    w.add_root(a);
    w.add_root(b);
    w.write_gltf(
        &d.join("models/floor.gltf"),
        &BufferStorage::External("floor.bin".into()),
    )
    .unwrap();
    let l = load_text(
        &d,
        r#"Scene(
            models: [
                (path: "models/floor.gltf", transform: (translation: (10, 0, 0), scale: (2, 2, 2)),
                 lights_cast_shadows: true),
                (path: "models/floor.gltf", transform: (rotation_deg: (0, 0, 180))),
            ],
            lights: [(position: (0, 1, 0), range: 2, intensity: 1)],
            light_sets: [Random(count: 100, spot_fraction: 0.3, placement: Box(min: (-1, 0, -1), max: (1, 1, 1)),
                                range: (0.5, 1), intensity: (1, 2), seed: 3, casts_shadow: true)],
            material_overrides: { "nope": "materials/x.ron" },
        )"#,
    )
    .unwrap();
    let s = &l.scene;
    assert_eq!(s.name, "floor");
    assert_eq!(s.meshes.len(), 2);
    let (lo, hi) = s.meshes[0]
        .positions
        .iter()
        .fold((Vec3::MAX, Vec3::MIN), |(a, b), p| (a.min(*p), b.max(*p)));
    assert_eq!(
        (lo, hi),
        (Vec3::new(8.0, 0.0, -2.0), Vec3::new(12.0, 0.0, 2.0))
    );
    // Rotated 180° about Z: faces down.
    assert!((s.meshes[1].normals[0] - Vec3::NEG_Y).length() < 1e-5);
    // 2 model lights + 1 explicit + 100 random.
    assert_eq!(s.lights.len(), 103);
    assert_eq!(s.lights[0].position, Vec3::new(10.0, 2.0, 0.0));
    assert!((s.lights[1].position - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-6);
    // lights_cast_shadows makes the first model's light cast, not the second's.
    assert_ne!(s.lights[0].flags & light_flags::CASTS_SHADOW, 0);
    assert_eq!(s.lights[1].flags & light_flags::CASTS_SHADOW, 0);
    let spots = s.lights[3..]
        .iter()
        .filter(|l| matches!(l.shape, LightShape::Spot { .. }))
        .count();
    assert_eq!(spots, 30);
    assert!(s.lights[3..]
        .iter()
        .all(|l| l.flags == light_flags::CASTS_SHADOW));
    assert!(
        l.warnings.iter().any(|w| w.contains("\"nope\"")),
        "{:?}",
        l.warnings
    );
}

/// Each broken scene RON and a fragment its error must contain.
const BAD_RON: &[(&str, &[&str])] = &[
    (
        r#"Scene(lights: [(name: "key", position: (0, NaN, 0), range: 1, intensity: 1)])"#,
        // Semantic errors point at the element's line and column like syntax errors.
        &["scene.ron:1:16: lights[0] (\"key\")", "position"],
    ),
    (
        r#"Scene(lights: [(position: (0, 0, 0), range: 1, intensity: 1), (position: (0, 0, 0), range: inf, intensity: 1)])"#,
        &["scene.ron:1:63: lights[1]", "range"],
    ),
    (
        r#"Scene(lights: [(position: (0, 0, 0), range: 0, intensity: 1)])"#,
        &["lights[0]", "range 0"],
    ),
    (
        r#"Scene(lights: [(position: (0, 0, 0), range: -2, intensity: 1)])"#,
        &["lights[0]", "range -2"],
    ),
    (
        r#"Scene(lights: [(name: "hot", position: (0, 0, 0), range: 1, intensity: NaN)])"#,
        &["\"hot\"", "intensity"],
    ),
    (
        r#"Scene(lights: [(position: (0, 0, 0), range: 1, intensity: 1, color: (1, inf, 1))])"#,
        &["lights[0]", "color"],
    ),
    (
        r#"Scene(lights: [(position: (0, 0, 0), range: 1, intensity: 1, spot: (direction: (0, -1, 0), inner_deg: NaN, outer_deg: 30))])"#,
        &["lights[0]", "angles"],
    ),
    (
        r#"Scene(lights: [(position: (0, 0, 0), range: 1, intensity: 1, spot: (direction: (0, -1, 0), inner_deg: 40, outer_deg: 30))])"#,
        &["lights[0]", "inner"],
    ),
    (
        r#"Scene(lights: [(position: (0, 0, 0), range: 1, intensity: 1, spot: (direction: (0, 0, 0), outer_deg: 30))])"#,
        &["lights[0]", "direction"],
    ),
    (
        r#"Scene(builtin: "cathedral")"#,
        &["scene.ron:1:7: builtin", "cathedral", "atrium"],
    ),
    (
        r#"Scene(builtin: "atrium", light_sets: [Random(count: 2000000, placement: SceneBounds(), range: (1, 2), intensity: (1, 1))])"#,
        &["scene.ron:1:39: light_sets[0]", "exceeds the limit"],
    ),
    (
        r#"Scene(builtin: "atrium", light_sets: [Random(count: 10, placement: SceneBounds(), range: (2, 1), intensity: (1, 1))])"#,
        &["light_sets[0]", "range", "min > max"],
    ),
    (
        r#"Scene(builtin: "atrium", light_sets: [Random(count: 10, placement: SceneBounds(), range: (0, 1), intensity: (1, 1))])"#,
        &["light_sets[0]", "> 0"],
    ),
    (
        r#"Scene(light_sets: [Amd()])"#,
        &["light_sets[0]", "bounding box"],
    ),
    (
        r#"Scene(models: [(path: "missing.gltf")])"#,
        &["scene.ron:1:16: models[0]", "missing.gltf", "cannot read"],
    ),
    (
        r#"Scene(models: [(path: "a.obj")])"#,
        &["models[0]", ".gltf or .glb"],
    ),
    (
        r#"Scene(builtin: "atrium", output_size: (0, 720))"#,
        &["output_size"],
    ),
    (
        r#"Scene(builtin: "atrium", camera: LookAt(eye: (0, 0, 0), target: (0, 0, 0)))"#,
        &["camera"],
    ),
    (r#"Scene(lihgts: [])"#, &["scene.ron:1:", "lihgts"]),
    (
        "Scene(\n  lights: [(position: (0, 0), range: 1, intensity: 1)],\n)",
        &["scene.ron:2:"],
    ),
];

#[test]
fn bad_scene_files_give_clear_errors() {
    let d = tmp("bad");
    let e = scene::load(&d.join("scene.obj")).unwrap_err().to_string();
    assert!(
        e.contains("scene.obj") && e.contains("unknown scene extension"),
        "{e}"
    );
    let e = scene::load(&d.join("absent.ron")).unwrap_err().to_string();
    assert!(e.contains("absent.ron") && e.contains("cannot read"), "{e}");
    for (text, fragments) in BAD_RON {
        let err = match load_text(&d, text) {
            Ok(_) => panic!("loaded without error: {text}"),
            Err(e) => e.to_string(),
        };
        for f in *fragments {
            assert!(err.contains(f), "error for {text}\n  {err}\nlacks {f:?}");
        }
    }
}

/// A model without a camera gets a fitted one only when the scene file gives none: the
/// warning says so once, naming the scene file, and never when a camera is given.
#[test]
fn fitted_camera_warning_only_when_the_scene_file_gives_none() {
    let d = tmp("camera_warning");
    let tri = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad/hostile/models/tri.gltf");
    let given = load_text(
        &d,
        &format!(
            "Scene(models: [(path: {tri:?})], camera: LookAt(eye: (0, 0, 3), target: (0, 0, 0), fov_y_deg: 50, near: 0.05, far: 100))"
        ),
    )
    .unwrap();
    assert!(
        !given.warnings.iter().any(|w| w.contains("fitted")),
        "{:?}",
        given.warnings
    );
    let fitted = load_text(&d, &format!("Scene(models: [(path: {tri:?})])")).unwrap();
    let warned: Vec<_> = fitted
        .warnings
        .iter()
        .filter(|w| w.contains("fitted"))
        .collect();
    assert_eq!(warned.len(), 1, "{:?}", fitted.warnings);
    assert!(warned[0].contains("scene.ron: no camera"), "{warned:?}");
}
