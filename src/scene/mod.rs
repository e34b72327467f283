//! Scenes: what gets rendered. Geometry in world space, lights, a camera.
//!
//! [`load`] reads a scene RON (`.ron`), a glTF (`.gltf`) or a binary glTF (`.glb`);
//! [`builtin`] has the procedural scenes; [`lights`] the procedural light sets.

pub mod builtin;
pub(crate) mod builtin_chairs;
pub(crate) mod builtin_glass;
mod error;
pub mod geometry;
pub mod gltf_import;
pub mod gltf_writer;
pub mod lights;
mod locate;
mod model_budget;
pub mod motion;
pub(crate) mod ranges;
pub mod scene_file;
pub mod tangent_space;
mod types;
pub(crate) mod vpl;

pub use error::SceneError;
pub use types::*;
pub use vpl::VplControls;

use std::path::Path;

/// A loaded scene and the warnings met while loading it (missing textures, skipped
/// primitives, lights given a finite range...). The library never prints them.
#[derive(Clone, Debug, Default)]
pub struct Loaded {
    /// The scene, ready for [`graph::compile`](crate::graph::compile) and
    /// [`SceneGpu::upload`](crate::render::SceneGpu::upload).
    pub scene: Scene,
    /// Non-fatal problems, one message each, for the caller to show.
    pub warnings: Vec<String>,
    /// Every file the scene was read from (scene file, glTF models, their buffers and
    /// images): what hot reload watches.
    pub(crate) files: Vec<std::path::PathBuf>,
}

/// Loads a scene file, dispatching on the extension: `.ron` (scene file), `.gltf`, `.glb`.
pub fn load(path: &Path) -> Result<Loaded, SceneError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let mut loaded = match ext.as_str() {
        "ron" => scene_file::load_scene_file(path)?,
        "gltf" | "glb" => gltf_import::import_gltf(path)?,
        _ => {
            return Err(SceneError::invalid(
                path,
                "file name",
                format!("unknown scene extension \"{ext}\" (expected .ron, .gltf or .glb)"),
            ))
        }
    };
    loaded.scene.source_path = Some(path.to_path_buf());
    // After every transform (node, model, scene), before anything reaches the GPU.
    loaded.scene.check_gpu_ranges(path)?;
    Ok(loaded)
}
