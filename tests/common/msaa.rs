//! MSAA test helpers shared by tests/msaa.rs (Forward+) and tests/deferred_msaa.rs: the
//! scenes with edges, the side-by-side sample layout of a graph, the counts the adapter
//! offers.

use super::{cuboid, graph_path, lambert};
use glam::{Vec3, Vec4};
use lightgraph::render::supported_sample_counts;
use lightgraph::scene::{Camera, Light, Scene, SurfaceMaterial};

/// The frame the MSAA tests render (the sub-pixel bars are laid out for it).
pub const MSAA_W: u32 = 96;
pub const MSAA_H: u32 = 54;
pub const MSAA_RESOLVE: &str = r#"Fullscreen(shader: "msaa/resolve.wgsl")"#;
pub const MSAA_OUTPUT: &str = r#"Texture(name: "hdr", format: Rgba32Float, size: Output)"#;

pub fn graph_file(name: &str) -> String {
    std::fs::read_to_string(graph_path(name)).unwrap()
}

/// `text` at `samples` samples, its resolve replaced by the side-by-side sample layout
/// (a `samples`·W × H output).
pub fn samples_graph(text: &str, samples: u32, w: u32, h: u32) -> String {
    assert!(text.contains(MSAA_RESOLVE) && text.contains(MSAA_OUTPUT));
    text.replace(MSAA_RESOLVE, r#"Fullscreen(shader: "msaa/samples.wgsl")"#)
        .replace(
            MSAA_OUTPUT,
            &format!(
                r#"Texture(name: "hdr", format: Rgba32Float, size: Fixed({}, {h}))"#,
                samples * w
            ),
        )
        .replace("samples: 4", &format!("samples: {samples}"))
}

/// Sample counts of `counts` the adapter offers for both MSAA formats.
pub fn offered(r: &lightgraph::render::Renderer, counts: &[u32]) -> Vec<u32> {
    let depth = supported_sample_counts(
        wgpu::TextureFormat::Depth32Float,
        &r.ctx.adapter,
        &r.ctx.device,
    );
    let color = supported_sample_counts(
        wgpu::TextureFormat::Rgba32Float,
        &r.ctx.adapter,
        &r.ctx.device,
    );
    counts
        .iter()
        .copied()
        .filter(|n| depth.contains(n) && color.contains(n))
        .collect()
}

/// One short vertical bar a third of a pixel wide in each 16×16 tile, each at its own
/// depth and sub-pixel offset, before a far wall, each lit by one short-range light just
/// in front of it: a bar covers some of a pixel's samples and not others, so culling that
/// reads fewer samples than all drops the light of a bar it did not see.
pub fn thin_bars_scene() -> Scene {
    let (w, h) = (MSAA_W, MSAA_H);
    let mut meshes = vec![cuboid(
        "wall",
        Vec3::new(-80.0, -50.0, -61.0),
        Vec3::new(80.0, 50.0, -60.0),
        0,
        false,
    )];
    let mut lights = Vec::new();
    // With a 60° vertical field of view over MSAA_H = 54 pixels a pixel is 0.021383 × depth wide.
    let (tiles_x, tiles_y) = (w / 16, h.div_ceil(16));
    for k in 0..tiles_x * tiles_y {
        let (tx, ty) = (k % tiles_x, k / tiles_x);
        let z = 4.0 + 1.5 * k as f32;
        let px = 0.021383 * z;
        let offset = (k as f32 * 0.37).fract();
        let x = (16.0 * tx as f32 + 8.0 + offset - w as f32 / 2.0) * px;
        let y = (h as f32 / 2.0 - (16.0 * ty as f32 + 8.0).min(h as f32 - 6.0)) * px;
        meshes.push(cuboid(
            &format!("bar{k}"),
            Vec3::new(x, y - 5.0 * px, -z - 0.02),
            Vec3::new(x + px / 3.0, y + 5.0 * px, -z + 0.02),
            1,
            false,
        ));
        lights.push(Light::point(Vec3::new(x, y, -z + 0.3), 0.6, Vec3::ONE, 5.0));
    }
    Scene {
        name: "thin_bars".into(),
        meshes,
        materials: vec![
            lambert("grey", Vec3::splat(0.6)),
            lambert("white", Vec3::splat(0.9)),
        ],
        lights,
        camera: Camera {
            eye: Vec3::ZERO,
            target: Vec3::new(0.0, 0.0, -1.0),
            up: Vec3::Y,
            fov_y: 60f32.to_radians(),
            near: 0.1,
            far: 100.0,
        },
        ..Default::default()
    }
}

pub fn emissive(name: &str, rgb: Vec3) -> SurfaceMaterial {
    SurfaceMaterial {
        name: name.into(),
        base_color: Vec4::new(0.0, 0.0, 0.0, 1.0),
        emissive: rgb,
        ..Default::default()
    }
}

/// Flat emissive boxes on black, no lights: every pixel's true colour is a coverage-
/// weighted mean of a few flat colours, so edges are the only thing MSAA changes.
pub fn flat_scene() -> Scene {
    let meshes = vec![
        cuboid(
            "a",
            Vec3::new(-3.0, -1.5, -9.0),
            Vec3::new(0.5, 1.0, -8.0),
            0,
            false,
        ),
        cuboid(
            "b",
            Vec3::new(-0.7, -0.4, -6.0),
            Vec3::new(2.2, 2.0, -5.0),
            1,
            false,
        ),
        cuboid(
            "c",
            Vec3::new(-2.0, -3.0, -12.0),
            Vec3::new(4.0, -1.0, -11.0),
            2,
            false,
        ),
    ];
    Scene {
        name: "flat".into(),
        meshes,
        materials: vec![
            emissive("red", Vec3::new(1.0, 0.1, 0.1)),
            emissive("green", Vec3::new(0.1, 1.0, 0.2)),
            emissive("blue", Vec3::new(0.2, 0.3, 1.0)),
        ],
        camera: Camera {
            // Slightly rolled and off-axis, so no edge runs along a pixel row.
            eye: Vec3::new(0.4, 0.3, 0.0),
            target: Vec3::new(0.0, 0.0, -8.0),
            up: Vec3::new(0.15, 1.0, 0.0),
            fov_y: 50f32.to_radians(),
            near: 0.1,
            far: 50.0,
        },
        ..Default::default()
    }
}
