//! A small glTF 2.0 writer, for tests and benchmarks: builds documents with meshes, materials,
//! PNG textures, KHR_lights_punctual lights, cameras and a node hierarchy, and writes them as
//! .gltf (external .bin or embedded base64 buffer) or .glb.

use super::gltf_import::base64_encode;
use glam::{Quat, Vec2, Vec3, Vec4};
use std::fmt::Write as _;
use std::io;
use std::path::Path;

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
    /// Accessor of the vertex positions (`POSITION`, from [`GltfWriter::add_positions`]).
    pub positions: usize,
    /// Accessor of the vertex normals (`NORMAL`).
    pub normals: Option<usize>,
    /// Accessor of the texture coordinates (`TEXCOORD_0`).
    pub uvs: Option<usize>,
    /// Accessor of the tangents (`TANGENT`, xyz and handedness w).
    pub tangents: Option<usize>,
    /// Accessor of the indices (from [`GltfWriter::add_indices`]); `None` for a non-indexed
    /// primitive.
    pub indices: Option<usize>,
    /// Material index (from [`GltfWriter::add_material`]); `None` leaves the glTF default
    /// material.
    pub material: Option<usize>,
    /// glTF primitive mode (4 = triangles).
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
    /// Texture indices from [`GltfWriter::add_texture_bytes`].
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
    /// (`"KHR_materials_unlit":{}`).
    pub extensions: Option<String>,
    /// A `KHR_texture_transform` object (JSON text) per textureInfo key
    /// (`"baseColorTexture"`, `"normalTexture"`, ...).
    pub texture_transforms: Vec<(&'static str, String)>,
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
    /// Mesh index (from [`GltfWriter::add_mesh`]).
    pub mesh: Option<usize>,
    /// Camera index (from [`GltfWriter::add_camera`]).
    pub camera: Option<usize>,
    /// KHR_lights_punctual light index (from [`GltfWriter::add_light`]).
    pub light: Option<usize>,
    /// Child node indices (from [`GltfWriter::add_node`]).
    pub children: Vec<usize>,
}

/// Builds a glTF document in memory.
#[derive(Default)]
pub struct GltfWriter {
    bin: Vec<u8>,
    views: Vec<String>,
    accessors: Vec<String>,
    meshes: Vec<String>,
    materials: Vec<String>,
    textures: Vec<String>,
    samplers: Vec<String>,
    images: Vec<(String, ImageStorage, Vec<u8>)>,
    nodes: Vec<String>,
    cameras: Vec<String>,
    lights: Vec<String>,
    roots: Vec<usize>,
    /// Extra names for `extensionsRequired` (to test refusal).
    pub extensions_required: Vec<String>,
}

fn js(s: &str) -> String {
    let mut o = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            c if (c as u32) < 0x20 => {
                let _ = write!(o, "\\u{:04x}", c as u32);
            }
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

fn arr(v: &[f32]) -> String {
    let parts: Vec<String> = v.iter().map(|x| format!("{x:?}")).collect();
    format!("[{}]", parts.join(","))
}

impl GltfWriter {
    /// An empty document: no meshes, nodes or buffer data.
    pub fn new() -> Self {
        Self::default()
    }

    fn push_view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        let target = target
            .map(|t| format!(",\"target\":{t}"))
            .unwrap_or_default();
        self.views.push(format!(
            "{{\"buffer\":0,\"byteOffset\":{offset},\"byteLength\":{}{target}}}",
            bytes.len()
        ));
        self.views.len() - 1
    }

    fn float_accessor(&mut self, data: &[f32], comps: usize, ty: &str, minmax: bool) -> usize {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let view = self.push_view(bytes, Some(34962));
        let count = data.len() / comps;
        let mut extra = String::new();
        if minmax && count > 0 {
            let mut lo = vec![f32::INFINITY; comps];
            let mut hi = vec![f32::NEG_INFINITY; comps];
            for e in data.chunks_exact(comps) {
                for c in 0..comps {
                    lo[c] = lo[c].min(e[c]);
                    hi[c] = hi[c].max(e[c]);
                }
            }
            if lo.iter().chain(&hi).all(|v| v.is_finite()) {
                extra = format!(",\"min\":{},\"max\":{}", arr(&lo), arr(&hi));
            }
        }
        self.accessors.push(format!(
            "{{\"bufferView\":{view},\"componentType\":5126,\"count\":{count},\"type\":\"{ty}\"{extra}}}"
        ));
        self.accessors.len() - 1
    }

    /// Adds a VEC3 float accessor with min/max (as glTF requires for `POSITION`); returns
    /// its index.
    pub fn add_positions(&mut self, p: &[Vec3]) -> usize {
        self.float_accessor(bytemuck::cast_slice(p), 3, "VEC3", true)
    }
    /// Adds a VEC3 float accessor (normals); returns its index.
    pub fn add_vec3(&mut self, v: &[Vec3]) -> usize {
        self.float_accessor(bytemuck::cast_slice(v), 3, "VEC3", false)
    }
    /// Adds a VEC2 float accessor (texture coordinates); returns its index.
    pub fn add_vec2(&mut self, v: &[Vec2]) -> usize {
        self.float_accessor(bytemuck::cast_slice(v), 2, "VEC2", false)
    }
    /// Adds a VEC4 float accessor (tangents); returns its index.
    pub fn add_vec4(&mut self, v: &[Vec4]) -> usize {
        self.float_accessor(bytemuck::cast_slice(v), 4, "VEC4", false)
    }

    /// Index accessor: u16 when every index fits, else u32.
    pub fn add_indices(&mut self, idx: &[u32]) -> usize {
        let (bytes, ct): (Vec<u8>, u32) = if idx.iter().all(|&i| i < 65535) {
            let v: Vec<u16> = idx.iter().map(|&i| i as u16).collect();
            (bytemuck::cast_slice(&v).to_vec(), 5123)
        } else {
            (bytemuck::cast_slice(idx).to_vec(), 5125)
        };
        let view = self.push_view(&bytes, Some(34963));
        self.accessors.push(format!(
            "{{\"bufferView\":{view},\"componentType\":{ct},\"count\":{},\"type\":\"SCALAR\"}}",
            idx.len()
        ));
        self.accessors.len() - 1
    }

    /// Adds a mesh of these primitives; returns the mesh index.
    pub fn add_mesh(&mut self, name: &str, prims: &[PrimitiveDesc]) -> usize {
        let ps: Vec<String> = prims
            .iter()
            .map(|p| {
                let mut attrs = format!("\"POSITION\":{}", p.positions);
                if let Some(n) = p.normals {
                    let _ = write!(attrs, ",\"NORMAL\":{n}");
                }
                if let Some(n) = p.uvs {
                    let _ = write!(attrs, ",\"TEXCOORD_0\":{n}");
                }
                if let Some(n) = p.tangents {
                    let _ = write!(attrs, ",\"TANGENT\":{n}");
                }
                let mut s = format!("{{\"attributes\":{{{attrs}}}");
                if let Some(i) = p.indices {
                    let _ = write!(s, ",\"indices\":{i}");
                }
                if let Some(m) = p.material {
                    let _ = write!(s, ",\"material\":{m}");
                }
                if let Some(m) = p.mode {
                    let _ = write!(s, ",\"mode\":{m}");
                }
                s.push('}');
                s
            })
            .collect();
        self.meshes.push(format!(
            "{{\"name\":{},\"primitives\":[{}]}}",
            js(name),
            ps.join(",")
        ));
        self.meshes.len() - 1
    }

    /// Adds a mesh of one primitive from raw arrays (normals/uvs optional, indexed or not).
    pub fn add_simple_mesh(
        &mut self,
        name: &str,
        positions: &[Vec3],
        normals: Option<&[Vec3]>,
        uvs: Option<&[Vec2]>,
        indices: Option<&[u32]>,
        material: Option<usize>,
    ) -> usize {
        let prim = PrimitiveDesc {
            positions: self.add_positions(positions),
            normals: normals.map(|n| self.add_vec3(n)),
            uvs: uvs.map(|u| self.add_vec2(u)),
            tangents: None,
            indices: indices.map(|i| self.add_indices(i)),
            material,
            mode: None,
        };
        self.add_mesh(name, &[prim])
    }

    /// Adds a metallic-roughness material; returns its index.
    pub fn add_material(&mut self, m: &MaterialDesc) -> usize {
        let tex = |key: &str, i: Option<usize>| {
            i.map(
                |i| match m.texture_transforms.iter().find(|(k, _)| *k == key) {
                    Some((_, t)) => format!(
                        "{{\"index\":{i},\"extensions\":{{\"KHR_texture_transform\":{t}}}}}"
                    ),
                    None => format!("{{\"index\":{i}}}"),
                },
            )
        };
        let mut pbr = format!(
            "\"baseColorFactor\":{},\"metallicFactor\":{:?},\"roughnessFactor\":{:?}",
            arr(&m.base_color.to_array()),
            m.metallic,
            m.roughness
        );
        if let Some(t) = tex("baseColorTexture", m.base_color_texture) {
            let _ = write!(pbr, ",\"baseColorTexture\":{t}");
        }
        if let Some(t) = tex("metallicRoughnessTexture", m.metallic_roughness_texture) {
            let _ = write!(pbr, ",\"metallicRoughnessTexture\":{t}");
        }
        let mut s = format!(
            "{{\"name\":{},\"pbrMetallicRoughness\":{{{pbr}}},\"emissiveFactor\":{},\"alphaMode\":\"{}\",\"doubleSided\":{}",
            js(&m.name),
            arr(&m.emissive.to_array()),
            m.alpha_mode,
            m.double_sided
        );
        if let Some(c) = m.alpha_cutoff {
            let _ = write!(s, ",\"alphaCutoff\":{c:?}");
        }
        for (k, t) in [
            ("normalTexture", m.normal_texture),
            ("emissiveTexture", m.emissive_texture),
            ("occlusionTexture", m.occlusion_texture),
        ] {
            if let Some(t) = tex(k, t) {
                let _ = write!(s, ",\"{k}\":{t}");
            }
        }
        if let Some(e) = &m.extensions {
            let _ = write!(s, ",\"extensions\":{{{e}}}");
        }
        s.push('}');
        self.materials.push(s);
        self.materials.len() - 1
    }

    /// Adds an image from PNG (or JPEG) bytes and a texture using it; returns the texture index.
    pub fn add_texture_bytes(
        &mut self,
        name: &str,
        encoded: Vec<u8>,
        storage: ImageStorage,
    ) -> usize {
        let view = if storage == ImageStorage::BufferView {
            Some(self.push_view(&encoded, None))
        } else {
            None
        };
        let image_json = match (&storage, view) {
            (ImageStorage::File(uri), _) => {
                format!("{{\"name\":{},\"uri\":{}}}", js(name), js(uri))
            }
            (ImageStorage::DataUri, _) => format!(
                "{{\"name\":{},\"uri\":\"data:image/png;base64,{}\"}}",
                js(name),
                base64_encode(&encoded)
            ),
            (ImageStorage::BufferView, Some(v)) => format!(
                "{{\"name\":{},\"bufferView\":{v},\"mimeType\":\"image/png\"}}",
                js(name)
            ),
            _ => unreachable!(),
        };
        self.images.push((image_json, storage, encoded));
        self.textures
            .push(format!("{{\"source\":{}}}", self.images.len() - 1));
        self.textures.len() - 1
    }

    /// Adds a sampler from its JSON text (`{"wrapS":33071}`); returns its index.
    pub fn add_sampler(&mut self, json: &str) -> usize {
        self.samplers.push(json.to_string());
        self.samplers.len() - 1
    }

    /// Makes `texture` sample through `sampler` (from [`GltfWriter::add_sampler`]).
    pub fn set_texture_sampler(&mut self, texture: usize, sampler: usize) {
        let t = &mut self.textures[texture];
        t.pop();
        let _ = write!(t, ",\"sampler\":{sampler}}}");
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

    /// Adds a perspective camera (`yfov` in radians, `znear`, optional `zfar`; infinite when
    /// `None`); returns its index.
    pub fn add_camera(&mut self, yfov: f32, znear: f32, zfar: Option<f32>) -> usize {
        let far = zfar.map(|f| format!(",\"zfar\":{f:?}")).unwrap_or_default();
        self.cameras.push(format!(
            "{{\"type\":\"perspective\",\"perspective\":{{\"yfov\":{yfov:?},\"znear\":{znear:?}{far}}}}}"
        ));
        self.cameras.len() - 1
    }

    /// A KHR_lights_punctual light. `spot`: (inner, outer) cone angles in radians.
    pub fn add_light(
        &mut self,
        name: &str,
        color: Vec3,
        intensity: f32,
        range: Option<f32>,
        spot: Option<(f32, f32)>,
    ) -> usize {
        let mut s = format!(
            "{{\"name\":{},\"color\":{},\"intensity\":{intensity:?}",
            js(name),
            arr(&color.to_array())
        );
        if let Some(r) = range {
            let _ = write!(s, ",\"range\":{r:?}");
        }
        match spot {
            Some((i, o)) => {
                let _ = write!(
                    s,
                    ",\"type\":\"spot\",\"spot\":{{\"innerConeAngle\":{i:?},\"outerConeAngle\":{o:?}}}}}"
                );
            }
            None => s.push_str(",\"type\":\"point\"}"),
        }
        self.lights.push(s);
        self.lights.len() - 1
    }

    /// Adds a node; returns its index (make it a root with [`GltfWriter::add_root`], or a
    /// child of another node).
    pub fn add_node(&mut self, n: &NodeDesc) -> usize {
        let mut s = String::from("{");
        let mut fields = Vec::new();
        if let Some(name) = &n.name {
            fields.push(format!("\"name\":{}", js(name)));
        }
        if let Some(t) = n.translation {
            fields.push(format!("\"translation\":{}", arr(&t.to_array())));
        }
        if let Some(r) = n.rotation {
            fields.push(format!("\"rotation\":{}", arr(&r.to_array())));
        }
        if let Some(sc) = n.scale {
            fields.push(format!("\"scale\":{}", arr(&sc.to_array())));
        }
        if let Some(m) = n.mesh {
            fields.push(format!("\"mesh\":{m}"));
        }
        if let Some(c) = n.camera {
            fields.push(format!("\"camera\":{c}"));
        }
        if let Some(l) = n.light {
            fields.push(format!(
                "\"extensions\":{{\"KHR_lights_punctual\":{{\"light\":{l}}}}}"
            ));
        }
        if !n.children.is_empty() {
            let c: Vec<String> = n.children.iter().map(|c| c.to_string()).collect();
            fields.push(format!("\"children\":[{}]", c.join(",")));
        }
        s.push_str(&fields.join(","));
        s.push('}');
        self.nodes.push(s);
        self.nodes.len() - 1
    }

    /// Makes a node a root of the (single) scene.
    pub fn add_root(&mut self, node: usize) {
        self.roots.push(node);
    }

    /// The JSON text; `buffer_uri` is the buffer's URI (`None` for GLB's binary chunk).
    pub fn to_json(&self, buffer_uri: Option<&str>) -> String {
        let list = |v: &[String]| format!("[{}]", v.join(","));
        let mut s = String::from(
            "{\"asset\":{\"version\":\"2.0\",\"generator\":\"lightgraph gltf_writer\"}",
        );
        let mut used = Vec::new();
        if !self.lights.is_empty() {
            used.push("\"KHR_lights_punctual\"".to_string());
        }
        used.extend(self.extensions_required.iter().map(|e| js(e)));
        if !used.is_empty() {
            let _ = write!(s, ",\"extensionsUsed\":[{}]", used.join(","));
        }
        if !self.extensions_required.is_empty() {
            let r: Vec<String> = self.extensions_required.iter().map(|e| js(e)).collect();
            let _ = write!(s, ",\"extensionsRequired\":[{}]", r.join(","));
        }
        let roots: Vec<String> = self.roots.iter().map(|r| r.to_string()).collect();
        let _ = write!(
            s,
            ",\"scene\":0,\"scenes\":[{{\"nodes\":[{}]}}]",
            roots.join(",")
        );
        for (k, v) in [
            ("nodes", &self.nodes),
            ("meshes", &self.meshes),
            ("materials", &self.materials),
            ("textures", &self.textures),
            ("samplers", &self.samplers),
            ("accessors", &self.accessors),
            ("bufferViews", &self.views),
            ("cameras", &self.cameras),
        ] {
            if !v.is_empty() {
                let _ = write!(s, ",\"{k}\":{}", list(v));
            }
        }
        if !self.images.is_empty() {
            let imgs: Vec<String> = self.images.iter().map(|i| i.0.clone()).collect();
            let _ = write!(s, ",\"images\":{}", list(&imgs));
        }
        if !self.bin.is_empty() {
            let uri = buffer_uri
                .map(|u| format!(",\"uri\":{}", js(u)))
                .unwrap_or_default();
            let _ = write!(
                s,
                ",\"buffers\":[{{\"byteLength\":{}{uri}}}]",
                self.bin.len()
            );
        }
        if !self.lights.is_empty() {
            let _ = write!(
                s,
                ",\"extensions\":{{\"KHR_lights_punctual\":{{\"lights\":{}}}}}",
                list(&self.lights)
            );
        }
        s.push('}');
        s
    }

    fn write_image_files(&self, dir: &Path) -> io::Result<()> {
        for (_, storage, bytes) in &self.images {
            if let ImageStorage::File(uri) = storage {
                std::fs::write(dir.join(uri), bytes)?;
            }
        }
        Ok(())
    }

    /// Writes a .gltf (and its .bin and image files, beside it).
    pub fn write_gltf(&self, path: &Path, buffers: &BufferStorage) -> io::Result<()> {
        let dir = path.parent().unwrap_or(Path::new("."));
        self.write_image_files(dir)?;
        let json = match buffers {
            BufferStorage::External(uri) => {
                std::fs::write(dir.join(uri), &self.bin)?;
                self.to_json(Some(uri))
            }
            BufferStorage::Embedded => {
                let uri = format!(
                    "data:application/octet-stream;base64,{}",
                    base64_encode(&self.bin)
                );
                self.to_json(Some(&uri))
            }
        };
        std::fs::write(path, json)
    }

    /// The GLB bytes (JSON chunk + binary chunk).
    pub fn to_glb(&self) -> Vec<u8> {
        let mut json = self.to_json(None).into_bytes();
        while !json.len().is_multiple_of(4) {
            json.push(b' ');
        }
        let mut bin = self.bin.clone();
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let total = 12 + 8 + json.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json);
        if !bin.is_empty() {
            out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
            out.extend_from_slice(b"BIN\0");
            out.extend_from_slice(&bin);
        }
        out
    }

    /// Writes a .glb (image files with [`ImageStorage::File`] go beside it).
    pub fn write_glb(&self, path: &Path) -> io::Result<()> {
        let dir = path.parent().unwrap_or(Path::new("."));
        self.write_image_files(dir)?;
        std::fs::write(path, self.to_glb())
    }
}

/// PNG bytes of an RGBA8 image.
pub fn encode_png(img: &image::RgbaImage) -> Vec<u8> {
    let mut out = Vec::new();
    img.write_to(&mut io::Cursor::new(&mut out), image::ImageFormat::Png)
        .expect("PNG encoding into memory cannot fail");
    out
}

/// A `cells × cells` grid of quads (2 triangles each) in the XZ plane, size `size`, with
/// normals and UVs: (positions, normals, uvs, indices).
pub fn grid(cells: u32, size: f32) -> (Vec<Vec3>, Vec<Vec3>, Vec<Vec2>, Vec<u32>) {
    let n = cells + 1;
    let mut p = Vec::with_capacity((n * n) as usize);
    let mut uv = Vec::with_capacity((n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (i as f32 / cells as f32, j as f32 / cells as f32);
            p.push(Vec3::new((u - 0.5) * size, 0.0, (v - 0.5) * size));
            uv.push(Vec2::new(u, v));
        }
    }
    let normals = vec![Vec3::Y; p.len()];
    let mut idx = Vec::with_capacity((cells * cells * 6) as usize);
    for j in 0..cells {
        for i in 0..cells {
            let a = j * n + i;
            let (b, c, d) = (a + 1, a + n + 1, a + n);
            idx.extend_from_slice(&[a, d, c, a, c, b]);
        }
    }
    (p, normals, uv, idx)
}

/// Writes a .glb of one grid mesh of at least `triangles` triangles (for benchmarks).
pub fn write_grid_glb(path: &Path, triangles: u32) -> io::Result<()> {
    let cells = ((triangles as f64 / 2.0).sqrt().ceil() as u32).max(1);
    let (p, n, uv, idx) = grid(cells, 100.0);
    let mut w = GltfWriter::new();
    let m = w.add_material(&MaterialDesc::default());
    let mesh = w.add_simple_mesh("grid", &p, Some(&n), Some(&uv), Some(&idx), Some(m));
    let node = w.add_node(&NodeDesc {
        mesh: Some(mesh),
        ..Default::default()
    });
    w.add_root(node);
    w.write_glb(path)
}
