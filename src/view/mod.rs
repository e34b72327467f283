//! `lightgraph view`: a window onto a hot-reloading graph. The graph renders at the
//! window's size (times `render_scale`), is tonemapped into the window, and an egui
//! overlay shows per-pass GPU times, light statistics and the current reload error.
//! Edits to shaders, materials, the graph or the scene show in the next frame.

mod animation;
mod app;
pub(crate) mod camera;
pub(crate) mod overlay;

pub use app::run;
pub use camera::{CameraController, CameraMode, Movement};

use crate::reload::SceneSource;
use std::path::PathBuf;
use thiserror::Error;

pub struct ViewOptions {
    pub scene: SceneSource,
    /// Shown in the overlay.
    pub scene_name: String,
    pub graph: PathBuf,
    /// Graph files the overlay offers as variants (the folder of `graph` by default).
    pub variants: Vec<PathBuf>,
    /// Extra paths to watch (materials/).
    pub watch: Vec<PathBuf>,
    pub window_size: [u32; 2],
    /// Render size relative to the window (0.5 renders a quarter of the pixels).
    pub render_scale: f32,
    pub exposure_ev: f32,
    /// Save the window's contents (scene and overlay) after this many frames, then exit.
    pub screenshot: Option<(PathBuf, u32)>,
}

#[derive(Debug, Error)]
pub enum ViewError {
    #[error("could not open a window: {0}")]
    Window(String),
    #[error(transparent)]
    Gpu(#[from] crate::gpu::GpuError),
    #[error("window surface: {0}")]
    Surface(String),
    #[error(transparent)]
    Shader(#[from] crate::shader::ShaderError),
    #[error("{0}")]
    Session(String),
    #[error("screenshot {path}: {message}")]
    Screenshot { path: PathBuf, message: String },
}
