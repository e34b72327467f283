//! Shared test helpers: small analytic scenes, a deterministic PRNG, rendering a graph
//! file on the real adapter (lavapipe on CI).
#![allow(dead_code)]

pub mod compute_raster;
pub mod cornell;
pub mod glass;
pub mod msaa;
pub mod shadow_jobs;
pub mod textured;

use glam::{Vec2, Vec3, Vec4};
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{FrameResult, PreparedFrame, RenderError, Renderer, SceneGpu};
use lightgraph::scene::geometry::MeshBuilder;
use lightgraph::scene::{Camera, Light, LightShape, Mesh, Scene, SurfaceMaterial};
use lightgraph::shader::ShaderLibrary;
use std::path::Path;
use std::sync::{Mutex, OnceLock};

/// One device for the whole test binary (opening lavapipe is slow); tests take turns.
pub fn renderer() -> std::sync::MutexGuard<'static, Renderer> {
    static R: OnceLock<Mutex<Renderer>> = OnceLock::new();
    R.get_or_init(|| Mutex::new(Renderer::headless().expect("a wgpu adapter (lavapipe on CI)")))
        .lock()
        .unwrap_or_else(|e| e.into_inner())
}

/// SplitMix64: fixed sequences that never change with a crate version.
pub struct Rng(pub u64);
impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e3779b97f4a7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        z ^ (z >> 31)
    }
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }
    pub fn vec3(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        Vec3::new(
            self.range(lo.x, hi.x),
            self.range(lo.y, hi.y),
            self.range(lo.z, hi.z),
        )
    }
}

/// The ray-cast shadow tests' room: a floor, five boxes of random size and place (from
/// `rng`), a floating slab and a standing column; floor material 0, the rest 1.
pub fn shadow_room(rng: &mut Rng) -> Vec<Mesh> {
    let mut meshes = vec![cuboid(
        "floor",
        Vec3::new(-8.0, -1.0, -12.0),
        Vec3::new(8.0, 0.0, 4.0),
        0,
        false,
    )];
    for i in 0..5 {
        let p = rng.vec3(Vec3::new(-5.0, 0.0, -9.0), Vec3::new(5.0, 0.0, 0.0));
        let s = rng.vec3(Vec3::new(0.4, 0.5, 0.4), Vec3::new(1.2, 2.5, 1.2));
        meshes.push(cuboid(&format!("box{i}"), p, p + s, 1, false));
    }
    meshes.push(cuboid(
        "slab",
        Vec3::new(-2.0, 2.5, -5.0),
        Vec3::new(1.0, 2.7, -3.0),
        1,
        false,
    ));
    let mut cyl = MeshBuilder::new("column", 1);
    cyl.cylinder(Vec3::new(2.5, 0.0, -2.0), 0.6, 3.0, 24, 4);
    meshes.push(cyl.build());
    meshes
}

/// An axis-aligned box as 12 triangles with outward normals (or inward when `inside`).
pub fn cuboid(name: &str, lo: Vec3, hi: Vec3, material: usize, inside: bool) -> Mesh {
    let mut m = Mesh {
        name: name.into(),
        material,
        ..Default::default()
    };
    let c = (lo + hi) * 0.5;
    let h = (hi - lo) * 0.5;
    for axis in [
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
    ] {
        let center = c + axis * h;
        let n = if inside { -axis } else { axis };
        // u x v = n makes the quad counter-clockwise seen from the side n points to.
        let u = if axis.x != 0.0 { Vec3::Z } else { Vec3::X };
        let v = n.cross(u);
        let (su, sv) = ((u * h).length(), (v * h).length());
        let base = m.positions.len() as u32;
        for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            m.positions.push(center + u * su * a + v * sv * b);
            m.normals.push(n);
            m.uvs.push(Vec2::new((a + 1.0) / 2.0, (b + 1.0) / 2.0));
            m.tangents.push(u.extend(1.0));
        }
        m.indices
            .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    m
}

pub fn lambert(name: &str, albedo: Vec3) -> SurfaceMaterial {
    SurfaceMaterial {
        name: name.into(),
        base_color: albedo.extend(1.0),
        ..Default::default()
    }
}

/// A floor, a few boxes at different depths and a far back wall, with `n` random lights.
pub fn random_scene(n: usize, seed: u64) -> Scene {
    let mut rng = Rng(seed);
    let mut meshes = vec![
        cuboid(
            "floor",
            Vec3::new(-20.0, -1.0, -40.0),
            Vec3::new(20.0, 0.0, 5.0),
            0,
            false,
        ),
        cuboid(
            "back",
            Vec3::new(-20.0, 0.0, -41.0),
            Vec3::new(20.0, 15.0, -40.0),
            0,
            false,
        ),
    ];
    for i in 0..6 {
        let p = rng.vec3(Vec3::new(-8.0, 0.0, -30.0), Vec3::new(8.0, 0.0, -2.0));
        let s = rng.vec3(Vec3::splat(0.5), Vec3::new(2.0, 4.0, 2.0));
        meshes.push(cuboid(
            &format!("box{i}"),
            p - Vec3::new(s.x, 0.0, s.z),
            p + s,
            1,
            false,
        ));
    }
    let lights = (0..n)
        .map(|_| {
            random_light(
                &mut rng,
                Vec3::new(-15.0, 0.0, -38.0),
                Vec3::new(15.0, 8.0, 4.0),
                1.0,
                6.0,
            )
        })
        .collect();
    Scene {
        name: format!("random{n}"),
        meshes,
        materials: vec![
            lambert("grey", Vec3::splat(0.7)),
            lambert("orange", Vec3::new(0.9, 0.5, 0.2)),
        ],
        lights,
        camera: Camera {
            eye: Vec3::new(0.0, 3.0, 6.0),
            target: Vec3::new(0.0, 1.0, -10.0),
            up: Vec3::Y,
            fov_y: 60f32.to_radians(),
            near: 0.1,
            far: 100.0,
        },
        output_size: None,
        ambient: Vec3::ZERO,
        ..Default::default()
    }
}

/// A random point or spot light (half and half) in a box.
pub fn random_light(rng: &mut Rng, lo: Vec3, hi: Vec3, rmin: f32, rmax: f32) -> Light {
    let position = rng.vec3(lo, hi);
    let color = rng.vec3(Vec3::splat(0.2), Vec3::ONE);
    let range = rng.range(rmin, rmax);
    let mut l = Light::point(position, range, color, rng.range(1.0, 10.0));
    if rng.f32() < 0.5 {
        let direction = rng
            .vec3(Vec3::splat(-1.0), Vec3::splat(1.0))
            .normalize_or(Vec3::NEG_Y);
        let outer = rng.range(0.2, 1.4);
        l.shape = LightShape::Spot {
            direction,
            inner_angle: outer * rng.f32(),
            outer_angle: outer,
        };
    }
    l
}

/// [`random_scene`]'s room with a thin near pillar in front of the far wall and `lights`
/// random lights spread through depth: depth discontinuities in most tiles.
pub fn pillar_scene(lights: usize) -> Scene {
    let mut s = random_scene(0, 3);
    s.meshes.push(cuboid(
        "pillar",
        Vec3::new(-0.3, 0.0, 2.0),
        Vec3::new(0.3, 6.0, 2.6),
        1,
        false,
    ));
    let mut rng = Rng(11);
    s.lights = (0..lights)
        .map(|_| {
            random_light(
                &mut rng,
                Vec3::new(-6.0, 0.0, -40.0),
                Vec3::new(6.0, 6.0, 3.0),
                0.5,
                3.0,
            )
        })
        .collect();
    s
}

/// `graph_text` with its (first) `LightCulling(...)` kind replaced by `kind`, whatever
/// parameters the file gives it.
pub fn with_culling(graph_text: &str, kind: &str) -> String {
    let start = graph_text
        .find("LightCulling(")
        .expect("the graph has a LightCulling pass");
    let mut depth = 0;
    for (i, c) in graph_text[start..].char_indices() {
        match c {
            '(' => depth += 1,
            ')' => {
                depth -= 1;
                if depth == 0 {
                    let end = start + i + 1;
                    return format!("{}{kind}{}", &graph_text[..start], &graph_text[end..]);
                }
            }
            _ => {}
        }
    }
    panic!("unbalanced LightCulling(...)")
}

/// The graph file `name` with its culling pass's kind replaced by `kind`.
pub fn graph_with_culling(name: &str, kind: &str) -> String {
    with_culling(&std::fs::read_to_string(graph_path(name)).unwrap(), kind)
}

/// Khronos sample model `name` (tests/assets/khronos/`name`/`name`.gltf), loaded.
pub fn khronos_model(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/assets/khronos")
        .join(name)
        .join(format!("{name}.gltf"));
    lightgraph::scene::load(&path)
        .expect("a Khronos sample model")
        .scene
}

/// The pipelines a fresh renderer (nothing from a pipeline cache) builds from `shader`
/// (e.g. `visibility/visibility_shading.wgsl`) to prepare `graph_text` for `scene` at
/// 64×48: each one's description (`PipelineKey::describe`: shader, defines, material).
pub fn pipelines_built_from(shader: &str, graph_text: &str, scene: &Scene) -> Vec<String> {
    let mut fresh = Renderer::headless().expect("a wgpu adapter");
    let prepared = prepare_text(&mut fresh, graph_text, scene, 64, 48, false).expect("prepare");
    prepared
        .stats()
        .pipelines_built
        .iter()
        .filter(|l| l.starts_with(shader))
        .cloned()
        .collect()
}

pub fn graph_path(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("graphs")
        .join(name)
}

/// The text of graphs/`name`.
pub fn graph_text(name: &str) -> String {
    std::fs::read_to_string(graph_path(name)).unwrap_or_else(|e| panic!("graphs/{name}: {e}"))
}

/// Compiles graph text for the scene and renders one frame with light statistics.
pub fn render_text(
    r: &mut Renderer,
    graph_text: &str,
    scene: &Scene,
    width: u32,
    height: u32,
) -> FrameResult {
    render_text_with(r, graph_text, scene, width, height, true)
}

/// `render_text` with light statistics on or off (they test every light at every pixel:
/// with tens of thousands of lights on lavapipe, most of a frame's time).
pub fn render_text_with(
    r: &mut Renderer,
    graph_text: &str,
    scene: &Scene,
    width: u32,
    height: u32,
    light_stats: bool,
) -> FrameResult {
    let prepared = prepare_text(r, graph_text, scene, width, height, light_stats).expect("prepare");
    prepared.render(r).expect("render")
}

/// A valid graph's text compiled for `scene` and prepared at `width`×`height` (light
/// statistics where asked and the graph has forward shading): what `render_text_with`
/// runs, for tests that read the frame's resources or expect prepare to refuse.
pub fn prepare_text(
    r: &mut Renderer,
    graph_text: &str,
    scene: &Scene,
    width: u32,
    height: u32,
    light_stats: bool,
) -> Result<PreparedFrame, RenderError> {
    let checked = graph::check_text(Path::new("<test>"), graph_text, &ShaderLibrary::builtin())
        .expect("valid graph");
    let size = FrameSize {
        width,
        height,
        lights: scene.lights.len() as u32,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, scene).expect("materials");
    let stats = light_stats && compiled.has_forward_shading();
    r.prepare(compiled, scene, &gpu, size, stats)
}

/// `graph_file` (under graphs/) prepared for `scene`, uploaded with light buffers holding
/// room for `capacity` lights (at least the scene's); with the scene's buffers, which light
/// updates and mesh edits take.
pub fn prepare_file_with_gpu(
    r: &mut Renderer,
    graph_file: &str,
    scene: &Scene,
    width: u32,
    height: u32,
    capacity: u32,
) -> (PreparedFrame, SceneGpu) {
    let text = std::fs::read_to_string(graph_path(graph_file)).unwrap();
    prepare_text_with_gpu(r, graph_file, &text, scene, width, height, capacity)
}

/// [`prepare_file_with_gpu`] for a graph given as text (`name` for its errors).
pub fn prepare_text_with_gpu(
    r: &mut Renderer,
    name: &str,
    text: &str,
    scene: &Scene,
    width: u32,
    height: u32,
    capacity: u32,
) -> (PreparedFrame, SceneGpu) {
    let checked =
        graph::check_text(Path::new(name), text, &ShaderLibrary::builtin()).expect("valid graph");
    let gpu = SceneGpu::upload_with_light_capacity(&r.ctx.device, &r.ctx.queue, scene, capacity)
        .expect("materials");
    let size = FrameSize {
        width,
        height,
        lights: gpu.light_capacity,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    let prepared = r
        .prepare(compiled, scene, &gpu, size, false)
        .expect("prepare");
    (prepared, gpu)
}

pub fn render_file(
    r: &mut Renderer,
    graph: &str,
    scene: &Scene,
    width: u32,
    height: u32,
) -> FrameResult {
    let text = std::fs::read_to_string(graph_path(graph)).unwrap();
    render_text(r, &text, scene, width, height)
}

/// Largest absolute difference, relative to the brightest reference pixel.
/// Pixels of two images of one size whose bits differ in any channel.
pub fn pixels_differing_in_bits(a: &[[f32; 4]], b: &[[f32; 4]]) -> usize {
    assert_eq!(a.len(), b.len(), "image sizes");
    a.iter()
        .zip(b)
        .filter(|(a, b)| a.map(f32::to_bits) != b.map(f32::to_bits))
        .count()
}

pub fn max_rel_diff(a: &[[f32; 4]], b: &[[f32; 4]]) -> (f32, usize) {
    // Without this an empty or truncated image would pass as identical.
    assert_eq!(a.len(), b.len(), "images of different sizes");
    assert!(!b.is_empty(), "empty images");
    let peak = b
        .iter()
        .flat_map(|p| p[..3].iter().copied())
        .fold(1e-6f32, f32::max);
    let mut worst = (0.0f32, 0);
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        for c in 0..3 {
            let d = (x[c] - y[c]).abs() / peak.max(y[c].abs());
            if d > worst.0 || d.is_nan() {
                worst = (d, i);
            }
        }
    }
    worst
}

pub fn vec4_unused() -> Vec4 {
    Vec4::ZERO
}
