//! The import driver: parse and validate the document, index its images, then flatten the
//! node graph into world space (meshes, the first perspective camera, punctual lights).

use super::camera::FoundCamera;
use super::images::ImageSource;
use super::lights::PendingLight;
use super::{named, Importer, SUPPORTED_EXTENSIONS};
use crate::scene::error::SceneError;
use crate::scene::lights::fit_camera;
use crate::scene::types::Camera;
use glam::{Mat4, Vec3};

impl Importer {
    pub(super) fn run(&mut self, bytes: &[u8]) -> Result<(), SceneError> {
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
        self.check_expansion(root)?;
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
            // As for a scene file's model: no normals, no winding, nothing to see.
            if local.determinant() == 0.0 {
                return Err(self.err(
                    element,
                    "transform is not invertible (a scale of 0 or an all-zero matrix)",
                ));
            }
            let world = parent * local;
            if let Some(mesh) = node.mesh() {
                self.import_mesh(&mesh, &world, node.weights())?;
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
                // Whether this fitted camera is used (and worth a warning) is the
                // caller's to say: a scene file may give its own.
                if let Some(b) = bounds {
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
}
