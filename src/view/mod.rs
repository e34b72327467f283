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

/// What `lightgraph view` opens: the scene, the graph and the window, for [`run`].
pub struct ViewOptions {
    /// The scene to render (a file, reloaded on edits, or a built-in).
    pub scene: SceneSource,
    /// Shown in the overlay.
    pub scene_name: String,
    /// The graph file rendered first.
    pub graph: PathBuf,
    /// Graph files the overlay offers as variants (the folder of `graph` by default).
    pub variants: Vec<PathBuf>,
    /// Extra paths to watch (materials/).
    pub watch: Vec<PathBuf>,
    /// Initial window size in physical pixels (width, height).
    pub window_size: [u32; 2],
    /// Render size relative to the window (0.5 renders a quarter of the pixels).
    pub render_scale: f32,
    /// Initial exposure in stops: the linear image is multiplied by `2^exposure_ev` before
    /// tonemapping (the overlay changes it).
    pub exposure_ev: f32,
    /// Save the window's contents (scene and overlay) after this many frames, then exit.
    pub screenshot: Option<(PathBuf, u32)>,
}

/// Why the viewer could not start or stopped.
#[derive(Debug, Error)]
pub enum ViewError {
    /// The window (or its event loop) could not be created.
    #[error("could not open a window: {0}")]
    Window(String),
    /// No GPU adapter or device.
    #[error(transparent)]
    Gpu(#[from] crate::gpu::GpuError),
    /// The window's surface could not be created or configured.
    #[error("window surface: {0}")]
    Surface(String),
    /// The present shader (`present.wgsl`) failed to compose or bind.
    #[error(transparent)]
    Shader(#[from] crate::shader::ShaderError),
    /// The reload session could not start (scene or graph).
    #[error("{0}")]
    Session(String),
    /// The screenshot could not be read back or written.
    #[error("screenshot {path}: {message}")]
    Screenshot {
        /// The PNG file.
        path: PathBuf,
        /// What failed.
        message: String,
    },
}
