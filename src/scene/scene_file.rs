//! Scene RON files: glTF models with transforms, a built-in scene, a camera, explicit lights,
//! procedural light sets, material overrides and an output size.
//!
//! ```ron
//! Scene(
//!     name: "cornell_many_lights",
//!     models: [
//!         (path: "../assets/cornell_box/scene.gltf",          // relative to this file
//!          transform: (translation: (0, 0, 0), rotation_deg: (0, 90, 0), scale: (1, 1, 1)),
//!          lights_cast_shadows: true,                          // its lights cast shadows
//!          blended_cast_shadows: false),                       // its glass casts none
//!     ],
//!     // builtin: "atrium",                                     // or/and a built-in scene
//!     camera: LookAt(eye: (0, 1, 6), target: (0, 1, 0), fov_y_deg: 50, near: 0.05, far: 100),
//!     lights: [
//!         (name: "key", position: (0, 1.9, 0), range: 5, intensity: 3, color: (1, 0.9, 0.8)),
//!         (name: "spot", position: (1, 1, 1), range: 4, intensity: 10,
//!          spot: (direction: (0, -1, 0), inner_deg: 20, outer_deg: 30), casts_shadow: true),
//!     ],
//!     light_sets: [
//!         Random(count: 1024, spot_fraction: 0.5, placement: SceneBounds(margin: 0),
//!                range: (0.2, 0.6), intensity: (0.5, 2), seed: 7),
//!         Amd(point_count: 2048, spot_count: 2048),
//!     ],
//!     material_overrides: { "floor": "materials/polished_marble.ron" },
//!     output_size: (1280, 720),
//!     ambient: (0, 0, 0),
//!     shadow_bvh: Fast,                                      // ray-cast shadow BVH quality
//!     all_lights_cast_shadows: false,                        // every light casts
//! )
//! ```
//!
//! `Some(...)` may be left out of optional fields, and an enum variant wrapping a struct is
//! written `Random(count: ...)` (RON extensions `implicit_some` and `unwrap_variant_newtypes`).

use super::error::SceneError;
use super::gltf_import::import_gltf_inner;
use super::lights::{amd_camera, check_light, fit_camera, AmdLights, RandomLights};
use super::model_budget::ModelBudget;
use super::types::{light_flags, Camera, Light, LightShape, Scene};
use super::{builtin, Loaded};
use glam::{EulerRot, Mat3, Mat4, Quat, Vec3};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Most lights a scene file may produce in total.
pub(crate) const MAX_SCENE_LIGHTS: u64 = 1 << 20;

/// A scene file (`scenes/*.ron`, written `Scene(...)`) as parsed; [`build_scene`] turns it
/// into a [`Scene`]. docs/format.md describes every field.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "Scene")]
pub struct SceneFile {
    /// The scene's name in reports (default: the built-in's or first model's name, else the
    /// file stem).
    #[serde(default)]
    pub name: Option<String>,
    /// A built-in scene (`atrium`, `harada`, `depth_discontinuity`) to start from.
    #[serde(default)]
    pub(crate) builtin: Option<String>,
    #[serde(default)]
    pub(crate) models: Vec<Model>,
    /// Default: the built-in's camera, else the first model's camera, else fitted to bounds.
    #[serde(default)]
    pub camera: Option<CameraSpec>,
    /// Explicit lights.
    #[serde(default)]
    pub lights: Vec<LightSpec>,
    #[serde(default)]
    pub(crate) light_sets: Vec<LightSetSpec>,
    /// Keep the lights of the built-in scene and of the glTF models (KHR_lights_punctual).
    #[serde(default = "yes")]
    pub(crate) keep_model_lights: bool,
    /// Imported material name → material RON path (kept as written, for the material module).
    #[serde(default)]
    pub(crate) material_overrides: std::collections::BTreeMap<String, PathBuf>,
    /// Preferred output width and height, each 1..=16384 (default: the command's size).
    #[serde(default)]
    pub(crate) output_size: Option<(u32, u32)>,
    /// Constant ambient radiance added to every surface; finite, ≥ 0 (default: the
    /// built-in's, else zero).
    #[serde(default)]
    pub(crate) ambient: Option<Vec3>,
    /// The ray-cast shadow BVH's build quality: Fastest, VeryFast, Fast (default), Medium.
    #[serde(default)]
    pub shadow_bvh: Option<super::BuildQuality>,
    /// Every light of the built scene casts shadows, whatever its own setting, the built-in's,
    /// the models' or the light sets' (default false): the "all lights casting" case of
    /// the stochastic and exact shadow benchmarks.
    #[serde(default)]
    pub all_lights_cast_shadows: bool,
}

fn yes() -> bool {
    true
}

/// A glTF model placed in the scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Model {
    /// .gltf or .glb, relative to the scene file.
    pub path: PathBuf,
    #[serde(default)]
    pub(crate) transform: Transform,
    /// Every light of this model (KHR_lights_punctual, kept with `keep_model_lights`)
    /// casts ray-cast shadows.
    #[serde(default)]
    pub(crate) lights_cast_shadows: bool,
    /// This model's blended meshes (glTF `alphaMode: BLEND`, glass) cast shadows like
    /// opaque ones; by default they cast none.
    #[serde(default)]
    pub(crate) blended_cast_shadows: bool,
}

/// Scale, then rotation (Euler XYZ, degrees), then translation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Transform {
    #[serde(default)]
    pub translation: Vec3,
    #[serde(default)]
    pub(crate) rotation_deg: Vec3,
    #[serde(default = "one")]
    pub scale: Vec3,
}

fn one() -> Vec3 {
    Vec3::ONE
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            translation: Vec3::ZERO,
            rotation_deg: Vec3::ZERO,
            scale: Vec3::ONE,
        }
    }
}

impl Transform {
    pub(crate) fn matrix(&self) -> Mat4 {
        let r = self.rotation_deg;
        Mat4::from_scale_rotation_translation(
            self.scale,
            Quat::from_euler(
                EulerRot::XYZ,
                r.x.to_radians(),
                r.y.to_radians(),
                r.z.to_radians(),
            ),
            self.translation,
        )
    }
}

/// How the scene file places the camera (`camera:`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum CameraSpec {
    /// An explicit perspective camera; needs finite `eye` ≠ `target`, `up` ≠ 0, 0 <
    /// `fov_y_deg` < 180 and 0 < `near` < `far`.
    LookAt {
        /// Camera position, metres.
        eye: Vec3,
        /// The point looked at.
        target: Vec3,
        /// Up direction (default `(0, 1, 0)`).
        #[serde(default = "up")]
        up: Vec3,
        /// Vertical field of view in degrees (default 60).
        #[serde(default = "fov")]
        fov_y_deg: f32,
        /// Near plane in metres (default 0.1).
        #[serde(default = "near")]
        near: f32,
        /// Far plane in metres (default 100).
        #[serde(default = "far")]
        far: f32,
    },
    /// Looks at the whole scene box.
    FitBounds,
    /// The AMD TiledLighting11 camera from the scene box.
    AmdBounds,
}

fn up() -> Vec3 {
    Vec3::Y
}
fn fov() -> f32 {
    60.0
}
fn near() -> f32 {
    0.1
}
fn far() -> f32 {
    100.0
}

/// One explicit light. Angles in degrees.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightSpec {
    /// Names the light in error messages.
    #[serde(default)]
    pub name: Option<String>,
    /// Position in metres.
    pub(crate) position: Vec3,
    /// Where the light's influence ends, metres; > 0.
    pub range: f32,
    /// Intensity in candela; ≥ 0.
    pub(crate) intensity: f32,
    /// Linear RGB colour, ≥ 0 (default white).
    #[serde(default = "one")]
    pub(crate) color: Vec3,
    #[serde(default)]
    pub(crate) spot: Option<SpotSpec>,
    #[serde(default)]
    pub(crate) casts_shadow: bool,
    #[serde(default)]
    pub(crate) indirect: bool,
    /// Art controls of the light's virtual point lights (only with `indirect: true`).
    #[serde(default)]
    pub(crate) vpl: Option<super::VplControls>,
    /// Material type bits this light lights (a material's `type_bit`; default all).
    #[serde(default = "all")]
    pub material_mask: u32,
    /// How the light moves and flickers over time.
    #[serde(default)]
    pub motion: Option<super::motion::Motion>,
}

fn all() -> u32 {
    u32::MAX
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SpotSpec {
    pub(crate) direction: Vec3,
    #[serde(default)]
    pub(crate) inner_deg: f32,
    pub(crate) outer_deg: f32,
}

impl LightSpec {
    /// The light this entry describes: checked once (`check_light`, the values as
    /// written in its messages) and its spot direction normalised once. Nothing later
    /// on the way to the GPU checks or normalises it again.
    pub(crate) fn to_light(&self) -> Result<Light, String> {
        let mut flags = 0;
        if self.casts_shadow {
            flags |= light_flags::CASTS_SHADOW;
        }
        if self.indirect {
            flags |= light_flags::INDIRECT;
        }
        let mut light = Light {
            position: self.position,
            range: self.range,
            color: self.color,
            intensity: self.intensity,
            shape: match &self.spot {
                None => LightShape::Point,
                Some(s) => LightShape::Spot {
                    direction: s.direction,
                    inner_angle: s.inner_deg.to_radians(),
                    outer_angle: s.outer_deg.to_radians(),
                },
            },
            flags,
            material_mask: self.material_mask,
        };
        check_light(&light)?;
        if let LightShape::Spot { direction, .. } = &mut light.shape {
            *direction = direction.normalize();
        }
        Ok(light)
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) enum LightSetSpec {
    Random(RandomLights),
    Amd(AmdLights),
}

pub(crate) fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(
        ron::extensions::Extensions::IMPLICIT_SOME
            | ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES,
    )
}

/// Parses a scene file's text (`file` names it in messages).
pub fn parse_scene_file(text: &str, file: &Path) -> Result<SceneFile, SceneError> {
    ron_options()
        .from_str(text)
        .map_err(|e: ron::error::SpannedError| SceneError::Parse {
            file: file.to_path_buf(),
            line: e.span.start.line,
            col: e.span.start.col,
            message: e.code.to_string(),
        })
}

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
    motion: Option<&super::motion::Motion>,
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
    scene.light_motion.push(super::motion::LightMotion {
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
