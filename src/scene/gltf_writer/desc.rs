//! What the caller describes: primitives, materials, nodes, and where data is stored.

use glam::{Quat, Vec3, Vec4};

/// Where a .gltf file keeps its binary buffer.
#[derive(Clone, Debug, PartialEq)]
pub enum BufferStorage {
    /// A file beside the .gltf, by this relative URI.
    External(String),
    /// A `data:application/octet-stream;base64,` URI.
    Embedded,
}

/// Where an image's PNG bytes go.
#[derive(Clone, Debug, PartialEq)]
pub enum ImageStorage {
    /// A file beside the .gltf, by this relative URI (written by `write_gltf`/`write_glb`).
    File(String),
    /// A `data:image/png;base64,` URI.
    DataUri,
    /// In the binary buffer, through a bufferView.
    BufferView,
}

/// One triangle primitive; attributes are accessor indices from the `add_*` methods.
#[derive(Clone, Debug, Default)]
pub struct PrimitiveDesc {
    /// Accessor of the vertex positions (`POSITION`, from
    /// [`GltfWriter::add_positions`](super::GltfWriter::add_positions)).
    pub positions: usize,
    /// Accessor of the vertex normals (`NORMAL`).
    pub normals: Option<usize>,
    /// Accessor of the texture coordinates (`TEXCOORD_0`).
    pub uvs: Option<usize>,
    /// Accessor of the second texture coordinates (`TEXCOORD_1`).
    pub uvs1: Option<usize>,
    /// Accessor of the tangents (`TANGENT`, xyz and handedness w).
    pub tangents: Option<usize>,
    /// Accessor of the vertex colours (`COLOR_0`, VEC3 or VEC4).
    pub colors: Option<usize>,
    /// Accessor of the indices (from
    /// [`GltfWriter::add_indices`](super::GltfWriter::add_indices)); `None` for a
    /// non-indexed primitive.
    pub indices: Option<usize>,
    /// Material index (from [`GltfWriter::add_material`](super::GltfWriter::add_material));
    /// `None` leaves the glTF default material.
    pub material: Option<usize>,
    /// glTF primitive mode, 0..=6 (4 = triangles, the default).
    pub mode: Option<u32>,
}

/// A metallic-roughness material.
#[derive(Clone, Debug)]
pub struct MaterialDesc {
    /// Material name (`name`).
    pub name: String,
    /// Linear RGBA `baseColorFactor`.
    pub base_color: Vec4,
    /// `metallicFactor`, 0..1.
    pub metallic: f32,
    /// `roughnessFactor`, 0..1.
    pub roughness: f32,
    /// Linear RGB `emissiveFactor`.
    pub emissive: Vec3,
    /// "OPAQUE", "MASK" or "BLEND".
    pub alpha_mode: &'static str,
    /// `alphaCutoff` of `MASK` materials (the glTF default 0.5 when `None`).
    pub alpha_cutoff: Option<f32>,
    /// `doubleSided`.
    pub double_sided: bool,
    /// Texture indices from
    /// [`GltfWriter::add_texture_bytes`](super::GltfWriter::add_texture_bytes).
    pub base_color_texture: Option<usize>,
    /// `metallicRoughnessTexture` (roughness in G, metallic in B).
    pub metallic_roughness_texture: Option<usize>,
    /// `normalTexture`.
    pub normal_texture: Option<usize>,
    /// `emissiveTexture`.
    pub emissive_texture: Option<usize>,
    /// `occlusionTexture`.
    pub occlusion_texture: Option<usize>,
    /// Members of the material's `extensions` object, as JSON text
    /// (`"KHR_materials_unlit":{}`), written as given.
    pub extensions: Option<String>,
    /// A `KHR_texture_transform` object (JSON text, written as given, so malformed ones
    /// can be tested) per textureInfo key (`"baseColorTexture"`, `"normalTexture"`, ...).
    pub texture_transforms: Vec<(&'static str, String)>,
    /// The `texCoord` (uv set) per textureInfo key; 0 where not listed.
    pub tex_coords: Vec<(&'static str, u32)>,
}

impl Default for MaterialDesc {
    fn default() -> Self {
        MaterialDesc {
            name: "material".into(),
            base_color: Vec4::ONE,
            metallic: 0.0,
            roughness: 1.0,
            emissive: Vec3::ZERO,
            alpha_mode: "OPAQUE",
            alpha_cutoff: None,
            double_sided: false,
            base_color_texture: None,
            metallic_roughness_texture: None,
            normal_texture: None,
            emissive_texture: None,
            occlusion_texture: None,
            extensions: None,
            texture_transforms: Vec::new(),
            tex_coords: Vec::new(),
        }
    }
}

/// A node: TRS, optional mesh / camera / light, children.
#[derive(Clone, Debug, Default)]
pub struct NodeDesc {
    /// Node name.
    pub name: Option<String>,
    /// Translation, written when given.
    pub translation: Option<Vec3>,
    /// Rotation quaternion, written when given.
    pub rotation: Option<Quat>,
    /// Scale, written when given.
    pub scale: Option<Vec3>,
    /// Mesh index (from [`GltfWriter::add_mesh`](super::GltfWriter::add_mesh)).
    pub mesh: Option<usize>,
    /// Camera index (from [`GltfWriter::add_camera`](super::GltfWriter::add_camera)).
    pub camera: Option<usize>,
    /// KHR_lights_punctual light index (from
    /// [`GltfWriter::add_light`](super::GltfWriter::add_light)).
    pub light: Option<usize>,
    /// Child node indices (from [`GltfWriter::add_node`](super::GltfWriter::add_node)).
    pub children: Vec<usize>,
}
