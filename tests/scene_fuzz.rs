//! Corrupted glTF bytes never panic the importer: a valid .glb and a valid .gltf (embedded
//! buffer) get random byte flips, truncations and JSON number edits, deterministically.

use glam::{Vec2, Vec3};
use lightgraph::scene::gltf_import::{import_gltf_slice, ImportLimits};
use lightgraph::scene::gltf_writer::{
    BufferStorage, GltfWriter, ImageStorage, MaterialDesc, NodeDesc,
};
use lightgraph::scene::lights::Pcg32;
use std::path::Path;

fn sample() -> GltfWriter {
    let mut w = GltfWriter::new();
    let img = image::RgbaImage::from_pixel(2, 2, image::Rgba([10, 20, 30, 255]));
    let t = w.add_texture_png("t", &img, ImageStorage::BufferView);
    let m = w.add_material(&MaterialDesc {
        base_color_texture: Some(t),
        ..Default::default()
    });
    let p = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE];
    let uv = [Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::ONE];
    let mesh = w.add_simple_mesh(
        "m",
        &p,
        Some(&[Vec3::Z; 4]),
        Some(&uv),
        Some(&[0, 1, 2, 2, 1, 3]),
        Some(m),
    );
    let l = w.add_light("l", Vec3::ONE, 1.0, Some(1.0), Some((0.1, 0.4)));
    let c = w.add_camera(1.0, 0.1, None);
    let child = w.add_node(&NodeDesc {
        mesh: Some(mesh),
        light: Some(l),
        ..Default::default()
    });
    let root = w.add_node(&NodeDesc {
        camera: Some(c),
        children: vec![child],
        translation: Some(Vec3::ONE),
        ..Default::default()
    });
    w.add_root(root);
    w
}

const FUZZ_CASES: u32 = 3000;
const FUZZ_SEED: u64 = 99;

fn run(bytes: &[u8]) -> bool {
    std::panic::catch_unwind(|| {
        let _ = import_gltf_slice(
            bytes,
            Path::new("/nonexistent"),
            Path::new("fuzz.glb"),
            &ImportLimits::default(),
        );
    })
    .is_ok()
}

#[test]
fn corrupted_files_never_panic() {
    let w = sample();
    let glb = w.to_glb();
    // The .gltf base embeds the real buffer (a stand-in URI failed before the fuzzing
    // reached anything past the buffer's length check).
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ok.gltf");
    w.write_gltf(&path, &BufferStorage::Embedded).unwrap();
    let gltf = std::fs::read(&path).unwrap();
    for (bytes, name) in [(&glb, "ok.glb"), (&gltf, "ok.gltf")] {
        let base = import_gltf_slice(
            bytes,
            Path::new("."),
            Path::new(name),
            &ImportLimits::default(),
        )
        .unwrap_or_else(|e| panic!("the uncorrupted {name} must import: {e}"));
        assert_eq!(base.scene.meshes.len(), 1, "{name}");
        assert_eq!(base.scene.lights.len(), 1, "{name}");
    }
    let mut rng = Pcg32::new(FUZZ_SEED);
    let mut panics = Vec::new();
    for case in 0..FUZZ_CASES {
        let base = if case % 2 == 0 { &glb } else { &gltf };
        let mut b = base.clone();
        match rng.next_u32() % 4 {
            0 => {
                for _ in 0..1 + rng.next_u32() % 8 {
                    let i = rng.next_u32() as usize % b.len();
                    b[i] = rng.next_u32() as u8;
                }
            }
            1 => b.truncate(rng.next_u32() as usize % b.len()),
            2 => {
                // Replace a digit in the JSON with another digit (counts, offsets, indices).
                let digits: Vec<usize> = (0..b.len().min(4000))
                    .filter(|&i| b[i].is_ascii_digit())
                    .collect();
                for _ in 0..1 + rng.next_u32() % 3 {
                    if let Some(&i) = digits.get(rng.next_u32() as usize % digits.len().max(1)) {
                        b[i] = b'0' + (rng.next_u32() % 10) as u8;
                    }
                }
            }
            _ => {
                let i = rng.next_u32() as usize % b.len();
                b.insert(i, b'9');
            }
        }
        if !run(&b) {
            panics.push(case);
        }
    }
    assert!(panics.is_empty(), "panicked on cases {panics:?}");
}
