//! lightgraph inside someone else's renderer: on the caller's device and queue, recording
//! into the caller's encoder, drawing into the caller's colour target through the present
//! pass; and on a device opened without lightgraph's wanted features, falling back and
//! saying so.

mod common;

use lightgraph::bench::tonemap::Tonemap;
use lightgraph::gpu::readback::read_texture;
use lightgraph::gpu::GpuContext;
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{Presenter, Renderer, SceneGpu};
use std::path::Path;

const SIZE: (u32, u32) = (96, 64);

/// What an engine would do: its own instance, adapter, device and queue.
fn callers_device(features: wgpu::Features) -> (wgpu::Adapter, wgpu::Device, wgpu::Queue) {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::VULKAN;
    let instance = wgpu::Instance::new(desc);
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))
        .expect("a Vulkan adapter (lavapipe on CI)");
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_features: adapter.features() & features,
        required_limits: GpuContext::wanted_limits(&adapter),
        ..Default::default()
    }))
    .expect("a device");
    (adapter, device, queue)
}

fn prepare(
    r: &mut Renderer,
    graph: &str,
    scene: &lightgraph::scene::Scene,
) -> Result<lightgraph::render::PreparedFrame, lightgraph::render::RenderError> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("graphs")
        .join(graph);
    let checked = graph::check_file(&path, &r.shaders).expect("valid graph");
    let size = FrameSize {
        width: SIZE.0,
        height: SIZE.1,
        lights: scene.lights.len() as u32,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, scene).expect("upload");
    r.prepare(compiled, scene, &gpu, size, false)
}

/// Harada's floor and boxes under 3,072 lights: most of the frame is lit.
fn harada() -> lightgraph::scene::Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/harada.ron");
    lightgraph::scene::load(&path).expect("harada").scene
}

#[test]
fn a_frame_recorded_into_the_callers_encoder_lands_in_the_callers_texture() {
    let (adapter, device, queue) = callers_device(GpuContext::wanted_features());
    let mut r = Renderer::from_device(adapter, device.clone(), queue.clone());
    let scene = harada();
    let frame = prepare(&mut r, "visibility_compute_raster.ron", &scene).expect("prepare");
    // The reference: the same prepared frame run and read back by lightgraph itself.
    let expected = frame.render(&r).expect("render").image;

    // The caller's target, in an 8-bit sRGB format lightgraph never renders to itself.
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("caller's target"),
        size: wgpu::Extent3d {
            width: SIZE.0,
            height: SIZE.1,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = target.create_view(&Default::default());
    let presenter = Presenter::new(&r, format).expect("present pipeline");
    let mut encoder = device.create_command_encoder(&Default::default());
    frame.record(&mut encoder);
    presenter.draw(
        &device,
        &queue,
        &mut encoder,
        frame.output_texture(),
        &view,
        [SIZE.0, SIZE.1],
        0.0,
    );
    queue.submit([encoder.finish()]);

    let got = read_texture(&device, &queue, &target, 4).expect("readback");
    assert_eq!(got.len(), (SIZE.0 * SIZE.1 * 4) as usize, "target size");
    let want = Tonemap::default().image_to_srgb8(&expected);
    assert_eq!(want.len(), (SIZE.0 * SIZE.1 * 3) as usize, "frame size");
    let mut worst = 0;
    let mut lit = 0;
    for (g, w) in got.chunks_exact(4).zip(want.chunks_exact(3)) {
        for c in 0..3 {
            worst = worst.max((g[c] as i32 - w[c] as i32).abs());
        }
        lit += usize::from(w.iter().any(|&c| c > 8));
    }
    // The same curve on both sides; the GPU's sRGB encode (the format's) and the CPU's
    // rounding may differ by one 8-bit step.
    assert!(
        worst <= 1,
        "present pass differs from the CPU tonemap by {worst} steps"
    );
    assert!(
        lit > (SIZE.0 * SIZE.1 / 4) as usize,
        "only {lit} lit pixels: an empty frame would pass"
    );
}

#[test]
fn a_device_without_the_wanted_features_falls_back_and_says_so() {
    // Triangle ids from the hardware rasterizer, but no 64-bit atomics for the compute one.
    let (adapter, device, queue) = callers_device(wgpu::Features::PRIMITIVE_INDEX);
    let offered = adapter.features();
    let mut r = Renderer::from_device(adapter, device, queue);
    assert_eq!(
        r.ctx.disabled_features,
        offered & (GpuContext::wanted_features() - wgpu::Features::PRIMITIVE_INDEX),
        "every other wanted feature the adapter offers counts as disabled on this device"
    );
    let scene = common::random_scene(16, 3);
    let frame = prepare(&mut r, "visibility_compute_raster.ron", &scene).expect("prepare");
    let result = frame.render(&r).expect("the frame runs on the fallback");
    assert!(
        result.fallbacks.iter().any(|f| f.pass == "compute_raster"),
        "the compute rasterizer's fallback is reported: {:?}",
        result.fallbacks
    );
    assert!(
        result.pass_ms.is_none(),
        "no timestamps without the feature"
    );
}

#[test]
fn a_device_that_cannot_run_a_pass_is_refused_with_the_pass_and_the_features() {
    let (adapter, device, queue) = callers_device(wgpu::Features::empty());
    let mut r = Renderer::from_device(adapter, device, queue);
    let scene = common::random_scene(16, 3);
    let e = prepare(&mut r, "visibility_compute_raster.ron", &scene)
        .err()
        .expect("no way to write triangle ids")
        .to_string();
    for needed in [
        "visibility_compute_raster.ron:",
        "compute_raster",
        "SHADER_INT64",
        "PRIMITIVE_INDEX",
    ] {
        assert!(e.contains(needed), "'{needed}' missing from: {e}");
    }
}

/// A project's own present shader that binds something the present pass does not offer
/// is refused when the presenter is built, naming its file and line, instead of failing
/// inside wgpu when the pipeline or bind group is made.
#[test]
fn a_present_shader_binding_an_unoffered_name_is_refused_with_its_line() {
    let (adapter, device, queue) = callers_device(GpuContext::wanted_features());
    let mut r = Renderer::from_device(adapter, device, queue);
    let dir = tempfile::tempdir().unwrap();
    let builtin = lightgraph::shader::assets::builtin("shaders/view/present.wgsl").unwrap();
    let own = builtin.replace(
        "@group(0) @binding(1) var<uniform> params: PresentParams;",
        "@group(0) @binding(1) var<uniform> params: PresentParams;\n@group(0) @binding(2) var<uniform> extra: vec4<f32>;",
    );
    assert_ne!(own, builtin, "the test edits the shipped shader");
    let own = own.replace(
        "return vec4<f32>(rgb, 1.0);",
        "return vec4<f32>(rgb, 1.0) + extra * 0.0;",
    );
    std::fs::create_dir_all(dir.path().join("view")).unwrap();
    std::fs::write(dir.path().join("view/present.wgsl"), own).unwrap();
    r.shaders = lightgraph::shader::ShaderLibrary::with_builtin(dir.path());
    let e = Presenter::new(&r, wgpu::TextureFormat::Rgba8UnormSrgb)
        .err()
        .expect("refused")
        .to_string();
    assert!(e.contains("present.wgsl:14"), "{e}");
    assert!(e.contains("'extra'"), "{e}");
}
