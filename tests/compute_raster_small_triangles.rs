//! The compute rasterizer's direct paths for small triangles (setup covers a fan triangle
//! of at most 16 pixels itself, and lists the blocks of one within 2×2 blocks without a
//! tile entry or bin): finely tessellated spheres, far and near, against the hardware
//! prepass and bit for bit against the tiled path alone (the test hook's `direct=0`), the
//! paths' counters, their list-full fallbacks, and alpha-masked small triangles.

mod common;
use common::compute_raster::*;
use common::textured::checker;
use common::*;
use glam::{Vec2, Vec3};
use lightgraph::scene::{AlphaMode, Mesh, Scene, SurfaceMaterial};
use std::sync::Arc;

/// A UV sphere, `segments` around and `rings` from pole to pole, counter-clockwise seen
/// from outside (as `MeshBuilder::cylinder`), uv = (around, up).
fn sphere(
    name: &str,
    centre: Vec3,
    radius: f32,
    segments: u32,
    rings: u32,
    material: usize,
) -> Mesh {
    let mut m = Mesh {
        name: name.into(),
        material,
        ..Default::default()
    };
    for r in 0..=rings {
        let lat = std::f32::consts::PI * (r as f32 / rings as f32 - 0.5);
        for s in 0..=segments {
            let a = std::f32::consts::TAU * s as f32 / segments as f32;
            let n = Vec3::new(lat.cos() * a.cos(), lat.sin(), -lat.cos() * a.sin());
            m.positions.push(centre + n * radius);
            m.normals.push(n);
            m.uvs.push(Vec2::new(
                s as f32 / segments as f32,
                r as f32 / rings as f32,
            ));
            m.tangents
                .push(Vec3::new(-a.sin(), 0.0, -a.cos()).extend(1.0));
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let a = r * row + s;
            m.indices
                .extend([a, a + 1, a + row + 1, a, a + row + 1, a + row]);
        }
    }
    m
}

/// A wall filling the view far behind (large triangles: the tiled path).
fn wall(material: usize) -> Mesh {
    cuboid(
        "wall",
        Vec3::new(-80.0, -50.0, -31.0),
        Vec3::new(80.0, 50.0, -30.0),
        material,
        false,
    )
}

const SIZE: (u32, u32) = (192, 108);

/// At 192×108 (a 90° vertical field of view: 54 pixels per unit at distance 1): a sphere
/// of 4 pixels' radius in 1,600 sub-pixel triangles, one of 15 pixels in 576 triangles of
/// about 4×4 pixels (thinner at the poles), one of 22 pixels in 144 of about 11×11, a
/// double-sided one cut by the frame's edge (clipped: several fan triangles a thread),
/// before the wall.
fn spheres_scene() -> Scene {
    scene(
        vec![
            wall(0),
            sphere("far", Vec3::new(-6.0, 3.0, -20.0), 1.5, 40, 20, 1),
            sphere("middle", Vec3::new(0.0, 0.0, -7.0), 2.0, 24, 12, 1),
            sphere("near", Vec3::new(5.0, -1.0, -5.0), 2.0, 12, 6, 2),
            sphere("edge", Vec3::new(-14.0, -3.0, -8.0), 1.5, 32, 16, 3),
        ],
        vec![
            lambert("grey", Vec3::splat(0.5)),
            lambert("red", Vec3::X),
            lambert("green", Vec3::Y),
            double_sided("blue", Vec3::Z),
        ],
        camera(0.1),
    )
}

/// Every path at once: the image against the hardware prepass and bit for bit against the
/// tiled path alone; each direct path taken, and the fan triangles accounted for (each
/// small one is a record less); the list-full fallbacks exact and counted.
#[test]
fn small_triangles_take_the_direct_paths_exactly() {
    if !has_atomics() {
        return;
    }
    let s = spheres_scene();
    let (w, h) = SIZE;
    let (px, report) = rasterize_limited(&s, w, h, "");
    let d = diff(&s, &px);
    eprintln!("direct paths: {d:?}, {report:?}");
    assert_eq!(d.covered, d.pixels, "the wall fills the frame: {d:?}");
    assert_matches("spheres", &d);
    assert_eq!(report.serial(), 0, "{report:?}");
    assert!(report.small_triangles > 500, "{report:?}");
    assert!(report.block_triangles > 50, "{report:?}");
    // The wall's and the near sphere's larger triangles still list tiles.
    assert!(
        report.records > report.block_triangles && report.tiles > 0,
        "{report:?}"
    );
    // Each sphere shows (ids by mesh: the wall's 12, then 1,600, 576, 144, 1,024).
    let shown = |lo: u32, hi: u32| px.iter().filter(|p| (lo..hi).contains(&p.id)).count();
    let starts = [12, 1612, 2188, 2332, 3356];
    for k in 0..4 {
        assert!(shown(starts[k], starts[k + 1]) > 20, "sphere {k} shows");
    }

    let (tiled, tiled_report) = rasterize_limited(&s, w, h, "direct=0");
    eprintln!("tiled path alone: {tiled_report:?}");
    assert_eq!(
        tiled_report.small_triangles + tiled_report.block_triangles,
        0
    );
    assert_eq!(
        bit_differences(&px, &tiled),
        0,
        "the direct paths change the image"
    );
    // Without the direct paths every fan triangle has a record; with them the small ones
    // have none (and those within 2×2 blocks whose edges reach no pixel centre neither).
    assert!(
        tiled_report.records >= report.records + report.small_triangles,
        "{tiled_report:?} vs {report:?}"
    );

    // The small path's threshold moved (the hook's `small=N`): no small path (its
    // triangles listed by block or tile instead), and four times the pixels.
    for (limits, fewer) in [("small=0", true), ("small=64", false)] {
        let (moved, r) = rasterize_limited(&s, w, h, limits);
        eprintln!("{limits}: {r:?}");
        let shifted = if fewer {
            r.small_triangles == 0 && r.block_triangles > report.block_triangles
        } else {
            r.small_triangles > report.small_triangles
        };
        assert!(shifted, "{limits}: {r:?}");
        assert_eq!(bit_differences(&px, &moved), 0, "{limits}");
    }

    // No room for records: the small triangles are drawn as before, every other fan
    // triangle by its setup thread, counted. No room for blocks: setup's and bin's
    // blocks drawn by the thread that found the list full.
    for limits in ["records=0", "blocks=20"] {
        let (full, r) = rasterize_limited(&s, w, h, limits);
        eprintln!("{limits}: {r:?}");
        let counted = match limits {
            "records=0" => {
                r.serial_triangles == report.records
                    && r.small_triangles == report.small_triangles
                    && r.block_triangles == report.block_triangles
            }
            _ => r.serial_blocks == report.blocks - 20 && r.blocks == 20,
        };
        assert!(counted, "{limits}: {r:?}");
        assert_eq!(bit_differences(&px, &full), 0, "{limits}");
    }
}

/// A sphere of small triangles in an alpha-masked material (the checker's
/// alpha stripes, a quarter of the way around each) before an opaque wall of large
/// triangles: the masked run's setup covers the small triangles itself and alpha-tests
/// them as every path does; the same bits as the tiled path alone, and the prepass's
/// alpha test.
#[test]
fn masked_small_triangles_are_alpha_tested_in_setup() {
    if !has_atomics() {
        return;
    }
    let tex = Arc::new(checker("stripes", 64, 8, [230, 120, 40], [40, 90, 200]));
    let masked = SurfaceMaterial {
        name: "masked".into(),
        base_color_texture: Some(tex),
        alpha_mode: AlphaMode::Mask(0.5),
        ..Default::default()
    };
    let mut s = scene(
        vec![
            wall(0),
            sphere("masked", Vec3::new(0.0, 0.0, -12.0), 2.5, 48, 24, 1),
        ],
        vec![lambert("grey", Vec3::splat(0.5)), masked],
        camera(0.1),
    );
    let (w, h) = SIZE;
    let (px, report) = rasterize_limited(&s, w, h, "");
    let d = diff(&s, &px);
    eprintln!("masked: {d:?}, {report:?}");
    assert_matches("masked sphere", &d);
    // The wall's 12 triangles are all large: every small one is the masked run's.
    assert!(report.small_triangles > 500, "{report:?}");
    let (tiled, tiled_report) = rasterize_limited(&s, w, h, "direct=0");
    assert_eq!(tiled_report.small_triangles, 0);
    assert_eq!(bit_differences(&px, &tiled), 0);
    // The stripes cut pixels out that the sphere covers when opaque, and keep others.
    s.materials[1].alpha_mode = AlphaMode::Opaque;
    let opaque = rasterize(&s, w, h);
    let sphere_pixels = |p: &[Pixel]| p.iter().filter(|p| p.id >= 12 && p.id != u32::MAX).count();
    let (kept, solid) = (sphere_pixels(&px), sphere_pixels(&opaque));
    eprintln!("masked sphere: {kept} of {solid} pixels kept");
    assert!(
        solid > 300 && kept > 100 && kept + 100 < solid,
        "{kept} of {solid}"
    );
}

/// Khronos's MetalRoughSpheresNoTextures (a million triangles, the gallery's spheres) at
/// 320×180, its fitted camera: every fan triangle with a pixel is drawn by its setup
/// thread, and the frame is the tiled path's bit for bit and the hardware prepass's in
/// coverage and ids.
///
/// Depth: ten of its 7,766 covered pixels differ from the prepass by more than
/// `DEPTH_TOLERANCE` (lavapipe), the worst by 3.8e-5, and the tiled path alone gives
/// the same bits, so this is the rasterizer's depth plane, not a path's: the plane comes
/// from the unsnapped vertices and divides by the triangle's area, which for the
/// spheres' sub-pixel slivers is tiny, so its rounding differs from the raster
/// pipeline's own setup. Checked here as counted: at most one covered pixel in 500
/// past DEPTH_TOLERANCE, none past 1e-4.
#[test]
fn metal_rough_spheres_draw_in_setup() {
    if !has_atomics() {
        return;
    }
    let s =
        load("tests/assets/khronos/MetalRoughSpheresNoTextures/MetalRoughSpheresNoTextures.gltf");
    let (w, h) = (320, 180);
    let (px, report) = rasterize_limited(&s, w, h, "");
    let (tiled, tiled_report) = rasterize_limited(&s, w, h, "direct=0");
    eprintln!("direct paths: {report:?}\ntiled path alone: {tiled_report:?}");
    assert_eq!(bit_differences(&px, &tiled), 0);
    assert_eq!(report.serial() + tiled_report.serial(), 0);
    // Here every fan triangle that holds a pixel centre is small.
    assert!(report.small_triangles > 40_000, "{report:?}");
    assert_eq!(
        tiled_report.records,
        report.records + report.small_triangles
    );
    let d = diff(&s, &px);
    let off = px
        .iter()
        .filter(|p| p.id != u32::MAX && p.hw < 1.0 && (p.cr - p.hw).abs() > DEPTH_TOLERANCE)
        .count();
    eprintln!("{d:?}, {off} pixels past the depth tolerance");
    assert!(d.covered > d.pixels / 10, "{d:?}");
    assert_eq!(d.bad_ids, 0, "{d:?}");
    assert!(d.coverage <= d.pixels / MAX_COVERAGE_DIFF, "{d:?}");
    assert!(off <= d.covered / 500 && d.depth <= 1e-4, "{d:?}, {off}");
}
