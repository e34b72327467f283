//! Building a [`Scene`] from a parsed scene file: the built-in scene and the glTF models
//! placed by their transforms, the camera, the lights and light sets with their motion,
//! and every limit checked, each refusal naming the file and the field.

use super::{parse_scene_file, CameraSpec, LightSetSpec, SceneFile, MAX_SCENE_LIGHTS};
use crate::scene::error::SceneError;
use crate::scene::gltf_import::import_gltf_inner;
use crate::scene::lights::{amd_camera, fit_camera};
use crate::scene::model_budget::ModelBudget;
use crate::scene::types::{light_flags, Camera, LightShape, Scene};
use crate::scene::{builtin, Loaded};
use glam::{Mat3, Mat4, Vec3};
use std::path::Path;

/// Loads a scene RON file: parses it and builds the scene.
pub(crate) fn load_scene_file(path: &Path) -> Result<Loaded, SceneError> {
    let text = crate::files::read_text(path, crate::files::caps::RON)
        .map_err(|e| SceneError::io(path, e))?;
    let spec = parse_scene_file(&text, path)?;
    build_scene(&spec, path).map_err(|e| e.located_in(path, &text))
}

fn transform_scene(scene: &mut Scene, m: Mat4) {
    let m3 = Mat3::from_mat4(m);
    let det = m3.determinant();
    let nm = if det.abs() > 1e-30 {
        m3.inverse().transpose()
    } else {
        m3
    };
    for mesh in &mut scene.meshes {
        mesh.positions
            .iter_mut()
            .for_each(|p| *p = m.transform_point3(*p));
        mesh.normals
            .iter_mut()
            .for_each(|n| *n = (nm * *n).normalize_or(Vec3::Y));
        mesh.tangents.iter_mut().for_each(|t| {
            let v = (m3 * t.truncate()).normalize_or(Vec3::X);
            *t = v.extend(t.w * det.signum());
        });
        if det < 0.0 {
            mesh.indices.chunks_exact_mut(3).for_each(|t| t.swap(1, 2));
        }
    }
    for l in &mut scene.lights {
        l.position = m.transform_point3(l.position);
        if let LightShape::Spot { direction, .. } = &mut l.shape {
            *direction = (m3 * *direction).normalize_or(Vec3::NEG_Y);
        }
    }
    let c = &mut scene.camera;
    c.eye = m.transform_point3(c.eye);
    c.target = m.transform_point3(c.target);
    c.up = (m3 * c.up).normalize_or(Vec3::Y);
}

/// Records `motion` for the `count` lights about to be appended to `scene`.
fn add_motion(
    scene: &mut Scene,
    motion: Option<&crate::scene::motion::Motion>,
    count: u32,
    file: &Path,
    element: &str,
) -> Result<(), SceneError> {
    let Some(motion) = motion else {
        return Ok(());
    };
    motion
        .check()
        .map_err(|m| SceneError::invalid(file, element, format!("motion: {m}")))?;
    scene.light_motion.push(crate::scene::motion::LightMotion {
        first: scene.lights.len() as u32,
        count,
        motion: motion.clone(),
    });
    Ok(())
}

/// When the lights just added have a motion (the scene's last), checks that each stays
/// within the limits along it (`Motion::check_reach`); `set` is the count of a light
/// set's lights, named by their place in it.
fn check_reach(
    scene: &Scene,
    moving: bool,
    set: Option<u64>,
    file: &Path,
    element: &str,
) -> Result<(), SceneError> {
    let Some(m) = scene.light_motion.last().filter(|_| moving) else {
        return Ok(());
    };
    let first = m.first as usize;
    let end = (first + m.count as usize).min(scene.lights.len());
    for (i, light) in scene.lights[first..end].iter().enumerate() {
        m.motion.check_reach(light).map_err(|e| {
            let which = match set {
                Some(n) => format!("light {i} of {n}: "),
                None => String::new(),
            };
            SceneError::invalid(file, element, format!("motion: {which}{e}"))
        })?;
    }
    Ok(())
}

/// Builds a scene from a parsed scene file; `file` is the RON file (relative paths resolve
/// against its folder).
pub fn build_scene(spec: &SceneFile, file: &Path) -> Result<Loaded, SceneError> {
    let dir = file.parent().unwrap_or(Path::new("."));
    let mut warnings = Vec::new();
    let mut files = vec![file.to_path_buf()];
    let mut scene = Scene::default();
    let mut camera: Option<Camera> = None;
    if let Some(name) = &spec.builtin {
        scene = builtin::by_name(name).ok_or_else(|| {
            SceneError::invalid(
                file,
                "builtin",
                format!(
                    "unknown built-in scene \"{name}\" (known: {})",
                    builtin::NAMES.join(", ")
                ),
            )
        })?;
        camera = Some(scene.camera);
        if !spec.keep_model_lights {
            scene.lights.clear();
        }
    }
    let mut budget = ModelBudget::default();
    for (i, model) in spec.models.iter().enumerate() {
        let element = format!("models[{i}] (\"{}\")", model.path.display());
        let m = model.transform.matrix();
        if !m.is_finite() || m.determinant() == 0.0 {
            return Err(SceneError::invalid(
                file,
                element,
                "transform is not finite or not invertible",
            ));
        }
        let path = dir.join(&model.path);
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        if !matches!(ext.as_deref(), Some("gltf" | "glb")) {
            return Err(SceneError::invalid(
                file,
                element,
                "a model must be a .gltf or .glb file",
            ));
        }
        let (loaded, has_camera, expansion) =
            import_gltf_inner(&path, &budget.limits()).map_err(|e| match e {
                // Named from the scene file: the model path may be the mistake.
                SceneError::Io {
                    file: model,
                    source,
                } => SceneError::invalid(
                    file,
                    &element,
                    format!("cannot read {}: {source}", model.display()),
                ),
                e => budget.explain(file, &element, e),
            })?;
        budget.record(expansion);
        let mut sub = loaded.scene;
        warnings.extend(loaded.warnings);
        files.extend(loaded.files);
        transform_scene(&mut sub, m);
        let offset = scene.materials.len();
        scene.materials.extend(sub.materials);
        scene.meshes.extend(sub.meshes.into_iter().map(|mut mesh| {
            mesh.material += offset;
            mesh.blended_casts_shadow = model.blended_cast_shadows;
            mesh
        }));
        if spec.keep_model_lights {
            scene.lights.extend(sub.lights.into_iter().map(|mut l| {
                if model.lights_cast_shadows {
                    l.flags |= light_flags::CASTS_SHADOW;
                }
                l
            }));
        }
        if camera.is_none() && has_camera {
            camera = Some(sub.camera);
        }
        if scene.name.is_empty() {
            scene.name = sub.name;
        }
    }
    if let Some(name) = &spec.name {
        scene.name = name.clone();
    } else if scene.name.is_empty() {
        scene.name = file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
    }

    // Explicit lights.
    for (i, l) in spec.lights.iter().enumerate() {
        let element = match &l.name {
            Some(n) => format!("lights[{i}] (\"{n}\")"),
            None => format!("lights[{i}]"),
        };
        let light = l
            .to_light()
            .map_err(|m| SceneError::invalid(file, &element, m))?;
        if let Some(vpl) = &l.vpl {
            if !l.indirect {
                return Err(SceneError::invalid(
                    file,
                    &element,
                    "vpl controls need indirect: true (only indirect lights spawn VPLs)",
                ));
            }
            vpl.check()
                .map_err(|m| SceneError::invalid(file, &element, m))?;
            scene.vpl_controls.insert(scene.lights.len() as u32, *vpl);
        }
        add_motion(&mut scene, l.motion.as_ref(), 1, file, &element)?;
        scene.lights.push(light);
        check_reach(&scene, l.motion.is_some(), None, file, &element)?;
    }

    // Procedural light sets (placed in the bounds of all geometry so far).
    let mut total = scene.lights.len() as u64;
    for (i, set) in spec.light_sets.iter().enumerate() {
        let (kind, count) = match set {
            LightSetSpec::Random(r) => ("Random", r.count as u64),
            LightSetSpec::Amd(a) => ("Amd", a.point_count as u64 + a.spot_count as u64),
        };
        let element = format!("light_sets[{i}] ({kind})");
        total += count;
        if total > MAX_SCENE_LIGHTS {
            return Err(SceneError::Limit {
                file: file.to_path_buf(),
                at: None,
                element,
                what: "total light count",
                count: total,
                limit: MAX_SCENE_LIGHTS,
            });
        }
        let bounds = scene.bounds();
        let motion = match set {
            LightSetSpec::Random(r) => r.motion.as_ref(),
            LightSetSpec::Amd(a) => a.motion.as_ref(),
        };
        add_motion(&mut scene, motion, count as u32, file, &element)?;
        match set {
            LightSetSpec::Random(r) => {
                r.check()
                    .map_err(|m| SceneError::invalid(file, &element, m))?;
                scene.lights.extend(r.generate(bounds));
            }
            LightSetSpec::Amd(a) => {
                let Some(b) = bounds else {
                    return Err(SceneError::invalid(
                        file,
                        element,
                        "the AMD light set needs scene geometry for its bounding box",
                    ));
                };
                scene.lights.extend(a.generate(b));
            }
        }
        check_reach(&scene, motion.is_some(), Some(count), file, &element)?;
    }

    let bounds = scene.bounds();
    scene.camera = match &spec.camera {
        Some(CameraSpec::LookAt {
            eye,
            target,
            up,
            fov_y_deg,
            near,
            far,
        }) => {
            let ok = eye.is_finite()
                && target.is_finite()
                && up.is_finite()
                && (eye - target).length_squared() > 0.0
                && up.length_squared() > 0.0;
            if !ok {
                return Err(SceneError::invalid(
                    file,
                    "camera",
                    "LookAt needs finite eye != target and up != 0",
                ));
            }
            if let Some(m) = Camera::lens_error(*fov_y_deg, *near, *far) {
                return Err(SceneError::invalid(file, "camera", m));
            }
            Camera {
                eye: *eye,
                target: *target,
                up: *up,
                fov_y: fov_y_deg.to_radians(),
                near: *near,
                far: *far,
            }
        }
        Some(CameraSpec::FitBounds) => bounds.map(fit_camera).unwrap_or_default(),
        Some(CameraSpec::AmdBounds) => bounds.map(amd_camera).unwrap_or_default(),
        None => match (camera, bounds) {
            (Some(c), _) => c,
            (None, Some(b)) => {
                warnings.push(format!(
                    "{}: no camera (none given, and no built-in or model has one); one was fitted to the scene bounds",
                    file.display()
                ));
                fit_camera(b)
            }
            (None, None) => Camera::default(),
        },
    };

    for (name, path) in &spec.material_overrides {
        if scene.material_index(name).is_none() {
            warnings.push(format!(
                "{}: material_overrides: no material named \"{name}\" in the scene; override ignored",
                file.display()
            ));
        }
        scene.material_overrides.push((name.clone(), path.clone()));
    }
    if let Some((w, h)) = spec.output_size {
        if w == 0 || h == 0 || w > 16384 || h > 16384 {
            return Err(SceneError::invalid(
                file,
                "output_size",
                format!("({w}, {h}) must lie in 1..=16384"),
            ));
        }
        scene.output_size = Some((w, h));
    }
    if let Some(a) = spec.ambient {
        if !a.is_finite() || a.min_element() < 0.0 {
            return Err(SceneError::invalid(
                file,
                "ambient",
                format!("{a} must be finite and >= 0"),
            ));
        }
        scene.ambient = a;
    }
    if let Some(q) = spec.shadow_bvh {
        scene.shadow_bvh = q;
    }
    if spec.all_lights_cast_shadows {
        scene.all_lights_cast_shadows = true;
        for light in &mut scene.lights {
            light.flags |= light_flags::CASTS_SHADOW;
        }
    }
    scene.source_path = Some(file.to_path_buf());
    Ok(Loaded {
        scene,
        warnings,
        files,
    })
}
