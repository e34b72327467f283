//! A small glTF 2.0 writer, for tests and benchmarks: builds documents with meshes, materials,
//! PNG textures, KHR_lights_punctual lights, cameras and a node hierarchy, and writes them as
//! .gltf (external .bin or embedded base64 buffer) or .glb.
//!
//! The document is `gltf::json` (the `gltf-json` crate the importer parses with), so the
//! JSON is serialised by serde and GLB framing comes from `gltf::binary::Glb`. One module
//! per job: [`desc`] the descriptions the caller fills in, `data` binary data and
//! accessors, `materials` materials and textures, `scene` meshes, cameras, lights and
//! nodes, `output` the .gltf/.glb files, [`grid`](mod@grid) a test mesh.

mod data;
pub mod desc;
pub mod grid;
mod materials;
mod output;
mod scene;

pub use desc::{BufferStorage, ImageStorage, MaterialDesc, NodeDesc, PrimitiveDesc};
pub use grid::{grid, write_grid_glb};
pub use materials::encode_png;

use gltf::json;

/// Builds a glTF document in memory.
pub struct GltfWriter {
    /// The document, without its buffer (added when written: its URI depends on how).
    root: json::Root,
    /// The binary buffer's bytes: every bufferView's data, 4-byte aligned.
    bin: Vec<u8>,
    /// Images stored as files beside the document: (relative URI, encoded bytes).
    image_files: Vec<(String, Vec<u8>)>,
    /// Extra names for `extensionsRequired` (to test refusal).
    pub extensions_required: Vec<String>,
}

impl GltfWriter {
    /// An empty document: no meshes, nodes or buffer data.
    pub fn new() -> Self {
        Self::default()
    }

    /// Makes a node a root of the (single) scene.
    pub fn add_root(&mut self, node: usize) {
        self.root.scenes[0].nodes.push(index(node));
    }
}

impl Default for GltfWriter {
    /// One scene, empty: every document the writer makes has scene 0.
    fn default() -> Self {
        let mut root = json::Root::default();
        root.scenes.push(json::Scene {
            extensions: None,
            extras: Default::default(),
            name: None,
            nodes: Vec::new(),
        });
        root.scene = Some(index(0));
        Self {
            root,
            bin: Vec::new(),
            image_files: Vec::new(),
            extensions_required: Vec::new(),
        }
    }
}

/// A glTF index from a caller's `usize` (the writer's methods return and take plain
/// indices).
fn index<T>(i: usize) -> json::Index<T> {
    json::Index::new(u32::try_from(i).expect("glTF indices are u32"))
}

/// The `usize` of an index `Root::push` returned.
fn position<T>(i: json::Index<T>) -> usize {
    i.value()
}
