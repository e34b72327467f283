//! The packed G-buffer (`graphs/tiled_deferred_packed.ron`) against the exact two-texture
//! one (`tiled_deferred.ron`, itself within 2e-6 of forward brute force: culling_exact.rs)
//! on every shipped scene. Not exact: it rebuilds each position on the pixel's view ray
//! while the rasterizer interpolates it over the snapped triangle, so its error is
//! measured here and held to the bound docs/deferred.md states. Against the exact G-buffer, not
//! brute force: the same culled lighting, so the test stays fast, and what differs is the
//! packing alone (deferred shading's own limits, such as no tangents for anisotropic
//! materials, are in both). Both draw the scenes' glass the same way after the deferred
//! frame (tiled_deferred_transparent.ron is the exact G-buffer with the glass passes).

mod common;
use common::*;
use lightgraph::scene;
use std::path::Path;

const W: u32 = 320;
const H: u32 = 180;
/// Worst pixel, relative to max(|reference|, 1e-3 of the peak), measured on lavapipe at
/// 320x180 (2026-12-01): atrium 2.35e-3, atrium_amd 5.20e-3, atrium_shadows 1.46e-3,
/// atrium_showcase 2.73e-3, chairs 3.1e-4, cornell_box 1.9e-6, depth_discontinuity 2.0e-4,
/// harada 1.14e-3. The bound is about twice the worst.
const BOUND: f32 = 1e-2;
/// The gallery (glTF models, textured since deferred takes textures) measured 1.15e-2
/// (2026-12-06; the same with its 98 spheres added, against tiled_deferred_transparent,
/// glass.ron 4.3e-5): its worst pixels were not located; it holds the 2CylinderEngine at 0.006
/// scale and a floor seen at grazing angles, where a position rebuilt on the view ray
/// departs most from the interpolated one. Twice the measured, like the others.
const GALLERY_BOUND: f32 = 2.5e-2;

#[test]
fn packed_gbuffer_error_on_every_shipped_scene() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut files: Vec<_> = std::fs::read_dir(&root)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    files.push(root.join("cornell_box/scene.gltf"));
    files.sort();
    assert!(files.len() >= 8, "{files:?}");
    let mut r = renderer();
    let mut report = Vec::new();
    for path in &files {
        let mut s = scene::load(path).unwrap().scene;
        s.add_headlight_if_unlit();
        let t = std::time::Instant::now();
        let reference = render_file(&mut r, "tiled_deferred_transparent.ron", &s, W, H);
        let packed = render_file(&mut r, "tiled_deferred_packed.ron", &s, W, H);
        assert_eq!(packed.image.len(), reference.image.len());
        assert_eq!(reference.image.len(), (W * H) as usize);
        let peak = reference
            .image
            .iter()
            .flat_map(|p| p[..3].to_vec())
            .fold(0.0f32, f32::max);
        assert!(peak > 0.0, "{}: black", path.display());
        let mut worst = 0.0f32;
        for (a, b) in packed.image.iter().zip(&reference.image) {
            for ch in 0..3 {
                let d = (a[ch] - b[ch]).abs() / b[ch].abs().max(1e-3 * peak);
                assert!(!d.is_nan(), "{}: NaN", path.display());
                worst = worst.max(d);
            }
        }
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        println!(
            "{name:24} worst {worst:.3e} ({} lights, {:.1} s)",
            s.lights.len(),
            t.elapsed().as_secs_f64()
        );
        report.push((name, worst));
    }
    let bound = |name: &str| {
        if name == "gallery.ron" {
            GALLERY_BOUND
        } else {
            BOUND
        }
    };
    let bad: Vec<_> = report.iter().filter(|(n, w)| *w > bound(n)).collect();
    assert!(
        bad.is_empty(),
        "above {BOUND:e} ({GALLERY_BOUND:e} for the gallery): {bad:?}"
    );
}
