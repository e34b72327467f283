//! The compute rasterizer's hardware fallback: on a device without its 64-bit atomics
//! (lavapipe has them, so the device here is opened with them left off,
//! `ContextOptions::disabled_features`) `ComputeRaster` draws with the hardware
//! visibility pass's draws, gives exactly `visibility_buffer.ron`'s depth, ids and image,
//! and the frame's report (and `lightgraph render`) says so; with the features, it says
//! nothing.

mod common;
use common::textured::*;
use common::*;
use lightgraph::gpu::{ContextOptions, GpuContext};
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{FrameResult, Renderer, SceneGpu};
use lightgraph::scene::Scene;
use lightgraph::shader::ShaderLibrary;
use std::path::Path;
use std::sync::{Mutex, MutexGuard, OnceLock};

const MASKED: wgpu::Features = wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX;
const NO_TRIANGLE: u32 = u32::MAX;

/// One device for this binary with the 64-bit atomic min left off (tests take turns).
fn masked_renderer() -> MutexGuard<'static, Renderer> {
    static R: OnceLock<Mutex<Renderer>> = OnceLock::new();
    R.get_or_init(|| {
        let options = ContextOptions {
            disabled_features: MASKED,
            ..Default::default()
        };
        Mutex::new(Renderer::headless_with(&options).expect("a wgpu adapter (lavapipe on CI)"))
    })
    .lock()
    .unwrap_or_else(|e| e.into_inner())
}

/// One frame of `graph` (text): the result and the bits of each texture in `read`.
fn render_reading(
    r: &mut Renderer,
    graph: &str,
    scene: &Scene,
    read: &[&str],
) -> Result<(FrameResult, Vec<Vec<u32>>), String> {
    let checked = graph::check_text(Path::new("<test>"), graph, &ShaderLibrary::builtin())
        .expect("valid graph");
    let size = FrameSize {
        width: 333,
        height: 197,
        lights: scene.lights.len() as u32,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, scene).expect("materials");
    let prepared = r
        .prepare(compiled, scene, &gpu, size, false)
        .map_err(|e| e.to_string())?;
    let result = prepared.render(r).expect("render");
    let bits = read
        .iter()
        .map(|name| prepared.read_texture_bits(r, name).expect("readback"))
        .collect();
    Ok((result, bits))
}

/// The shipped compute-only graph, and the same with a Depth32Float depth.
fn compute_raster_graphs() -> [(&'static str, String); 2] {
    let float = graph_text("visibility_compute_raster.ron");
    let line = r#"Texture(name: "depth", format: R32Float, size: Output)"#;
    assert!(float.contains(line));
    let depth32 = float.replace(
        line,
        r#"Texture(name: "depth", format: Depth32Float, size: Output)"#,
    );
    [("R32Float depth", float), ("Depth32Float depth", depth32)]
}

fn harada() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/harada.ron");
    lightgraph::scene::load(&path).unwrap().scene
}

#[test]
fn the_masked_device_lacks_the_atomics() {
    let r = masked_renderer();
    assert!(!r.ctx.device.features().contains(MASKED));
    assert!(
        r.ctx
            .device
            .features()
            .contains(wgpu::Features::PRIMITIVE_INDEX),
        "the fallback draws need PRIMITIVE_INDEX"
    );
    assert_eq!(r.ctx.disabled_features, MASKED);
}

/// Without the atomics, ComputeRaster's depth, ids and image are exactly the hardware
/// visibility buffer's (the same draws), for an R32Float depth (drawn into a Depth32Float
/// and copied) and a Depth32Float one (drawn into directly); the report names the pass,
/// the adapter and the missing feature. On harada and on the textured scene, whose
/// alpha-masked panels the draws alpha-test.
#[test]
fn without_the_atomics_it_draws_the_hardware_visibility_buffer() {
    for scene in [harada(), textured_scene()] {
        draws_the_hardware_visibility_buffer(&scene);
    }
}

fn draws_the_hardware_visibility_buffer(scene: &Scene) {
    let mut r = masked_renderer();
    let adapter = r.ctx.adapter_name();
    let (reference, want) = render_reading(
        &mut r,
        &graph_text("visibility_buffer.ron"),
        scene,
        &["depth", "visibility"],
    )
    .unwrap();
    assert!(reference.fallbacks.is_empty(), "{:?}", reference.fallbacks);
    let covered = want[1].iter().filter(|&&id| id != NO_TRIANGLE).count();
    assert!(
        covered > 10_000,
        "{covered} covered pixels: nothing compared"
    );
    assert_eq!(want[0].len(), 333 * 197);
    for (what, graph) in compute_raster_graphs() {
        let (frame, got) = render_reading(&mut r, &graph, scene, &["depth", "visibility"])
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        let differ = |a: &[u32], b: &[u32]| {
            assert_eq!(a.len(), b.len());
            a.iter().zip(b).filter(|(x, y)| x != y).count()
        };
        assert_eq!(differ(&got[0], &want[0]), 0, "{what}: depth bits differ");
        assert_eq!(differ(&got[1], &want[1]), 0, "{what}: ids differ");
        assert_eq!(
            frame.culling[0].counts, reference.culling[0].counts,
            "{what}: tile lists"
        );
        assert_eq!(frame.image.len(), reference.image.len());
        assert!(frame.image == reference.image, "{what}: images differ");
        let lines: Vec<String> = frame.fallbacks.iter().map(|f| f.line()).collect();
        eprintln!("{what}: {lines:?}");
        assert_eq!(
            lines,
            [format!(
                "compute_raster: adapter {adapter} lacks SHADER_INT64_ATOMIC_MIN_MAX (offered by the adapter, disabled on request); drawn with the hardware rasterizer"
            )],
            "{what}"
        );
    }
}

/// Without the atomics, `TransparentDepth` into R32Float draws the blended meshes with
/// the raster units and copies them: bit for bit the Depth32Float the same draws give,
/// and the report says so. On the built-in glass scene.
#[test]
fn without_the_atomics_the_transparent_depth_is_drawn_and_copied() {
    let mut r = masked_renderer();
    let adapter = r.ctx.adapter_name();
    let scene = lightgraph::scene::builtin::by_name("glass").expect("the glass scene");
    let (frame, bits) = render_reading(
        &mut r,
        common::compute_raster::TRANSPARENT_COMPARE,
        &scene,
        &["transparent_cr", "transparent_hw"],
    )
    .unwrap();
    let covered = bits[1].iter().filter(|&&d| f32::from_bits(d) < 1.0).count();
    assert!(
        covered > 5_000,
        "{covered} blended pixels: nothing compared"
    );
    assert!(bits[0] == bits[1], "the copied depth's bits differ");
    let lines: Vec<String> = frame.fallbacks.iter().map(|f| f.line()).collect();
    assert_eq!(
        lines,
        [format!(
            "cr: adapter {adapter} lacks SHADER_INT64_ATOMIC_MIN_MAX (offered by the adapter, disabled on request); drawn with the hardware rasterizer and copied"
        )]
    );
}

/// Without the atomics, ComputeRaster with the transparent depth in its writes
/// (`graphs/default.ron`, here with the farthest glass too) draws the blended meshes too: the depth the raster units give
/// them (TransparentDepth into Depth32Float, the same draws), bit for bit; their farthest
/// depth is the far plane (not drawn).
#[test]
fn without_the_atomics_the_opaque_pass_still_writes_the_transparent_depth() {
    let mut r = masked_renderer();
    let scene = lightgraph::scene::builtin::by_name("glass").expect("the glass scene");
    let (_, want) = render_reading(
        &mut r,
        common::compute_raster::TRANSPARENT_COMPARE,
        &scene,
        &["transparent_hw"],
    )
    .unwrap();
    let (frame, got) = render_reading(
        &mut r,
        &common::glass::default_with_farthest_glass(),
        &scene,
        &["transparent_depth", "transparent_far"],
    )
    .unwrap();
    let covered = want[0].iter().filter(|&&d| f32::from_bits(d) < 1.0).count();
    assert!(
        covered > 5_000,
        "{covered} blended pixels: nothing compared"
    );
    assert!(got[0] == want[0], "the transparent depth's bits differ");
    // No farthest depth drawn: the far plane everywhere, so culling bounds the glass's
    // ranges by the opaque depth alone.
    assert!(
        got[1].iter().all(|&b| b == 1f32.to_bits()),
        "the farthest transparent depth is not the far plane everywhere"
    );
    assert!(
        frame.fallbacks.iter().any(|f| f.pass == "compute_raster"),
        "{:?}",
        frame.fallbacks
    );
}

/// With the atomics the compute rasterizer runs and nothing is reported.
#[test]
fn with_the_atomics_nothing_falls_back() {
    let mut r = Renderer::new(
        GpuContext::new_headless().expect("a wgpu adapter (lavapipe on CI)"),
        ShaderLibrary::builtin(),
    );
    if !r
        .ctx
        .device
        .features()
        .contains(wgpu::Features::SHADER_INT64 | MASKED)
    {
        eprintln!(
            "!!!!! {} lacks 64-bit atomics: only the fallback runs here !!!!!",
            r.ctx.adapter_name()
        );
        return;
    }
    assert!(r.ctx.disabled_features.is_empty());
    let scene = random_scene(4, 1);
    for (what, graph) in compute_raster_graphs() {
        let (frame, _) = render_reading(&mut r, &graph, &scene, &[]).unwrap();
        assert!(frame.fallbacks.is_empty(), "{what}: {:?}", frame.fallbacks);
    }
}

/// `lightgraph render --disable-features` opens the device without them and prints the
/// fallback line; without the flag there is no such line.
#[test]
fn render_says_when_it_falls_back() {
    let run = |extra: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_lightgraph"))
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .args([
                "render",
                "--scene",
                "scenes/harada.ron",
                "--graph",
                "graphs/visibility_compute_raster.ron",
                "--width",
                "64",
                "--height",
                "36",
            ])
            .args(extra)
            .env_remove("LIGHTGRAPH_ROOT")
            .output()
            .expect("the binary runs");
        let out = String::from_utf8_lossy(&o.stdout).into_owned();
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{out}\n{err}");
        out
    };
    let out = run(&["--disable-features", "shader_int64_atomic_min_max"]);
    assert!(
        out.contains("  fallback: compute_raster: adapter ")
            && out.contains(
                "lacks SHADER_INT64_ATOMIC_MIN_MAX (offered by the adapter, disabled on request); drawn with the hardware rasterizer"
            ),
        "{out}"
    );
    let out = run(&[]);
    let has_atomics = GpuContext::new_headless()
        .expect("a wgpu adapter")
        .device
        .features()
        .contains(wgpu::Features::SHADER_INT64 | MASKED);
    assert_eq!(out.contains("fallback"), !has_atomics, "{out}");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_lightgraph"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["render", "--disable-features", "no_such_feature"])
        .output()
        .expect("the binary runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("--disable-features: 'no_such_feature' is not a wgpu feature name"),
        "{err}"
    );
}

/// Without PRIMITIVE_INDEX too, neither way can write ids: refused, naming both.
#[test]
fn without_primitive_index_too_it_is_refused_naming_both() {
    let options = ContextOptions {
        disabled_features: MASKED | wgpu::Features::PRIMITIVE_INDEX,
        ..Default::default()
    };
    let mut r = Renderer::headless_with(&options).expect("a wgpu adapter (lavapipe on CI)");
    let e = render_reading(
        &mut r,
        &graph_text("visibility_compute_raster.ron"),
        &random_scene(2, 5),
        &[],
    )
    .err()
    .expect("refused");
    assert!(e.contains("pass 'compute_raster'"), "{e}");
    assert!(
        e.contains("lacks SHADER_INT64_ATOMIC_MIN_MAX for the compute rasterizer, and PRIMITIVE_INDEX for its hardware fallback"),
        "{e}"
    );
}

/// On a device that lets a shader stage bind only 8 storage buffers (WebGPU's default,
/// which smaller GPUs give), a pipeline that binds more is refused at prepare with the
/// pass, the shader, its switches and both counts, not wgpu's layout validation text;
/// a graph whose shaders fit renders.
#[test]
fn a_shader_over_the_storage_buffer_limit_is_refused_by_name() {
    let options = ContextOptions {
        storage_buffers_per_stage: Some(8),
        ..Default::default()
    };
    let mut r = Renderer::headless_with(&options).expect("a wgpu adapter (lavapipe on CI)");
    assert_eq!(
        r.ctx.device.limits().max_storage_buffers_per_shader_stage,
        8
    );
    let scene = lightgraph::scene::builtin::by_name("glass").expect("the glass scene");
    let error = render_reading(&mut r, &graph_text("default.ron"), &scene, &[])
        .err()
        .expect("the compute rasterizer binds more than 8 storage buffers");
    eprintln!("{error}");
    assert!(
        error.contains("compute_raster")
            && error.contains("visibility/compute_raster.wgsl: binds ")
            && error.contains("storage buffers in one stage (")
            && error.contains("over the 8 this device allows"),
        "{error}"
    );
    assert!(!error.contains("Validation Error"), "{error}");
    let (frame, _) = render_reading(&mut r, &graph_text("forward_plus.ron"), &scene, &[])
        .expect("Forward+ fits 8 storage buffers a stage");
    assert_eq!(frame.image.len(), 333 * 197);
}
