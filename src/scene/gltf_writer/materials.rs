//! Materials, and the textures, images and samplers they sample.

use super::desc::{ImageStorage, MaterialDesc};
use super::{index, position, GltfWriter};
use gltf::json;
use gltf::json::material::{AlphaCutoff, AlphaMode, EmissiveFactor, PbrBaseColorFactor};
use gltf::json::material::{PbrMetallicRoughness, StrengthFactor};
use gltf::json::validation::Checked::Valid;
use std::io;

impl GltfWriter {
    /// Adds a metallic-roughness material; returns its index.
    ///
    /// # Panics
    ///
    /// When `alpha_mode` is not one of glTF's three, or the extension texts are not JSON
    /// objects' members (a caller's mistake in a test).
    pub fn add_material(&mut self, m: &MaterialDesc) -> usize {
        let tex_coord = |key: &str| {
            m.tex_coords
                .iter()
                .find(|(k, _)| *k == key)
                .map_or(0, |&(_, set)| set)
        };
        let info = |key: &str, texture: Option<usize>| {
            texture.map(|i| json::texture::Info {
                index: index(i),
                tex_coord: tex_coord(key),
                extensions: transform(m, key).map(|others| json::extensions::texture::Info {
                    others,
                    ..Default::default()
                }),
                extras: Default::default(),
            })
        };
        let alpha_mode = match m.alpha_mode {
            "OPAQUE" => AlphaMode::Opaque,
            "MASK" => AlphaMode::Mask,
            "BLEND" => AlphaMode::Blend,
            other => panic!("alpha mode {other:?} is not OPAQUE, MASK or BLEND"),
        };
        let material = json::Material {
            alpha_cutoff: m.alpha_cutoff.map(AlphaCutoff),
            alpha_mode: Valid(alpha_mode),
            double_sided: m.double_sided,
            name: Some(m.name.clone()),
            pbr_metallic_roughness: PbrMetallicRoughness {
                base_color_factor: PbrBaseColorFactor(m.base_color.to_array()),
                base_color_texture: info("baseColorTexture", m.base_color_texture),
                metallic_factor: StrengthFactor(m.metallic),
                roughness_factor: StrengthFactor(m.roughness),
                metallic_roughness_texture: info(
                    "metallicRoughnessTexture",
                    m.metallic_roughness_texture,
                ),
                extensions: None,
                extras: Default::default(),
            },
            normal_texture: m.normal_texture.map(|i| json::material::NormalTexture {
                index: index(i),
                scale: 1.0,
                tex_coord: 0,
                extensions: transform(m, "normalTexture")
                    .map(|others| json::extensions::material::NormalTexture { others }),
                extras: Default::default(),
            }),
            occlusion_texture: m
                .occlusion_texture
                .map(|i| json::material::OcclusionTexture {
                    index: index(i),
                    strength: StrengthFactor(1.0),
                    tex_coord: 0,
                    extensions: transform(m, "occlusionTexture")
                        .map(|others| json::extensions::material::OcclusionTexture { others }),
                    extras: Default::default(),
                }),
            emissive_texture: info("emissiveTexture", m.emissive_texture),
            emissive_factor: EmissiveFactor(m.emissive.to_array()),
            extensions: m.extensions.as_deref().map(|members| {
                json::extensions::material::Material {
                    others: json_object(&format!("{{{members}}}")),
                    ..Default::default()
                }
            }),
            extras: Default::default(),
        };
        position(self.root.push(material))
    }

    /// Adds an image from PNG (or JPEG) bytes and a texture using it; returns the texture index.
    pub fn add_texture_bytes(
        &mut self,
        name: &str,
        encoded: Vec<u8>,
        storage: ImageStorage,
    ) -> usize {
        let mut image = json::Image {
            buffer_view: None,
            mime_type: None,
            name: Some(name.to_string()),
            uri: None,
            extensions: None,
            extras: Default::default(),
        };
        match storage {
            ImageStorage::File(uri) => {
                image.uri = Some(uri.clone());
                self.image_files.push((uri, encoded));
            }
            ImageStorage::DataUri => {
                let data = base64::encode(&encoded);
                image.uri = Some(format!("data:image/png;base64,{data}"));
            }
            ImageStorage::BufferView => {
                image.buffer_view = Some(index(self.push_view(&encoded, None)));
                image.mime_type = Some(json::image::MimeType("image/png".into()));
            }
        }
        let source = self.root.push(image);
        position(self.root.push(json::Texture {
            name: None,
            sampler: None,
            source,
            extensions: None,
            extras: Default::default(),
        }))
    }

    /// Adds a sampler from its JSON text (`{"wrapS":33071}`); returns its index.
    ///
    /// # Panics
    ///
    /// When `json` is not a glTF sampler.
    pub fn add_sampler(&mut self, json: &str) -> usize {
        let sampler: json::texture::Sampler = json::deserialize::from_str(json)
            .unwrap_or_else(|e| panic!("{json} is not a glTF sampler: {e}"));
        position(self.root.push(sampler))
    }

    /// Makes `texture` sample through `sampler` (from [`GltfWriter::add_sampler`]).
    pub fn set_texture_sampler(&mut self, texture: usize, sampler: usize) {
        self.root.textures[texture].sampler = Some(index(sampler));
    }

    /// Adds an RGBA8 image encoded as PNG; returns the texture index.
    pub fn add_texture_png(
        &mut self,
        name: &str,
        img: &image::RgbaImage,
        storage: ImageStorage,
    ) -> usize {
        self.add_texture_bytes(name, encode_png(img), storage)
    }
}

/// The textureInfo `key`'s extensions: its `KHR_texture_transform`, if `m` gives one.
fn transform(m: &MaterialDesc, key: &str) -> Option<Members> {
    let (_, t) = m.texture_transforms.iter().find(|(k, _)| *k == key)?;
    Some(json_object(&format!("{{\"KHR_texture_transform\":{t}}}")))
}

/// A JSON object's members: what gltf::json keeps of extensions it does not model.
type Members = serde_json::Map<String, json::Value>;

/// The members of the JSON object `text`.
fn json_object(text: &str) -> Members {
    match json::deserialize::from_str(text) {
        Ok(json::Value::Object(members)) => members,
        _ => panic!("{text} is not a JSON object"),
    }
}

/// PNG bytes of an RGBA8 image.
pub fn encode_png(img: &image::RgbaImage) -> Vec<u8> {
    let mut out = Vec::new();
    img.write_to(&mut io::Cursor::new(&mut out), image::ImageFormat::Png)
        .expect("PNG encoding into memory cannot fail");
    out
}
