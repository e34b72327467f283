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
use super::lights::{check_light, AmdLights, RandomLights};
use super::types::{light_flags, Light, LightShape};
use glam::{EulerRot, Mat4, Quat, Vec3};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

mod build;
pub use build::build_scene;
pub(crate) use build::load_scene_file;

/// Most lights a scene file may produce in total.
pub(crate) const MAX_SCENE_LIGHTS: u64 = 1 << 20;

/// A scene file (`scenes/*.ron`, written `Scene(...)`) as parsed; [`build_scene`] turns it
/// into a [`Scene`](crate::scene::Scene). docs/format.md describes every field.
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
