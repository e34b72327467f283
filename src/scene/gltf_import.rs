//! glTF 2.0 import (.gltf with external or embedded buffers, .glb) into a world-space
//! [`Scene`].
//!
//! Buffers, accessors and images are read here (not through `gltf::import`) so that every
//! failure is an error naming the file and the element, bounds are checked before anything is
//! sliced, and a missing texture only costs a warning.

use super::error::SceneError;
use super::geometry::{compute_normals, compute_tangents};
use super::lights::fit_camera;
use super::types::{
    AlphaMode, Camera, Light, LightShape, Mesh, Scene, SurfaceMaterial, TextureImage,
};
use super::Loaded;
use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Extensions this importer understands; any other in `extensionsRequired` is refused.
pub const SUPPORTED_EXTENSIONS: &[&str] =
    &["KHR_lights_punctual", "KHR_materials_emissive_strength"];

/// Safety limits: inputs past them are refused with a [`SceneError::Limit`].
#[derive(Clone, Copy, Debug)]
pub struct ImportLimits {
    /// Elements in one accessor.
    pub max_accessor_count: u64,
    /// Triangles in the whole scene.
    pub max_triangles: u64,
    /// Declared `byteLength` of one buffer.
    pub max_buffer_bytes: u64,
    pub max_nodes: u64,
    pub max_lights: u64,
    /// Pixels in one decoded image.
    pub max_image_pixels: u64,
}

impl Default for ImportLimits {
    fn default() -> Self {
        ImportLimits {
            max_accessor_count: 1 << 27,
            max_triangles: 1 << 26,
            max_buffer_bytes: 1 << 32,
            max_nodes: 1 << 20,
            max_lights: 1 << 20,
            max_image_pixels: 1 << 26,
        }
    }
}

/// Lights without a `range` get the distance where `intensity · max(colour) / d²` falls to
/// this illuminance (lux), capped at twice the scene's diagonal.
pub const INFINITE_RANGE_CUTOFF: f32 = 1e-3;

/// Imports a .gltf or .glb file with default limits.
pub fn import_gltf(path: &Path) -> Result<Loaded, SceneError> {
    import_gltf_with(path, &ImportLimits::default())
}

/// Imports a .gltf or .glb file. Relative URIs resolve against the file's folder.
pub fn import_gltf_with(path: &Path, limits: &ImportLimits) -> Result<Loaded, SceneError> {
    import_gltf_inner(path, limits).map(|(l, _)| l)
}

/// Imports and tells whether the file had a perspective camera (else one was fitted).
pub(crate) fn import_gltf_inner(
    path: &Path,
    limits: &ImportLimits,
) -> Result<(Loaded, bool), SceneError> {
    let bytes = std::fs::read(path).map_err(|e| SceneError::io(path, e))?;
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
    import_slice_inner(bytes, base_dir, file, limits).map(|(l, _)| l)
}

fn import_slice_inner(
    bytes: &[u8],
    base_dir: &Path,
    file: &Path,
    limits: &ImportLimits,
) -> Result<(Loaded, bool), SceneError> {
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
        files_read: std::cell::RefCell::new(vec![file.to_path_buf()]),
    };
    imp.run(bytes)?;
    Ok((
        Loaded {
            scene: imp.scene,
            warnings: imp.warnings,
            files: imp.files_read.into_inner(),
        },
        imp.has_camera,
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
    /// The glTF file and every external buffer and image read for it.
    files_read: std::cell::RefCell<Vec<PathBuf>>,
}

fn named(kind: &str, index: usize, name: Option<&str>) -> String {
    match name {
        Some(n) => format!("{kind} {index} (\"{n}\")"),
        None => format!("{kind} {index}"),
    }
}

/// (element name, world matrix, (yfov, znear, zfar)).
type FoundCamera = (String, Mat4, (f32, f32, Option<f32>));

struct PendingLight {
    element: String,
    position: Vec3,
    direction: Vec3,
    color: Vec3,
    intensity: f32,
    range: Option<f32>,
    spot: Option<(f32, f32)>,
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

    fn run(&mut self, bytes: &[u8]) -> Result<(), SceneError> {
        let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| match e {
            gltf::Error::Deserialize(e) => SceneError::Parse {
                file: self.file.clone(),
                line: e.line(),
                col: e.column(),
                message: format!("invalid glTF JSON: {e}"),
            },
            gltf::Error::Binary(e) => self.err("GLB container", e),
            e => self.err("document", e),
        })?;
        let root = gltf.as_json();
        for (i, ext) in root.extensions_required.iter().enumerate() {
            if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
                return Err(self.err(
                    format!("extensionsRequired[{i}]"),
                    format!("unsupported required extension \"{ext}\""),
                ));
            }
        }
        self.limit(
            "nodes",
            "node count",
            root.nodes.len() as u64,
            self.limits.max_nodes,
        )?;
        self.precheck(root)?;
        {
            use gltf::json::validation::Validate;
            let mut errors = Vec::new();
            let mut lenient = Vec::new();
            root.validate(root, gltf::json::Path::new, &mut |path, error| {
                let path = path().to_string();
                // POSITION min/max are required by the spec but often missing; bounds are
                // computed from the data anyway.
                if matches!(error, gltf::json::validation::Error::Missing)
                    && (path.ends_with(".min") || path.ends_with(".max"))
                {
                    lenient.push(path);
                } else {
                    errors.push(format!("{path}: {error}"))
                }
            });
            if let Some(first) = lenient.first() {
                self.warn(format!("{first}: missing (not required by this importer)"));
            }
            if !errors.is_empty() {
                let first = errors[0].clone();
                let more = if errors.len() > 1 {
                    format!(" (and {} more)", errors.len() - 1)
                } else {
                    String::new()
                };
                return Err(self.err("glTF validation", format!("{first}{more}")));
            }
        }
        self.scene.name = self
            .file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        self.load_buffers(&gltf)?;
        for (i, img) in root.images.iter().enumerate() {
            // Read from the JSON: the gltf crate's `Image::source` unwraps mimeType.
            let (src, name) = match (&img.buffer_view, &img.uri) {
                (Some(view), _) => {
                    let v = &root.buffer_views[view.value()];
                    (
                        ImageSource::View {
                            buffer: v.buffer.value(),
                            offset: v.byte_offset.map(|o| o.0 as usize).unwrap_or(0),
                            length: v.byte_length.0 as usize,
                        },
                        format!("image{i}"),
                    )
                }
                (None, Some(uri)) => (
                    ImageSource::Uri(uri.clone()),
                    if uri.starts_with("data:") {
                        format!("image{i}")
                    } else {
                        uri.clone()
                    },
                ),
                (None, None) => (ImageSource::Missing, format!("image{i}")),
            };
            let img_name = img.name.clone();
            self.image_sources.push(src);
            self.image_names.push(img_name.unwrap_or(name));
        }

        // Scene graph: flatten into world space.
        let roots: Vec<gltf::Node> = match gltf.default_scene().or_else(|| gltf.scenes().next()) {
            Some(s) => s.nodes().collect(),
            None => {
                let mut child = vec![false; gltf.nodes().len()];
                for n in gltf.nodes() {
                    for c in n.children() {
                        child[c.index()] = true;
                    }
                }
                gltf.nodes().filter(|n| !child[n.index()]).collect()
            }
        };
        let node_count = gltf.nodes().len();
        let mut stack: Vec<(gltf::Node, Mat4, usize)> = roots
            .into_iter()
            .rev()
            .map(|n| (n, Mat4::IDENTITY, 0))
            .collect();
        let mut camera: Option<FoundCamera> = None;
        let mut lights = Vec::new();
        let mut visits = 0u64;
        while let Some((node, parent, depth)) = stack.pop() {
            let element = named("node", node.index(), node.name());
            visits += 1;
            // Nodes reachable along many paths (not a tree) could explode exponentially.
            self.limit(
                &element,
                "node instance count",
                visits,
                self.limits.max_nodes,
            )?;
            if depth > node_count {
                return Err(self.err(element, "node hierarchy contains a cycle"));
            }
            let local = Mat4::from_cols_array_2d(&node.transform().matrix());
            if !local.is_finite() {
                return Err(self.err(element, "transform is not finite (NaN or Inf)"));
            }
            let world = parent * local;
            if let Some(mesh) = node.mesh() {
                self.import_mesh(&mesh, &world)?;
            }
            if let Some(cam) = node.camera() {
                match cam.projection() {
                    gltf::camera::Projection::Perspective(p) => {
                        if camera.is_none() {
                            let lens = (p.yfov(), p.znear(), p.zfar());
                            camera = Some((named("camera", cam.index(), cam.name()), world, lens));
                        }
                    }
                    gltf::camera::Projection::Orthographic(_) => self.warn(format!(
                        "{}: orthographic cameras are not supported; ignored",
                        named("camera", cam.index(), cam.name())
                    )),
                }
            }
            if let Some(light) = node.light() {
                let le = named("light", light.index(), light.name());
                let position = world.transform_point3(Vec3::ZERO);
                let direction = world.transform_vector3(-Vec3::Z).normalize_or_zero();
                let spot = match light.kind() {
                    gltf::khr_lights_punctual::Kind::Directional => {
                        self.warn(format!(
                            "{le}: directional lights are not supported; ignored"
                        ));
                        None
                    }
                    gltf::khr_lights_punctual::Kind::Point => Some(None),
                    gltf::khr_lights_punctual::Kind::Spot {
                        inner_cone_angle,
                        outer_cone_angle,
                    } => Some(Some((inner_cone_angle, outer_cone_angle))),
                };
                if let Some(spot) = spot {
                    lights.push(PendingLight {
                        element: format!("{le} on {element}"),
                        position,
                        direction,
                        color: Vec3::from(light.color()),
                        intensity: light.intensity(),
                        range: light.range(),
                        spot,
                    });
                    self.limit(
                        "lights",
                        "light count",
                        lights.len() as u64,
                        self.limits.max_lights,
                    )?;
                }
            }
            for c in node.children().collect::<Vec<_>>().into_iter().rev() {
                stack.push((c, world, depth + 1));
            }
        }

        let bounds = self.scene.bounds();
        let diag = bounds
            .map(|(lo, hi)| (hi - lo).length())
            .unwrap_or(10.0)
            .max(1e-3);
        for l in lights {
            let light = self.finish_light(l, diag)?;
            self.scene.lights.push(light);
        }
        self.scene.camera = match camera {
            Some((element, world, lens)) => {
                self.has_camera = true;
                self.make_camera(&element, world, lens, bounds)?
            }
            None => {
                if let Some(b) = bounds {
                    self.warn("no perspective camera; one was fitted to the scene bounds");
                    fit_camera(b)
                } else {
                    Camera::default()
                }
            }
        };
        if self.scene.meshes.is_empty() {
            self.warn("the scene has no triangle geometry");
        }
        Ok(())
    }

    /// Checks what the gltf crate's validation or accessors would panic on.
    fn precheck(&self, root: &gltf::json::Root) -> Result<(), SceneError> {
        use gltf::json::validation::Checked;
        for (mi, mesh) in root.meshes.iter().enumerate() {
            for (pi, prim) in mesh.primitives.iter().enumerate() {
                let pos = prim
                    .attributes
                    .get(&Checked::Valid(gltf::Semantic::Positions));
                if let Some(a) = pos {
                    if a.value() >= root.accessors.len() {
                        return Err(self.err(
                            format!("{} primitive {pi}", named("mesh", mi, mesh.name.as_deref())),
                            format!("POSITION accessor {} does not exist", a.value()),
                        ));
                    }
                }
            }
        }
        for (i, img) in root.images.iter().enumerate() {
            if let Some(v) = &img.buffer_view {
                if v.value() >= root.buffer_views.len() {
                    return Err(self.err(
                        named("image", i, img.name.as_deref()),
                        format!("bufferView {} does not exist", v.value()),
                    ));
                }
            }
        }
        for (i, cam) in root.cameras.iter().enumerate() {
            use gltf::json::camera::Type;
            let ok = match cam.type_ {
                Checked::Valid(Type::Perspective) => cam.perspective.is_some(),
                Checked::Valid(Type::Orthographic) => cam.orthographic.is_some(),
                Checked::Invalid => true, // reported by validation
            };
            if !ok {
                return Err(self.err(
                    named("camera", i, cam.name.as_deref()),
                    "the camera's projection object is missing",
                ));
            }
        }
        Ok(())
    }

    fn finish_light(&mut self, l: PendingLight, diag: f32) -> Result<Light, SceneError> {
        let bad = |what: &str, v: &dyn std::fmt::Display| {
            self.err(
                &l.element,
                format!("{what} {v} is not valid (NaN, Inf or out of range)"),
            )
        };
        if !l.position.is_finite() {
            return Err(bad("position", &l.position));
        }
        if !l.color.is_finite() || l.color.min_element() < 0.0 {
            return Err(bad("color", &l.color));
        }
        if !l.intensity.is_finite() || l.intensity < 0.0 {
            return Err(bad("intensity", &l.intensity));
        }
        let range = match l.range {
            Some(r) if r.is_finite() && r > 0.0 => r,
            Some(r) => return Err(bad("range", &r)),
            None => {
                let r = (l.intensity * l.color.max_element().max(1e-6) / INFINITE_RANGE_CUTOFF)
                    .sqrt()
                    .clamp(1e-3, 2.0 * diag);
                self.warn(format!(
                    "{}: no range (infinite); using {r:.3} (where intensity/d² < {INFINITE_RANGE_CUTOFF}, at most twice the scene diagonal)",
                    l.element
                ));
                r
            }
        };
        let shape = match l.spot {
            None => LightShape::Point,
            Some((inner, outer)) => {
                if !inner.is_finite()
                    || !outer.is_finite()
                    || inner < 0.0
                    || inner > outer
                    || outer > std::f32::consts::FRAC_PI_2 + 1e-6
                {
                    return Err(self.err(
                        &l.element,
                        format!("spot cone angles inner {inner}, outer {outer} need 0 <= inner <= outer <= pi/2"),
                    ));
                }
                if l.direction == Vec3::ZERO || !l.direction.is_finite() {
                    return Err(self.err(
                        &l.element,
                        "spot direction is degenerate (zero scale on its node)",
                    ));
                }
                LightShape::Spot {
                    direction: l.direction,
                    inner_angle: inner,
                    outer_angle: outer,
                }
            }
        };
        Ok(Light {
            position: l.position,
            range,
            color: l.color,
            intensity: l.intensity,
            shape,
            flags: 0,
            material_mask: u32::MAX,
        })
    }

    fn make_camera(
        &mut self,
        element: &str,
        world: Mat4,
        lens: (f32, f32, Option<f32>),
        bounds: Option<(Vec3, Vec3)>,
    ) -> Result<Camera, SceneError> {
        let eye = world.transform_point3(Vec3::ZERO);
        let fwd = world.transform_vector3(-Vec3::Z).normalize_or_zero();
        let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
        let (yfov, znear, zfar) = lens;
        if !eye.is_finite() || fwd == Vec3::ZERO || up == Vec3::ZERO || !fwd.is_finite() {
            return Err(self.err(element, "camera node transform is degenerate"));
        }
        if !(yfov.is_finite() && yfov > 0.0 && yfov < std::f32::consts::PI) {
            return Err(self.err(element, format!("yfov {yfov} must lie in (0, pi)")));
        }
        if !(znear.is_finite() && znear > 0.0) {
            return Err(self.err(element, format!("znear {znear} must be > 0")));
        }
        let far = match zfar {
            Some(f) if f.is_finite() && f > znear => f,
            Some(f) => {
                return Err(self.err(
                    element,
                    format!("zfar {f} must be finite and > znear {znear}"),
                ))
            }
            None => {
                // Infinite projection: reach past the farthest corner of the scene.
                let far = bounds
                    .map(|(lo, hi)| {
                        let c = (lo + hi) * 0.5;
                        (eye - c).length() + (hi - lo).length()
                    })
                    .unwrap_or(1000.0);
                far.max(znear * 10.0)
            }
        };
        Ok(Camera {
            eye,
            target: eye + fwd,
            up,
            fov_y: yfov,
            near: znear,
            far,
        })
    }

    fn load_buffers(&mut self, gltf: &gltf::Gltf) -> Result<(), SceneError> {
        for buffer in gltf.buffers() {
            let element = named("buffer", buffer.index(), buffer.name());
            let declared = buffer.length() as u64;
            self.limit(
                &element,
                "byteLength",
                declared,
                self.limits.max_buffer_bytes,
            )?;
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => match &gltf.blob {
                    Some(b) => b.clone(),
                    None => {
                        return Err(self.err(
                            element,
                            "refers to the GLB binary chunk, but the file has none",
                        ))
                    }
                },
                gltf::buffer::Source::Uri(uri) => self.read_uri(uri, &element)?,
            };
            if (data.len() as u64) < declared {
                return Err(self.err(
                    element,
                    format!("holds {} bytes but byteLength says {declared}", data.len()),
                ));
            }
            self.buffers.push(data);
        }
        Ok(())
    }

    fn read_uri(&self, uri: &str, element: &str) -> Result<Vec<u8>, SceneError> {
        if let Some(rest) = uri.strip_prefix("data:") {
            let Some((header, payload)) = rest.split_once(',') else {
                return Err(self.err(element, "malformed data URI (no ',')"));
            };
            if !header.ends_with(";base64") {
                return Err(self.err(element, "data URI is not base64-encoded"));
            }
            return base64_decode(payload)
                .map_err(|e| self.err(element, format!("bad base64 in data URI: {e}")));
        }
        if uri.contains("://") {
            return Err(self.err(element, format!("unsupported URI scheme in \"{uri}\"")));
        }
        let path = self.base_dir.join(percent_decode(uri));
        // Recorded even if the read fails: fixing the file should trigger a reload.
        self.files_read.borrow_mut().push(path.clone());
        std::fs::read(&path)
            .map_err(|e| self.err(element, format!("cannot read \"{}\": {e}", path.display())))
    }

    /// The bytes of a buffer view, bounds-checked.
    fn view_bytes(&self, view: &gltf::buffer::View, element: &str) -> Result<&[u8], SceneError> {
        let buf = &self.buffers[view.buffer().index()];
        let (off, len) = (view.offset() as u64, view.length() as u64);
        if off + len > buf.len() as u64 {
            return Err(self.err(
                element,
                format!(
                    "bufferView {} (offset {off}, length {len}) is out of bounds of buffer {} ({} bytes)",
                    view.index(),
                    view.buffer().index(),
                    buf.len()
                ),
            ));
        }
        Ok(&buf[off as usize..(off + len) as usize])
    }

    /// Reads an accessor into `count` rows of `N` components as f32 (normalized integers are
    /// mapped to [0, 1] / [-1, 1]).
    fn read_f32<const N: usize>(
        &self,
        acc: &gltf::Accessor,
        element: &str,
        allowed: &[DataType],
    ) -> Result<Vec<[f32; N]>, SceneError> {
        let dims = match N {
            1 => Dimensions::Scalar,
            2 => Dimensions::Vec2,
            3 => Dimensions::Vec3,
            _ => Dimensions::Vec4,
        };
        if acc.dimensions() != dims {
            return Err(self.err(
                element,
                format!("expected {dims:?}, found {:?}", acc.dimensions()),
            ));
        }
        let dt = acc.data_type();
        if !allowed.contains(&dt) || (dt != DataType::F32 && !acc.normalized()) {
            return Err(self.err(
                element,
                format!(
                    "unsupported component type {dt:?} (normalized: {})",
                    acc.normalized()
                ),
            ));
        }
        let (bytes, stride, count) = self.accessor_layout(acc, element)?;
        let cs = dt.size();
        let mut out = Vec::with_capacity(count);
        for i in 0..count {
            let e = &bytes[i * stride..];
            let mut v = [0f32; N];
            for (c, slot) in v.iter_mut().enumerate() {
                let b = &e[c * cs..c * cs + cs];
                *slot = match dt {
                    DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                    DataType::U8 => b[0] as f32 / 255.0,
                    DataType::I8 => (b[0] as i8 as f32 / 127.0).max(-1.0),
                    DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0,
                    DataType::I16 => (i16::from_le_bytes([b[0], b[1]]) as f32 / 32767.0).max(-1.0),
                    DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
                };
            }
            out.push(v);
        }
        Ok(out)
    }

    fn read_indices(&self, acc: &gltf::Accessor, element: &str) -> Result<Vec<u32>, SceneError> {
        if acc.dimensions() != Dimensions::Scalar {
            return Err(self.err(
                element,
                format!("indices must be SCALAR, found {:?}", acc.dimensions()),
            ));
        }
        let dt = acc.data_type();
        if !matches!(dt, DataType::U8 | DataType::U16 | DataType::U32) {
            return Err(self.err(
                element,
                format!("index component type {dt:?} is not unsigned"),
            ));
        }
        let (bytes, stride, count) = self.accessor_layout(acc, element)?;
        Ok((0..count)
            .map(|i| {
                let b = &bytes[i * stride..];
                match dt {
                    DataType::U8 => b[0] as u32,
                    DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
                    _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                }
            })
            .collect())
    }

    /// (bytes from the first element, stride, count), with every element proven in bounds.
    fn accessor_layout<'s>(
        &'s self,
        acc: &gltf::Accessor,
        element: &str,
    ) -> Result<(&'s [u8], usize, usize), SceneError> {
        let count = acc.count() as u64;
        self.limit(
            element,
            "accessor count",
            count,
            self.limits.max_accessor_count,
        )?;
        if acc.sparse().is_some() {
            return Err(self.err(element, "sparse accessors are not supported"));
        }
        let Some(view) = acc.view() else {
            return Err(self.err(element, "accessor has no bufferView"));
        };
        let elem = acc.size() as u64;
        let stride = view.stride().map(|s| s as u64).unwrap_or(elem);
        if stride < elem {
            return Err(self.err(
                element,
                format!("byteStride {stride} is smaller than the element size {elem}"),
            ));
        }
        let bytes = self.view_bytes(&view, element)?;
        let off = acc.offset() as u64;
        let needed = if count == 0 {
            0
        } else {
            off + stride * (count - 1) + elem
        };
        if needed > bytes.len() as u64 {
            return Err(self.err(
                element,
                format!(
                    "accessor out of bounds: {count} elements at offset {off} with stride {stride} need {needed} bytes, bufferView {} has {}",
                    view.index(),
                    bytes.len()
                ),
            ));
        }
        Ok((
            &bytes[off.min(bytes.len() as u64) as usize..],
            stride as usize,
            count as usize,
        ))
    }

    fn import_mesh(&mut self, mesh: &gltf::Mesh, world: &Mat4) -> Result<(), SceneError> {
        let mesh_el = named("mesh", mesh.index(), mesh.name());
        let prim_count = mesh.primitives().len();
        for prim in mesh.primitives() {
            let pel = format!("{mesh_el} primitive {}", prim.index());
            use gltf::mesh::Mode;
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                self.warn(format!(
                    "{pel}: {mode:?} primitives are not triangles; skipped"
                ));
                continue;
            }
            let Some(pos_acc) = prim.get(&gltf::Semantic::Positions) else {
                self.warn(format!("{pel}: no POSITION attribute; skipped"));
                continue;
            };
            let el =
                |sem: &str, acc: &gltf::Accessor| format!("{pel} {sem} accessor {}", acc.index());
            let pe = el("POSITION", &pos_acc);
            let local: Vec<[f32; 3]> = self.read_f32(&pos_acc, &pe, &[DataType::F32])?;
            let n = local.len();
            if let Some(i) = local.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
                return Err(self.err(
                    pe,
                    format!(
                        "vertex {i} position {:?} is not finite (NaN or Inf)",
                        local[i]
                    ),
                ));
            }
            let mut indices = match prim.indices() {
                Some(acc) => {
                    let ie = el("indices", &acc);
                    let idx = self.read_indices(&acc, &ie)?;
                    if let Some(k) = idx.iter().position(|&i| i as usize >= n) {
                        return Err(self.err(
                            ie,
                            format!("index {k} is {}, past the vertex count {n}", idx[k]),
                        ));
                    }
                    idx
                }
                None => (0..n as u32).collect(),
            };
            indices = match mode {
                Mode::TriangleStrip => (2..indices.len())
                    .flat_map(|i| {
                        let (a, b, c) = (indices[i - 2], indices[i - 1], indices[i]);
                        if i % 2 == 0 {
                            [a, b, c]
                        } else {
                            [a, c, b]
                        }
                    })
                    .collect(),
                Mode::TriangleFan => (2..indices.len())
                    .flat_map(|i| [indices[i - 1], indices[i], indices[0]])
                    .collect(),
                _ => indices,
            };
            if indices.len() % 3 != 0 {
                self.warn(format!(
                    "{pel}: {} indices is not a multiple of 3; the last {} ignored",
                    indices.len(),
                    indices.len() % 3
                ));
                indices.truncate(indices.len() / 3 * 3);
            }
            self.triangles += indices.len() as u64 / 3;
            self.limit(
                &pel,
                "scene triangle count",
                self.triangles,
                self.limits.max_triangles,
            )?;

            let read_attr = |this: &Self,
                             sem: gltf::Semantic,
                             name: &str|
             -> Result<Option<(gltf::Accessor, String)>, SceneError> {
                match prim.get(&sem) {
                    Some(acc) => {
                        let e = el(name, &acc);
                        if acc.count() != n {
                            return Err(this.err(
                                e,
                                format!("has {} elements but POSITION has {n}", acc.count()),
                            ));
                        }
                        Ok(Some((acc, e)))
                    }
                    None => Ok(None),
                }
            };
            let normals_local: Option<Vec<[f32; 3]>> =
                match read_attr(self, gltf::Semantic::Normals, "NORMAL")? {
                    Some((acc, e)) => {
                        let v = self.read_f32(&acc, &e, &[DataType::F32])?;
                        if v.iter().any(|p| !p.iter().all(|c| c.is_finite())) {
                            self.warn(format!("{e}: non-finite normals; normals regenerated"));
                            None
                        } else {
                            Some(v)
                        }
                    }
                    None => None,
                };
            let uvs: Vec<Vec2> = match read_attr(self, gltf::Semantic::TexCoords(0), "TEXCOORD_0")?
            {
                Some((acc, e)) => self
                    .read_f32::<2>(&acc, &e, &[DataType::F32, DataType::U8, DataType::U16])?
                    .into_iter()
                    .map(|[u, v]| {
                        if u.is_finite() && v.is_finite() {
                            Vec2::new(u, v)
                        } else {
                            Vec2::ZERO
                        }
                    })
                    .collect(),
                None => Vec::new(),
            };
            let tangents_local: Option<Vec<[f32; 4]>> =
                match read_attr(self, gltf::Semantic::Tangents, "TANGENT")? {
                    Some((acc, e)) => {
                        let v = self.read_f32(&acc, &e, &[DataType::F32])?;
                        if v.iter().any(|p| !p.iter().all(|c| c.is_finite())) {
                            self.warn(format!("{e}: non-finite tangents; tangents regenerated"));
                            None
                        } else {
                            Some(v)
                        }
                    }
                    None => None,
                };

            // To world space.
            let m3 = Mat3::from_mat4(*world);
            let det = m3.determinant();
            let normal_m = if det.abs() > 1e-30 {
                m3.inverse().transpose()
            } else {
                m3
            };
            let positions: Vec<Vec3> = local
                .iter()
                .map(|p| world.transform_point3(Vec3::from(*p)))
                .collect();
            if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
                return Err(self.err(
                    pe,
                    format!("vertex {i} is not finite after the node transforms"),
                ));
            }
            if det < 0.0 {
                // Mirroring transform: keep counter-clockwise front faces.
                for t in indices.chunks_exact_mut(3) {
                    t.swap(1, 2);
                }
            }
            let normals = match &normals_local {
                Some(v) => v
                    .iter()
                    .map(|n| {
                        (normal_m * Vec3::from(*n))
                            .try_normalize()
                            .unwrap_or(Vec3::Y)
                    })
                    .collect(),
                None => compute_normals(&positions, &indices),
            };
            let tangents = match &tangents_local {
                Some(v) if normals_local.is_some() => v
                    .iter()
                    .zip(&normals)
                    .map(|(t, n)| {
                        let t3 = (m3 * Vec3::new(t[0], t[1], t[2]))
                            .try_normalize()
                            .unwrap_or_else(|| super::geometry::any_perpendicular(*n));
                        let w = if t[3] < 0.0 { -1.0 } else { 1.0 } * det.signum();
                        t3.extend(w)
                    })
                    .collect::<Vec<Vec4>>(),
                _ => compute_tangents(&positions, &normals, &uvs, &indices),
            };
            let material = self.material(prim.material())?;
            let name = match (mesh.name(), prim_count) {
                (Some(nm), 1) => nm.to_string(),
                (Some(nm), _) => format!("{nm}/{}", prim.index()),
                (None, 1) => format!("mesh{}", mesh.index()),
                (None, _) => format!("mesh{}/{}", mesh.index(), prim.index()),
            };
            self.scene.meshes.push(Mesh {
                name,
                positions,
                normals,
                uvs,
                tangents,
                indices,
                material,
            });
        }
        Ok(())
    }

    fn material(&mut self, m: gltf::Material) -> Result<usize, SceneError> {
        if let Some(&i) = self.materials.get(&m.index()) {
            return Ok(i);
        }
        let element = match m.index() {
            Some(i) => named("material", i, m.name()),
            None => "default material".into(),
        };
        let pbr = m.pbr_metallic_roughness();
        let tex = |this: &mut Self, info: Option<(gltf::Texture, u32)>, slot: &str, srgb: bool| {
            let (t, set) = info?;
            if set != 0 {
                this.warn(format!(
                    "{element} {slot}: TEXCOORD_{set} is not supported; TEXCOORD_0 used"
                ));
            }
            this.texture(t.source().index(), srgb, &format!("{element} {slot}"))
        };
        let base_color_texture = tex(
            self,
            pbr.base_color_texture()
                .map(|i| (i.texture(), i.tex_coord())),
            "baseColorTexture",
            true,
        );
        let metallic_roughness_texture = tex(
            self,
            pbr.metallic_roughness_texture()
                .map(|i| (i.texture(), i.tex_coord())),
            "metallicRoughnessTexture",
            false,
        );
        let normal = m.normal_texture();
        let normal_scale = normal.as_ref().map(|n| n.scale()).unwrap_or(1.0);
        let normal_texture = tex(
            self,
            normal.map(|i| (i.texture(), i.tex_coord())),
            "normalTexture",
            false,
        );
        let occ = m.occlusion_texture();
        let occlusion_strength = occ.as_ref().map(|o| o.strength()).unwrap_or(1.0);
        let occlusion_texture = tex(
            self,
            occ.map(|i| (i.texture(), i.tex_coord())),
            "occlusionTexture",
            false,
        );
        let emissive_texture = tex(
            self,
            m.emissive_texture().map(|i| (i.texture(), i.tex_coord())),
            "emissiveTexture",
            true,
        );
        let base_color = Vec4::from(pbr.base_color_factor());
        let emissive = Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0);
        let (metallic, roughness) = (pbr.metallic_factor(), pbr.roughness_factor());
        let ok = base_color.is_finite()
            && emissive.is_finite()
            && metallic.is_finite()
            && roughness.is_finite();
        if !ok {
            return Err(self.err(element, "material factors are not finite"));
        }
        let alpha_mode = match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask(m.alpha_cutoff().unwrap_or(0.5)),
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        };
        let sm = SurfaceMaterial {
            name: m
                .name()
                .map(str::to_string)
                .unwrap_or_else(|| match m.index() {
                    Some(i) => format!("material{i}"),
                    None => "default".into(),
                }),
            base_color,
            metallic: metallic.clamp(0.0, 1.0),
            roughness: roughness.clamp(0.0, 1.0),
            emissive,
            alpha_mode,
            double_sided: m.double_sided(),
            type_bit: 1,
            base_color_texture,
            metallic_roughness_texture,
            normal_texture,
            normal_scale,
            emissive_texture,
            occlusion_texture,
            occlusion_strength,
        };
        let idx = self.scene.materials.len();
        self.scene.materials.push(sm);
        self.materials.insert(m.index(), idx);
        Ok(idx)
    }

    /// A texture, or `None` with a warning when the image is missing or undecodable (the
    /// material's factor then applies alone: a neutral texture).
    fn texture(&mut self, image: usize, srgb: bool, slot: &str) -> Option<Arc<TextureImage>> {
        if let Some(t) = self.textures.get(&(image, srgb)) {
            return t.clone();
        }
        let rgba = self.decode_image(image, slot);
        let t = rgba.map(|img| {
            Arc::new(TextureImage {
                name: self.image_name(image),
                width: img.width(),
                height: img.height(),
                rgba8: img.as_raw().clone(),
                srgb,
            })
        });
        self.textures.insert((image, srgb), t.clone());
        t
    }

    fn image_name(&self, image: usize) -> String {
        self.image_names
            .get(image)
            .cloned()
            .unwrap_or_else(|| format!("image{image}"))
    }

    fn decode_image(&mut self, index: usize, slot: &str) -> Option<Arc<image::RgbaImage>> {
        if let Some(i) = self.images.get(&index) {
            return i.clone();
        }
        let result = self.try_decode_image(index);
        let out = match result {
            Ok(img) => Some(Arc::new(img)),
            Err(msg) => {
                self.warn(format!(
                    "{slot}: image {index}: {msg}; using a neutral texture"
                ));
                None
            }
        };
        self.images.insert(index, out.clone());
        out
    }

    fn try_decode_image(&self, index: usize) -> Result<image::RgbaImage, String> {
        let src = self.image_sources.get(index).ok_or("no such image")?;
        let bytes: Vec<u8> = match src {
            ImageSource::Missing => return Err("the image has neither uri nor bufferView".into()),
            ImageSource::Uri(uri) => {
                self.read_uri(uri, &format!("image {index}"))
                    .map_err(|e| match e {
                        SceneError::Invalid { message, .. } => message,
                        e => e.to_string(),
                    })?
            }
            ImageSource::View {
                buffer,
                offset,
                length,
            } => {
                let buf = &self.buffers[*buffer];
                buf.get(*offset..offset.saturating_add(*length))
                    .ok_or("bufferView is out of bounds")?
                    .to_vec()
            }
        };
        let reader = image::ImageReader::new(std::io::Cursor::new(&bytes))
            .with_guessed_format()
            .map_err(|e| e.to_string())?;
        let (w, h) = reader
            .into_dimensions()
            .map_err(|e| format!("cannot decode: {e}"))?;
        if w as u64 * h as u64 > self.limits.max_image_pixels {
            return Err(format!(
                "{w}×{h} pixels exceeds the limit of {}",
                self.limits.max_image_pixels
            ));
        }
        let img = image::load_from_memory(&bytes).map_err(|e| format!("cannot decode: {e}"))?;
        Ok(img.to_rgba8())
    }
}

enum ImageSource {
    Missing,
    Uri(String),
    View {
        buffer: usize,
        offset: usize,
        length: usize,
    },
}

/// Decodes `%XX` escapes in a relative URI.
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            let hex = |c: u8| (c as char).to_digit(16);
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Standard base64 (RFC 4648, padding optional, whitespace ignored).
pub fn base64_decode(s: &str) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(s.len() / 4 * 3);
    let mut acc = 0u32;
    let mut bits = 0;
    for (i, c) in s.bytes().enumerate() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            b'=' => break,
            b' ' | b'\n' | b'\r' | b'\t' => continue,
            _ => return Err(format!("invalid character {:?} at {i}", c as char)),
        };
        acc = (acc << 6) | v as u32;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
        }
    }
    Ok(out)
}

/// Standard base64 with padding.
pub fn base64_encode(data: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(data.len().div_ceil(3) * 4);
    for chunk in data.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(T[(n >> (18 - 6 * k)) as usize & 63] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}
