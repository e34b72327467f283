//! Scene cases of a sweep (`cases: [...]`): named variations applied to every scene, for
//! numerical stress runs. A case may replace the lights (scene-RON light sets and explicit
//! lights), force every light's range or intensity, override the camera's near and far
//! planes, and put the camera at a light's centre.
//!
//! ```ron
//! cases: [
//!     (name: "range_1e-4", light_sets: [Random(count: 64, placement: SceneBounds(margin: 0),
//!                                               range: (1, 1), intensity: (1, 1))],
//!      range: 1e-4),
//!     (name: "far_1e6", far: 1e6),
//!     (name: "camera_at_light", camera_at_light: 0),
//!     (name: "no_lights", lights: []),
//! ]
//! ```

use crate::scene::scene_file::{LightSetSpec, LightSpec};
use crate::scene::{Light, Scene};
use serde::Deserialize;

/// One variation of the sweep's scenes. Applied after the sweep's light count, in field order.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SceneCase {
    /// Rows name the scene `scene/name`.
    pub name: String,
    /// If given (even empty), these light sets (scene-RON syntax: `Random(...)`, `Amd(...)`,
    /// placed in the scene's bounds) replace the scene's lights.
    #[serde(default)]
    pub(crate) light_sets: Option<Vec<LightSetSpec>>,
    /// If given (even empty), these explicit lights (scene-RON syntax) replace the scene's
    /// lights; with `light_sets` they follow the sets' lights.
    #[serde(default)]
    pub lights: Option<Vec<LightSpec>>,
    /// Every light's range, in metres.
    #[serde(default)]
    pub range: Option<f32>,
    /// Every light's intensity, in candela.
    #[serde(default)]
    pub(crate) intensity: Option<f32>,
    /// The camera's near plane.
    #[serde(default)]
    pub(crate) near: Option<f32>,
    /// The camera's far plane.
    #[serde(default)]
    pub(crate) far: Option<f32>,
    /// Moves the camera's eye to this light's centre (index into the lights after the fields
    /// above), keeping the view direction.
    #[serde(default)]
    pub(crate) camera_at_light: Option<usize>,
}

impl SceneCase {
    /// Checks the values that do not depend on a scene; the message names the field.
    pub fn check(&self) -> Result<(), String> {
        if self.name.is_empty() {
            return Err("name must not be empty".into());
        }
        let positive = |field: &str, v: Option<f32>| match v {
            Some(x) if !(x.is_finite() && x > 0.0) => {
                Err(format!("{field} {x} must be finite and > 0"))
            }
            _ => Ok(()),
        };
        positive("range", self.range)?;
        positive("near", self.near)?;
        positive("far", self.far)?;
        if let Some(i) = self.intensity.filter(|i| !(i.is_finite() && *i >= 0.0)) {
            return Err(format!("intensity {i} must be finite and >= 0"));
        }
        for (i, set) in self.light_sets.iter().flatten().enumerate() {
            if let LightSetSpec::Random(r) = set {
                r.check().map_err(|m| format!("light_sets[{i}]: {m}"))?;
            }
        }
        for (i, l) in self.lights.iter().flatten().enumerate() {
            l.to_light().map_err(|m| format!("lights[{i}]: {m}"))?;
        }
        Ok(())
    }

    /// The scene with this case applied; the message says what does not fit the scene.
    pub(crate) fn apply(&self, scene: &Scene) -> Result<Scene, String> {
        let mut s = scene.clone();
        if self.light_sets.is_some() || self.lights.is_some() {
            let bounds = s.bounds();
            let mut lights: Vec<Light> = Vec::new();
            for (i, set) in self.light_sets.iter().flatten().enumerate() {
                match set {
                    LightSetSpec::Random(r) => lights.extend(r.generate(bounds)),
                    LightSetSpec::Amd(a) => match bounds {
                        Some(b) => lights.extend(a.generate(b)),
                        None => {
                            return Err(format!(
                                "light_sets[{i}]: the AMD light set needs scene geometry"
                            ))
                        }
                    },
                }
            }
            for (i, l) in self.lights.iter().flatten().enumerate() {
                lights.push(l.to_light().map_err(|m| format!("lights[{i}]: {m}"))?);
            }
            s.lights = lights;
            // Replaced lights do not move as the scene file said (sweeps' `animate`
            // orbits them instead).
            s.light_motion.clear();
        }
        for l in &mut s.lights {
            l.range = self.range.unwrap_or(l.range);
            l.intensity = self.intensity.unwrap_or(l.intensity);
        }
        s.camera.near = self.near.unwrap_or(s.camera.near);
        s.camera.far = self.far.unwrap_or(s.camera.far);
        let (c, fov) = (&s.camera, s.camera.fov_y.to_degrees());
        if let Some(m) = crate::scene::Camera::lens_error(fov, c.near, c.far) {
            return Err(m);
        }
        if let Some(i) = self.camera_at_light {
            let Some(light) = s.lights.get(i) else {
                return Err(format!(
                    "camera_at_light {i}: the scene has {} lights",
                    s.lights.len()
                ));
            };
            let forward = s.camera.target - s.camera.eye;
            s.camera.eye = light.position;
            s.camera.target = light.position + forward;
        }
        s.name = format!("{}/{}", s.name, self.name);
        Ok(s)
    }
}
