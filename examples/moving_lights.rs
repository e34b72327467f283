//! Lights that move, through the library: the scene's motion uploaded once
//! (`set_light_motion`) and evaluated on the GPU before each frame's passes; each frame
//! the CPU only sets the time (`move_lights_to`: a few bytes per motion, no pipeline or
//! bind group rebuilt), then the frame runs; the last one is written as a PNG. A caller
//! that places lights itself writes them with `update_lights` instead.
//!
//!     cargo run --release --example moving_lights -- [SCENE] [FRAMES] [OUT.png]
use lightgraph::bench::image_io::write_png_tonemapped;
use lightgraph::bench::tonemap::Tonemap;
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{Renderer, SceneGpu};
use lightgraph::shader::assets;
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let scene_path = PathBuf::from(
        args.next()
            .unwrap_or_else(|| "scenes/atrium_moving.ron".into()),
    );
    let frames: u32 = args.next().map_or(Ok(60), |n| n.parse())?;
    let out = PathBuf::from(args.next().unwrap_or_else(|| "moving_lights.png".into()));

    let scene = lightgraph::scene::load(&scene_path)?.scene;
    let mut renderer = Renderer::headless()?;
    // The project's graphs/default.ron, else the copy built into the library.
    let graph_path = assets::project().locate("graphs/default.ron");
    let checked = assets::check_graph(&graph_path, &renderer.shaders)?;
    // Room for the scene's lights; the graph is sized for the upload's capacity.
    let gpu = SceneGpu::upload_with_light_capacity(
        &renderer.ctx.device,
        &renderer.ctx.queue,
        &scene,
        scene.lights.len() as u32,
    )?;
    let size = FrameSize {
        width: 640,
        height: 360,
        lights: gpu.light_capacity,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    let frame = renderer.prepare(compiled, &scene, &gpu, size, false)?;

    frame.set_light_motion(&renderer, &gpu, &scene.lights, &scene.light_motion)?;
    for i in 0..frames {
        frame.move_lights_to(&renderer, f64::from(i) / 60.0)?;
        frame.execute(&renderer)?;
    }
    let result = frame.render(&renderer)?;
    write_png_tonemapped(
        &out,
        &result.image,
        size.width,
        size.height,
        &Tonemap::default(),
    )?;
    println!(
        "wrote {} after {frames} frames of {} moving lights",
        out.display(),
        scene.lights.len()
    );
    Ok(())
}
