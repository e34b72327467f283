//! glTF 2.0 import (.gltf with external or embedded buffers, .glb) into a world-space
//! [`Scene`].
//!
//! Buffers, accessors and images are read here (not through `gltf::import`) so that every
//! failure is an error naming the file and the element, bounds are checked before anything is
//! sliced, and a missing texture only costs a warning.
//!
//! One job per module: `document` parses, validates and walks the node graph; `buffers`
//! and `accessors` read the binary data (`sparse`: sparse accessors and those without a
//! bufferView, made dense); `mesh`, `morph` (morph targets at their default weights),
//! `materials`, `images`, `lights` and `camera` turn glTF elements into scene ones;
//! `encoding` holds the URI / base64 codecs.

mod accessors;
mod alignment;
mod buffers;
mod camera;
mod document;
mod encoding;
mod images;
pub mod instancing;
mod lights;
mod locate;
mod materials;
mod mesh;
mod morph;
mod sparse;

pub use encoding::{base64_decode, base64_encode};
pub use lights::INFINITE_RANGE_CUTOFF;

use super::error::SceneError;
use super::types::{Scene, TextureImage};
use super::Loaded;
use images::ImageSource;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Extensions this importer understands; any other in `extensionsRequired` is refused.
pub(crate) const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_unlit",
    "KHR_texture_transform",
];

/// Safety limits: inputs past them are refused with a [`SceneError::Limit`].
#[derive(Clone, Copy, Debug)]
pub struct ImportLimits {
    /// Elements in one accessor.
    pub(crate) max_accessor_count: u64,
    /// Triangles in the whole scene.
    pub(crate) max_triangles: u64,
    /// Declared `byteLength` of one buffer.
    pub(crate) max_buffer_bytes: u64,
    /// Nodes in the file, and node instances after instancing.
    pub(crate) max_nodes: u64,
    /// Mesh primitives after instancing (each becomes a mesh with its own draw).
    pub(crate) max_primitives: u64,
    pub(crate) max_lights: u64,
    /// Pixels in one decoded image.
    pub(crate) max_image_pixels: u64,
}

impl Default for ImportLimits {
    fn default() -> Self {
        ImportLimits {
            max_accessor_count: 1 << 27,
            // After instancing; about 1.3 GB of vertices if none are shared.
            max_triangles: 1 << 23,
            max_buffer_bytes: 1 << 32,
            max_nodes: 1 << 20,
            max_primitives: 1 << 15,
            max_lights: 1 << 20,
            max_image_pixels: 1 << 26,
        }
    }
}

/// Imports a .gltf or .glb file with default limits.
pub(crate) fn import_gltf(path: &Path) -> Result<Loaded, SceneError> {
    import_gltf_with(path, &ImportLimits::default())
}

/// Imports a .gltf or .glb file. Relative URIs resolve against the file's folder.
pub(crate) fn import_gltf_with(path: &Path, limits: &ImportLimits) -> Result<Loaded, SceneError> {
    import_gltf_inner(path, limits)
        .map(|(l, has_camera, _)| with_camera_warning(l, has_camera, path))
}

/// A glTF file loaded on its own renders through its own camera, or a fitted one: the
/// latter is worth a warning. (A scene file that places the model decides for itself.)
fn with_camera_warning(mut loaded: Loaded, has_camera: bool, file: &Path) -> Loaded {
    if !has_camera && loaded.scene.bounds().is_some() {
        loaded.warnings.push(format!(
            "{}: no perspective camera; one was fitted to the scene bounds",
            file.display()
        ));
    }
    loaded
}

/// Imports and tells whether the file had a perspective camera (else one was fitted),
/// and what its node graph expanded to.
pub(crate) fn import_gltf_inner(
    path: &Path,
    limits: &ImportLimits,
) -> Result<(Loaded, bool, instancing::Expansion), SceneError> {
    let bytes = crate::files::read_bytes(path, crate::files::caps::GLTF)
        .map_err(|e| SceneError::io(path, e))?;
    let base = path.parent().unwrap_or(Path::new("."));
    import_slice_inner(&bytes, base, path, limits)
}

/// Imports glTF bytes; `base_dir` resolves relative URIs, `file` names the source in messages.
pub fn import_gltf_slice(
    bytes: &[u8],
    base_dir: &Path,
    file: &Path,
    limits: &ImportLimits,
) -> Result<Loaded, SceneError> {
    import_slice_inner(bytes, base_dir, file, limits)
        .map(|(l, has_camera, _)| with_camera_warning(l, has_camera, file))
}

fn import_slice_inner(
    bytes: &[u8],
    base_dir: &Path,
    file: &Path,
    limits: &ImportLimits,
) -> Result<(Loaded, bool, instancing::Expansion), SceneError> {
    import_unlocated(bytes, base_dir, file, limits).map_err(|e| {
        // Semantic errors of a .gltf point at its JSON text (a .glb's chunk is binary).
        let text = std::str::from_utf8(bytes).ok();
        match text.filter(|t| {
            t.trim_start_matches('\u{feff}')
                .trim_start()
                .starts_with('{')
        }) {
            Some(text) => e.located_by(file, |element, message| {
                locate::locate(text, element, message)
            }),
            None => e,
        }
    })
}

fn import_unlocated(
    bytes: &[u8],
    base_dir: &Path,
    file: &Path,
    limits: &ImportLimits,
) -> Result<(Loaded, bool, instancing::Expansion), SceneError> {
    let mut imp = Importer {
        file: file.to_path_buf(),
        base_dir: base_dir.to_path_buf(),
        limits: *limits,
        warnings: Vec::new(),
        buffers: Vec::new(),
        images: HashMap::new(),
        textures: HashMap::new(),
        materials: HashMap::new(),
        image_sources: Vec::new(),
        image_names: Vec::new(),
        scene: Scene::default(),
        triangles: 0,
        has_camera: false,
        expansion: Default::default(),
        files_read: std::cell::RefCell::new(vec![file.to_path_buf()]),
    };
    // A byte-order mark before the JSON is tolerated, as in every other input format.
    imp.run(bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes))?;
    Ok((
        Loaded {
            scene: imp.scene,
            warnings: imp.warnings,
            files: imp.files_read.into_inner(),
        },
        imp.has_camera,
        imp.expansion,
    ))
}

struct Importer {
    file: PathBuf,
    base_dir: PathBuf,
    limits: ImportLimits,
    warnings: Vec<String>,
    buffers: Vec<Vec<u8>>,
    /// Decoded RGBA8 per glTF image index (`None`: failed, already warned).
    images: HashMap<usize, Option<Arc<image::RgbaImage>>>,
    textures: HashMap<(usize, bool), Option<Arc<TextureImage>>>,
    /// glTF material index (`None`: default material) to scene material index.
    materials: HashMap<Option<usize>, usize>,
    image_sources: Vec<ImageSource>,
    image_names: Vec<String>,
    scene: Scene,
    triangles: u64,
    has_camera: bool,
    /// What the node graph expands to, counted before anything is read.
    expansion: instancing::Expansion,
    /// The glTF file and every external buffer and image read for it.
    files_read: std::cell::RefCell<Vec<PathBuf>>,
}

fn named(kind: &str, index: usize, name: Option<&str>) -> String {
    match name {
        Some(n) => format!("{kind} {index} (\"{n}\")"),
        None => format!("{kind} {index}"),
    }
}

impl Importer {
    fn err(&self, element: impl std::fmt::Display, message: impl std::fmt::Display) -> SceneError {
        SceneError::invalid(&self.file, element, message)
    }

    fn limit(
        &self,
        element: impl std::fmt::Display,
        what: &'static str,
        count: u64,
        limit: u64,
    ) -> Result<(), SceneError> {
        if count > limit {
            return Err(SceneError::Limit {
                file: self.file.clone(),
                at: None,
                element: element.to_string(),
                what,
                count,
                limit,
            });
        }
        Ok(())
    }

    fn warn(&mut self, msg: impl std::fmt::Display) {
        self.warnings
            .push(format!("{}: {msg}", self.file.display()));
    }
}
