//! The compute rasterizer (`ComputeRaster`) beside the hardware depth prepass in one
//! frame, for tests/compute_raster*.rs: both depths and the compute ids per pixel, the
//! pass's report, what the two differ in, and small scenes seen by a 90° camera.

use super::lambert;
use super::render_text;
use super::renderer;
use glam::{Vec2, Vec3};
use lightgraph::render::RasterReport;
use lightgraph::scene::{AlphaMode, Camera, Light, Mesh, Scene};
use std::path::Path;

pub const NO_TRIANGLE: u32 = u32::MAX;

/// Both rasterizers into one image: compute depth, prepass depth, the id's two halves.
pub const COMPARE: &str = r#"Graph(
    name: "compute_raster_compare",
    resources: [
        Texture(name: "depth_cr", format: Depth32Float),
        Texture(name: "depth_hw", format: Depth32Float),
        Texture(name: "visibility", format: R32Uint),
        Texture(name: "out", format: Rgba32Float),
        Import(name: "geometry", from: Geometry),
        Import(name: "vertices", from: Vertices),
        Import(name: "triangles", from: Triangles),
        Import(name: "material_triangles", from: MaterialTriangles),
    ],
    passes: [
        Pass(name: "cr", kind: ComputeRaster, reads: ["vertices", "triangles", "material_triangles"], writes: ["depth=depth_cr", "visibility"]),
        Pass(name: "pre", kind: DepthPrepass, reads: ["geometry"], writes: ["depth_hw"]),
        Pass(name: "compare", kind: Fullscreen(shader: "visibility/compute_raster_compare.wgsl"), reads: ["depth_cr", "depth_hw", "visibility"], writes: ["out"]),
    ],
    output: "out",
)"#;

/// `TransparentDepth` both ways, into `transparent_cr` (R32Float: the compute rasterizer)
/// and `transparent_hw` (Depth32Float: the raster units), after a forward frame that
/// gives the graph its output (their passes kept by `side_effects`; last, so no later
/// pass reuses their memory).
pub const TRANSPARENT_COMPARE: &str = r#"Graph(
    name: "transparent_depth_compare",
    resources: [
        Texture(name: "depth", format: Depth32Float),
        Texture(name: "transparent_cr", format: R32Float),
        Texture(name: "transparent_hw", format: Depth32Float),
        Texture(name: "hdr", format: Rgba32Float),
        Import(name: "geometry", from: Geometry),
        Import(name: "light_geometry", from: LightGeometry),
        Import(name: "light_properties", from: LightProperties),
    ],
    passes: [
        Pass(name: "pre", kind: DepthPrepass, reads: ["geometry"], writes: ["depth"]),
        Pass(name: "shade", kind: ForwardShading(lights: AllLights), reads: ["geometry", "depth", "light_geometry", "light_properties"], writes: ["hdr"]),
        Pass(name: "cr", kind: TransparentDepth, reads: ["geometry"], writes: ["depth=transparent_cr"]),
        Pass(name: "hw", kind: TransparentDepth, reads: ["geometry"], writes: ["depth=transparent_hw"]),
    ],
    output: "hdr",
    side_effects: ["cr", "hw"],
)"#;

pub struct Pixel {
    pub cr: f32,
    pub hw: f32,
    pub id: u32,
}

/// What the two rasterizers differ in over a frame.
#[derive(Debug, Default)]
pub struct Diff {
    pub pixels: usize,
    pub covered: usize,
    /// Covered by one rasterizer only.
    pub coverage: usize,
    /// Largest depth difference where both cover.
    pub depth: f32,
    /// Ids past the scene's triangles, or a depth without an id.
    pub bad_ids: usize,
}

pub fn rasterize(scene: &Scene, width: u32, height: u32) -> Vec<Pixel> {
    rasterize_limited(scene, width, height, "").0
}

/// The compute rasterizer's test hook (`compute_raster.rs`): list capacities and
/// workgroups per dispatch dimension, read when the pass is prepared.
pub const TEST_LIMITS: &str = "LIGHTGRAPH_COMPUTE_RASTER_TEST_LIMITS";

/// Sets the test hook while alive.
pub struct Limits;
impl Limits {
    pub fn set(limits: &str) -> Self {
        std::env::set_var(TEST_LIMITS, limits);
        Limits
    }
}
impl Drop for Limits {
    fn drop(&mut self) {
        std::env::remove_var(TEST_LIMITS);
    }
}

/// As `rasterize`, under the test hook's `limits` ("" for none), with the pass's report.
pub fn rasterize_limited(
    scene: &Scene,
    width: u32,
    height: u32,
    limits: &str,
) -> (Vec<Pixel>, RasterReport) {
    // The renderer's lock keeps the other tests of this binary from preparing while the
    // variable is set (dropped after `_limits`).
    let mut r = renderer();
    let _limits = Limits::set(limits);
    let out = render_text(&mut r, COMPARE, scene, width, height);
    assert_eq!(out.image.len(), (width * height) as usize);
    assert_eq!(out.rasters.len(), 1, "one ComputeRaster report");
    let px = out
        .image
        .iter()
        .map(|p| Pixel {
            cr: p[0],
            hw: p[1],
            id: p[2] as u32 | (p[3] as u32) << 16,
        })
        .collect();
    (px, out.rasters[0].clone())
}

/// Pixels whose compute depth bits or id differ between two runs.
pub fn bit_differences(a: &[Pixel], b: &[Pixel]) -> usize {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .filter(|(p, q)| p.cr.to_bits() != q.cr.to_bits() || p.id != q.id)
        .count()
}

pub fn triangles(scene: &Scene) -> u32 {
    scene
        .meshes
        .iter()
        .filter(|m| scene.materials[m.material].alpha_mode != AlphaMode::Blend)
        .map(|m| m.indices.len() as u32 / 3)
        .sum()
}

pub fn diff(scene: &Scene, px: &[Pixel]) -> Diff {
    let n = triangles(scene);
    let mut d = Diff {
        pixels: px.len(),
        ..Default::default()
    };
    for p in px {
        let cr = p.id != NO_TRIANGLE;
        let hw = p.hw < 1.0;
        d.bad_ids += (cr && p.id >= n) as usize + (!cr && p.cr != 1.0) as usize;
        if cr && hw {
            d.covered += 1;
            d.depth = d.depth.max((p.cr - p.hw).abs());
        } else if cr != hw {
            d.coverage += 1;
        }
    }
    d
}

pub fn load(rel: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    lightgraph::scene::load(&path).unwrap().scene
}

pub fn has_atomics() -> bool {
    let r = renderer();
    let ok = r
        .ctx
        .device
        .features()
        .contains(wgpu::Features::SHADER_INT64 | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX);
    if !ok {
        eprintln!(
            "!!!!! no 64-bit atomics on {}: skipped !!!!!",
            r.ctx.adapter_name()
        );
    }
    ok
}

/// Coverage may differ only where float rounding of a vertex's transform (the vertex
/// stage and this compute shader may contract multiply-adds differently) moves its
/// snapped 1/256-pixel position, which flips only pixel centres within 1/256 pixel of
/// an edge: at most one pixel in 5000 (lavapipe: none on every scene here). Depth where
/// both cover: the plane evaluated in another order, a few ulps of 1.0 (lavapipe: at
/// most 4.2e-7, cornell box).
pub const MAX_COVERAGE_DIFF: usize = 5000;
pub const DEPTH_TOLERANCE: f32 = 1e-6;

pub fn assert_matches(what: &str, d: &Diff) {
    assert_eq!(d.bad_ids, 0, "{what}: {d:?}");
    assert!(d.coverage <= d.pixels / MAX_COVERAGE_DIFF, "{what}: {d:?}");
    assert!(d.depth <= DEPTH_TOLERANCE, "{what}: {d:?}");
}

/// A camera at the origin looking down -Z with a 90° field of view: at distance d the
/// view spans [-d, d] in x and y (square frames).
pub fn camera(near: f32) -> Camera {
    Camera {
        eye: Vec3::ZERO,
        target: Vec3::NEG_Z,
        up: Vec3::Y,
        fov_y: 90f32.to_radians(),
        near,
        far: 100.0,
    }
}

pub fn scene(
    meshes: Vec<Mesh>,
    materials: Vec<lightgraph::scene::SurfaceMaterial>,
    camera: Camera,
) -> Scene {
    Scene {
        name: "compute_raster".into(),
        meshes,
        materials,
        lights: vec![Light::point(
            Vec3::new(0.0, 2.0, -3.0),
            20.0,
            Vec3::ONE,
            10.0,
        )],
        camera,
        output_size: None,
        ambient: Vec3::ZERO,
        ..Default::default()
    }
}

/// One triangle (normals towards +Z), material `material`.
pub fn triangle(name: &str, p: [Vec3; 3], material: usize) -> Mesh {
    Mesh {
        name: name.into(),
        material,
        positions: p.to_vec(),
        normals: vec![Vec3::Z; 3],
        uvs: vec![Vec2::ZERO; 3],
        tangents: vec![Vec3::X.extend(1.0); 3],
        indices: vec![0, 1, 2],
        ..Default::default()
    }
}

pub fn double_sided(name: &str, albedo: Vec3) -> lightgraph::scene::SurfaceMaterial {
    let mut m = lambert(name, albedo);
    m.double_sided = true;
    m
}
