//! Procedural light sets: a small deterministic PRNG, random light sets described in scene
//! RON files, and the AMD TiledLighting11 light setup.

use super::types::{light_flags, Camera, Light, LightShape};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// PCG32 (O'Neill, XSH-RR, 64-bit state). Our own so light sets never change with a crate
/// version.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    const MUL: u64 = 6364136223846793005;

    /// A generator seeded with `seed` on the default stream; the same seed gives the same
    /// sequence on every platform.
    pub fn new(seed: u64) -> Self {
        Self::with_stream(seed, 0xda3e_39cb_94b9_5bdb)
    }

    /// A generator seeded with `seed` on stream `stream`: different streams give independent
    /// sequences for one seed.
    pub fn with_stream(seed: u64, stream: u64) -> Self {
        let mut rng = Pcg32 {
            state: 0,
            inc: (stream << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(seed);
        rng.next_u32();
        rng
    }

    /// The next uniformly distributed 32-bit value.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MUL).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1) with 24 bits of precision.
    pub(crate) fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }

    /// A point uniform in the box from `lo` to `hi` (per axis in [lo, hi)).
    pub fn vec3_in(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        Vec3::new(
            self.range(lo.x, hi.x),
            self.range(lo.y, hi.y),
            self.range(lo.z, hi.z),
        )
    }

    /// Uniform direction on the unit sphere.
    pub fn unit_vector(&mut self) -> Vec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, std::f32::consts::TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// Where a random light set is placed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) enum Placement {
    /// Uniformly in this box.
    Box { min: Vec3, max: Vec3 },
    /// Uniformly in the scene's bounding box, grown by `margin` on every side (may be negative).
    SceneBounds {
        #[serde(default)]
        margin: f32,
    },
}

fn default_spot_cone() -> (f32, f32) {
    (20.0, 35.26)
}
fn default_color() -> (Vec3, Vec3) {
    (Vec3::splat(0.2), Vec3::ONE)
}

/// A random light set (`light_sets: [Random(...)]` in a scene RON). Ranges are `(min, max)`,
/// uniform.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RandomLights {
    /// Number of lights.
    pub count: u32,
    /// Fraction of spot lights, 0 (all point) .. 1 (all spot).
    #[serde(default)]
    pub(crate) spot_fraction: f32,
    pub(crate) placement: Placement,
    /// Range in metres, min ≤ max, min > 0.
    pub range: (f32, f32),
    /// Intensity in candela, 0 ≤ min ≤ max.
    pub(crate) intensity: (f32, f32),
    /// Linear RGB, per channel.
    #[serde(default = "default_color")]
    pub(crate) color: (Vec3, Vec3),
    /// Spot (inner, outer) cone half-angles in degrees.
    #[serde(default = "default_spot_cone")]
    pub(crate) spot_cone_deg: (f32, f32),
    /// PRNG seed (PCG32); the same seed gives the same lights on every platform.
    #[serde(default)]
    pub seed: u64,
    #[serde(default)]
    pub(crate) casts_shadow: bool,
    #[serde(default)]
    pub(crate) indirect: bool,
    /// Material type bits the lights light (all by default).
    #[serde(default = "all_bits")]
    pub material_mask: u32,
    /// How every light of the set moves (each from its own position).
    #[serde(default)]
    pub motion: Option<super::motion::Motion>,
}

fn all_bits() -> u32 {
    u32::MAX
}

impl RandomLights {
    /// A point/spot mix in a box with sensible defaults.
    pub fn in_box(count: u32, min: Vec3, max: Vec3, seed: u64) -> Self {
        RandomLights {
            count,
            spot_fraction: 0.5,
            placement: Placement::Box { min, max },
            range: (1.0, 3.0),
            intensity: (0.5, 2.0),
            color: default_color(),
            spot_cone_deg: default_spot_cone(),
            seed,
            casts_shadow: false,
            indirect: false,
            material_mask: u32::MAX,
            motion: None,
        }
    }

    /// Checks the parameters; the message names the bad field.
    pub(crate) fn check(&self) -> Result<(), String> {
        let finite = |v: f32| v.is_finite();
        let pair = |name: &str, (a, b): (f32, f32), positive: bool| -> Result<(), String> {
            if !finite(a) || !finite(b) {
                return Err(format!("{name} ({a}, {b}) is not finite"));
            }
            if a > b {
                return Err(format!("{name} ({a}, {b}): min > max"));
            }
            if positive && a <= 0.0 {
                return Err(format!("{name} ({a}, {b}) must be > 0"));
            }
            Ok(())
        };
        pair("range", self.range, true)?;
        pair("intensity", self.intensity, false)?;
        if self.intensity.0 < 0.0 {
            return Err(format!("intensity {:?} must be >= 0", self.intensity));
        }
        pair("spot_cone_deg", self.spot_cone_deg, false)?;
        if self.spot_cone_deg.0 < 0.0 || self.spot_cone_deg.1 > 90.0 {
            return Err(format!(
                "spot_cone_deg {:?} must lie in 0..=90",
                self.spot_cone_deg
            ));
        }
        if !(0.0..=1.0).contains(&self.spot_fraction) {
            return Err(format!(
                "spot_fraction {} must lie in 0..=1",
                self.spot_fraction
            ));
        }
        for v in [self.color.0, self.color.1] {
            if !v.is_finite() || v.min_element() < 0.0 {
                return Err(format!("color {:?} must be finite and >= 0", self.color));
            }
        }
        if let Placement::Box { min, max } = self.placement {
            if !min.is_finite() || !max.is_finite() || min.cmpgt(max).any() {
                return Err(format!("placement box {min} .. {max} is not a valid box"));
            }
        }
        if let Placement::SceneBounds { margin } = self.placement {
            if !margin.is_finite() {
                return Err(format!("placement margin {margin} is not finite"));
            }
        }
        Ok(())
    }

    /// Generates the lights. `bounds` is the scene's bounding box (used by
    /// [`Placement::SceneBounds`]; an empty scene uses the unit box).
    pub(crate) fn generate(&self, bounds: Option<(Vec3, Vec3)>) -> Vec<Light> {
        let (lo, hi) = match self.placement {
            Placement::Box { min, max } => (min, max),
            Placement::SceneBounds { margin } => {
                let (lo, hi) = bounds.unwrap_or((Vec3::splat(-1.0), Vec3::ONE));
                let (lo, hi) = (lo - Vec3::splat(margin), hi + Vec3::splat(margin));
                (lo.min(hi), lo.max(hi))
            }
        };
        let mut rng = Pcg32::new(self.seed);
        let spots = (self.count as f64 * self.spot_fraction as f64).round() as u32;
        let mut flags = 0;
        if self.casts_shadow {
            flags |= light_flags::CASTS_SHADOW;
        }
        if self.indirect {
            flags |= light_flags::INDIRECT;
        }
        (0..self.count)
            .map(|i| {
                let position = rng.vec3_in(lo, hi);
                let range = rng.range(self.range.0, self.range.1);
                let intensity = rng.range(self.intensity.0, self.intensity.1);
                let color = rng.vec3_in(self.color.0, self.color.1);
                // Spots are spread evenly through the set (Bresenham) so any prefix has the mix.
                let is_spot = ((i as u64 + 1) * spots as u64 / self.count as u64)
                    > (i as u64 * spots as u64 / self.count as u64);
                let dir = rng.unit_vector();
                let shape = if is_spot {
                    LightShape::Spot {
                        direction: dir,
                        inner_angle: self.spot_cone_deg.0.to_radians(),
                        outer_angle: self.spot_cone_deg.1.to_radians(),
                    }
                } else {
                    LightShape::Point
                };
                Light {
                    position,
                    range,
                    color,
                    intensity,
                    shape,
                    flags,
                    material_mask: self.material_mask,
                }
            })
            .collect()
    }
}

/// The AMD TiledLighting11 sample's light setup (`light_sets: [Amd(...)]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AmdLights {
    /// Point lights (default 2048).
    #[serde(default = "amd_count")]
    pub point_count: u32,
    /// Spot lights (default 2048).
    #[serde(default = "amd_count")]
    pub spot_count: u32,
    /// How many of the first point and of the first spot lights cast shadows (sample: 12 + 12).
    #[serde(default)]
    pub shadow_casters: u32,
    /// PRNG seed (default a fixed constant).
    #[serde(default = "amd_seed")]
    pub seed: u64,
    /// How every light of the set moves (each from its own position).
    #[serde(default)]
    pub motion: Option<super::motion::Motion>,
}

fn amd_count() -> u32 {
    2048
}
fn amd_seed() -> u64 {
    AMD_SEED
}

/// The fixed seed of [`amd_lights`].
pub(crate) const AMD_SEED: u64 = 0x4D44_7469_6C65_6421; // "AMDtiled!"-ish
/// Light radius as a fraction of |half-extent| of the scene box.
pub(crate) const AMD_RADIUS_FACTOR: f32 = 0.075;
/// cos of the spot cone half-angle (35.26°).
pub const AMD_SPOT_COS: f32 = 0.8165;

impl Default for AmdLights {
    fn default() -> Self {
        AmdLights {
            point_count: 2048,
            spot_count: 2048,
            shadow_casters: 0,
            seed: AMD_SEED,
            motion: None,
        }
    }
}

impl AmdLights {
    /// Generates the lights: points first, then spots, uniformly in the box `bounds`.
    ///
    /// - range = 0.075 · |half-extent| for every light;
    /// - spot outer cone: acos(0.8165) = 35.26°, inner cone 0.8 of it (the sample's smooth
    ///   falloff start); direction uniform on the sphere;
    /// - colour: uniform per channel in [0.1, 1] (the sample uses random colours);
    /// - intensity (candela) = range² / 4, so the unwindowed illuminance at half the range is 1.
    pub fn generate(&self, bounds: (Vec3, Vec3)) -> Vec<Light> {
        let (lo, hi) = bounds;
        let half = (hi - lo) * 0.5;
        let range = (AMD_RADIUS_FACTOR * half.length()).max(1e-4);
        let intensity = range * range * 0.25;
        let outer = AMD_SPOT_COS.acos();
        let mut rng = Pcg32::new(self.seed);
        let mut out = Vec::with_capacity((self.point_count + self.spot_count) as usize);
        for i in 0..self.point_count + self.spot_count {
            let spot = i >= self.point_count;
            let k = if spot { i - self.point_count } else { i };
            let position = rng.vec3_in(lo, hi);
            let color = rng.vec3_in(Vec3::splat(0.1), Vec3::ONE);
            let dir = rng.unit_vector();
            out.push(Light {
                position,
                range,
                color,
                intensity,
                shape: if spot {
                    LightShape::Spot {
                        direction: dir,
                        inner_angle: outer * 0.8,
                        outer_angle: outer,
                    }
                } else {
                    LightShape::Point
                },
                flags: if k < self.shadow_casters {
                    light_flags::CASTS_SHADOW
                } else {
                    0
                },
                material_mask: u32::MAX,
            });
        }
        out
    }
}

/// 2,048 point + 2,048 spot lights in `bounds` with the fixed seed (AMD TiledLighting11).
pub fn amd_lights(bounds: (Vec3, Vec3)) -> Vec<Light> {
    AmdLights::default().generate(bounds)
}

/// The AMD sample's camera from the scene box (`ext` = half-extent):
/// eye = centre − (0.45·ext.x, 0.35·ext.y, 0), target = centre − (0, 0.35·ext.y, 0).
/// near/far are chosen from the box size (0.001·|ext| and 4·|ext|); fov 60°.
pub fn amd_camera(bounds: (Vec3, Vec3)) -> Camera {
    let (lo, hi) = bounds;
    let c = (lo + hi) * 0.5;
    let ext = (hi - lo) * 0.5;
    let len = ext.length().max(1e-3);
    let eye = c - Vec3::new(0.45 * ext.x, 0.35 * ext.y, 0.0);
    let mut target = c - Vec3::new(0.0, 0.35 * ext.y, 0.0);
    if (target - eye).length_squared() < 1e-12 {
        target = eye - Vec3::Z;
    }
    Camera {
        eye,
        target,
        up: Vec3::Y,
        fov_y: 60f32.to_radians(),
        near: 0.001 * len,
        far: 4.0 * len,
    }
}

/// A camera looking at the whole box from the +Z side, slightly above (for scenes without
/// one).
pub(crate) fn fit_camera(bounds: (Vec3, Vec3)) -> Camera {
    let (lo, hi) = bounds;
    let c = (lo + hi) * 0.5;
    let radius = ((hi - lo) * 0.5).length().max(1e-3);
    let fov_y = 50f32.to_radians();
    let dist = radius / (fov_y * 0.5).sin();
    let eye = c + Vec3::new(0.0, 0.35, 1.0).normalize() * dist;
    Camera {
        eye,
        target: c,
        up: Vec3::Y,
        fov_y,
        near: (dist - radius).max(dist * 0.001),
        far: dist + radius * 2.0,
    }
}

/// Checks a light for NaN/Inf and impossible values; the message names the bad field.
pub fn check_light(l: &Light) -> Result<(), String> {
    if !l.position.is_finite() {
        return Err(format!("position {} is not finite", l.position));
    }
    if !l.range.is_finite() || l.range <= 0.0 {
        return Err(format!("range {} must be finite and > 0", l.range));
    }
    if !l.intensity.is_finite() || l.intensity < 0.0 {
        return Err(format!("intensity {} must be finite and >= 0", l.intensity));
    }
    if !l.color.is_finite() || l.color.min_element() < 0.0 {
        return Err(format!("color {} must be finite and >= 0", l.color));
    }
    if let LightShape::Spot {
        direction,
        inner_angle,
        outer_angle,
    } = l.shape
    {
        if !direction.is_finite() || direction.length_squared() < 1e-12 {
            return Err(format!(
                "spot direction {direction} is not a finite non-zero vector"
            ));
        }
        if !inner_angle.is_finite() || !outer_angle.is_finite() {
            return Err(format!(
                "spot angles ({inner_angle}, {outer_angle}) are not finite"
            ));
        }
        if inner_angle < 0.0
            || inner_angle > outer_angle
            || outer_angle > std::f32::consts::FRAC_PI_2 + 1e-6
        {
            return Err(format!(
                "spot angles need 0 <= inner ({inner_angle}) <= outer ({outer_angle}) <= pi/2"
            ));
        }
    }
    Ok(())
}

/// For a scene that brings no lights (many glTF files): a headlight, a point light at the
/// camera, as most glTF viewers do. Every surface the camera sees faces it, so all of them
/// are lit (a light inside the bounds leaves closed models such as the Khronos Box dark).
/// About unit irradiance at the centre of the bounds; the range reaches twice past the
/// farthest corner, so the range window dims nothing visible by more than ~12%.
pub(crate) fn headlight(camera: &Camera, bounds: (Vec3, Vec3)) -> Light {
    let (lo, hi) = bounds;
    let centre = (lo + hi) * 0.5;
    let to_centre = (centre - camera.eye).length();
    let reach = (to_centre + 0.5 * (hi - lo).length()).max(1e-3);
    Light::point(
        camera.eye,
        2.0 * reach,
        Vec3::ONE,
        to_centre.max(1e-3).powi(2),
    )
}
