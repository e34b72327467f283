//! Render a scene through a graph file, headless, and write a PNG:
//!
//!     cargo run --release --example headless_png -- [SCENE] [GRAPH] [OUT.png]
//!
//! Defaults: scenes/harada.ron (3,072 lights), graphs/visibility_compute_raster.ron,
//! headless.png; 640×360 so that it is quick on a software adapter too.
use lightgraph::bench::image_io::write_png_tonemapped;
use lightgraph::bench::tonemap::Tonemap;
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{Renderer, SceneGpu};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let mut arg = |default: &str| PathBuf::from(args.next().unwrap_or_else(|| default.into()));
    let (scene_path, graph_path) = (
        arg("scenes/harada.ron"),
        arg("graphs/visibility_compute_raster.ron"),
    );
    let out = arg("headless.png");

    let scene = lightgraph::scene::load(&scene_path)?.scene;
    let mut renderer = Renderer::headless()?;
    let checked = graph::check_file(&graph_path, &renderer.shaders)?;
    let size = FrameSize {
        width: 640,
        height: 360,
        lights: scene.lights.len() as u32,
    };
    // Passes the scene does not need (no glass, no shadow casters, ...) are dropped here.
    let compiled = graph::compile(checked, &scene.features(), size);
    let gpu = SceneGpu::upload(&renderer.ctx.device, &renderer.ctx.queue, &scene)?;
    let frame = renderer.prepare(compiled, &scene, &gpu, size, false)?;
    let result = frame.render(&renderer)?;

    write_png_tonemapped(
        &out,
        &result.image,
        size.width,
        size.height,
        &Tonemap::default(),
    )?;
    println!(
        "wrote {} ({} lights, {})",
        out.display(),
        scene.lights.len(),
        renderer.ctx.adapter_name()
    );
    Ok(())
}
