//! lightgraph: a data-driven render graph for scenes with thousands of dynamic lights.
//!
//! Pass graphs and materials are RON files; they are parsed, validated and compiled
//! without a GPU (see [`graph`]), then executed on wgpu (see [`render`]). A frame is four
//! steps: load a scene ([`scene::load`], or a built-in one), check a graph file against
//! the shaders ([`graph::check_file`]), compile it for the scene, which drops the passes
//! the scene does not need ([`graph::compile`]), and prepare it on the GPU
//! ([`render::Renderer::prepare`]) to run as often as wanted:
//!
//! ```
//! use lightgraph::graph::{self, FrameSize};
//! use lightgraph::render::{Renderer, SceneGpu};
//! use lightgraph::shader::assets;
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! // Harada's boxes under 3,072 lights (scenes/harada.ron names the same scene).
//! let scene = lightgraph::scene::builtin::harada();
//! let mut renderer = Renderer::headless()?;
//! // The project's graphs/default.ron, else the copy built into the library.
//! let path = assets::project().locate("graphs/default.ron");
//! let checked = assets::check_graph(&path, &renderer.shaders)?;
//! let size = FrameSize { width: 64, height: 36, lights: scene.lights.len() as u32 };
//! let compiled = graph::compile(checked, &scene.features(), size);
//! let gpu = SceneGpu::upload(&renderer.ctx.device, &renderer.ctx.queue, &scene)?;
//! let frame = renderer.prepare(compiled, &scene, &gpu, size, false)?;
//! let result = frame.render(&renderer)?; // linear HDR RGBA, read back
//! assert_eq!(result.image.len(), 64 * 36);
//! assert!(result.image.iter().any(|p| p[0] > 0.0), "harada is lit");
//! # Ok(())
//! # }
//! ```
//!
//! On an engine's own device and encoder: [`render::Renderer::from_device`],
//! [`render::PreparedFrame::record`] and [`render::Presenter`]. Moving lights:
//! [`render::PreparedFrame::update_lights`]. The `examples/` folder has each of these as
//! a program; docs/architecture.md describes the steps.

#![warn(missing_docs)]

#[cfg(feature = "bench")]
pub mod bench;
pub mod cull;
pub mod file_kind;
pub mod files;
pub mod gpu;
pub mod graph;
pub mod indirect;
pub mod material;
pub mod reload;
pub mod render;
pub mod scene;
pub mod shader;
pub mod shadow;
#[cfg(feature = "viewer")]
pub mod view;

/// The folder the user's shaders/, graphs/ and materials/ are looked for in first (see
/// [`shader::assets`]): the CLI's `--root`, else `LIGHTGRAPH_ROOT`, else the current
/// directory. Files not there come from the copies built into the binary. Never the
/// source tree the binary was built from: code that needs that uses `CARGO_MANIFEST_DIR`.
pub fn project_root() -> std::path::PathBuf {
    shader::assets::project()
        .root
        .unwrap_or_else(|| std::env::current_dir().unwrap_or_else(|_| ".".into()))
}
