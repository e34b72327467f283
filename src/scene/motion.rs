//! Light motion in scene files: orbits, keyframed paths and intensity flicker. Every
//! value is a pure function of (light, time), so a frame at time t is the same on every
//! run; evaluating it allocates nothing (see [`animate_into`]).

use super::ranges::{MAX_COORDINATE, MAX_LIGHT_POWER};
use super::types::{Light, LightShape};
use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

/// How a light, or every light of a light set, moves over time (`motion:` in a scene
/// file). The parts combine: the path offset is added to the light's position, the orbit
/// then turns the result about its axis, and flicker scales the intensity.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Motion {
    /// A circle about an axis.
    #[serde(default)]
    pub orbit: Option<Orbit>,
    /// Keyframed offsets from the light's position, looping.
    #[serde(default)]
    pub path: Option<KeyframePath>,
    /// Seeded noise on the intensity.
    #[serde(default)]
    pub flicker: Option<Flicker>,
}

/// A circle about an axis through `centre`; the radius is the light's distance from the
/// axis at time 0. Spot directions turn with it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Orbit {
    /// A point on the axis, world space; finite.
    pub centre: Vec3,
    /// The axis direction (default +Y); finite and non-zero, normalised when used.
    #[serde(default = "up")]
    pub axis: Vec3,
    /// Degrees per second (counter-clockwise looking down the axis).
    pub speed_deg: f32,
}

fn up() -> Vec3 {
    Vec3::Y
}

/// Offsets from the light's position, reached at evenly spaced times over `period`
/// seconds, looping back to the first.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeyframePath {
    pub(crate) points: Vec<Vec3>,
    pub(crate) period: f32,
    #[serde(default)]
    pub(crate) interpolation: Interpolation,
}

/// How a path moves between its points.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub(crate) enum Interpolation {
    /// Straight segments.
    #[default]
    Linear,
    /// A uniform Catmull–Rom spline through the points (smooth at every point).
    CatmullRom,
}

/// Seeded 1D value noise on the intensity: `intensity × (1 + amplitude × n(t))` with
/// n in [−1, 1], a new random value `frequency` times a second, smoothly blended.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Flicker {
    /// Relative depth of the noise, 0..=1 (the intensity stays ≥ 0).
    pub amplitude: f32,
    /// New random values per second; finite, ≥ 0.
    pub frequency: f32,
    /// Seeds the noise, together with the light's index in its set (default 0).
    #[serde(default)]
    pub seed: u64,
}

/// A motion applied to `count` consecutive lights of a scene from `first`.
#[derive(Clone, Debug, PartialEq)]
pub struct LightMotion {
    /// Index of the first light in [`Scene::lights`](super::Scene::lights).
    pub first: u32,
    /// Number of consecutive lights that move.
    pub count: u32,
    /// How they move.
    pub motion: Motion,
}

/// Most keyframes a path may have (a scene file is read whole; this bounds one path).
pub(crate) const MAX_PATH_POINTS: usize = 1 << 16;

impl Motion {
    /// Checks the parameters; the message names the bad field.
    pub(crate) fn check(&self) -> Result<(), String> {
        if let Some(o) = &self.orbit {
            if !o.centre.is_finite() {
                return Err(format!("orbit centre {} is not finite", o.centre));
            }
            if !o.axis.is_finite() || o.axis.length_squared() < 1e-12 {
                return Err(format!(
                    "orbit axis {} is not a finite non-zero vector",
                    o.axis
                ));
            }
            if !o.speed_deg.is_finite() {
                return Err(format!("orbit speed_deg {} is not finite", o.speed_deg));
            }
        }
        if let Some(p) = &self.path {
            if p.points.is_empty() || p.points.len() > MAX_PATH_POINTS {
                return Err(format!(
                    "path has {} points; it needs 1..={MAX_PATH_POINTS}",
                    p.points.len()
                ));
            }
            if let Some(bad) = p.points.iter().position(|v| !v.is_finite()) {
                return Err(format!("path point {bad} is not finite"));
            }
            if !p.period.is_finite() || p.period <= 0.0 {
                return Err(format!(
                    "path period {} must be finite and > 0 seconds",
                    p.period
                ));
            }
        }
        if let Some(f) = &self.flicker {
            if !(0.0..=1.0).contains(&f.amplitude) {
                return Err(format!(
                    "flicker amplitude {} must lie in 0..=1",
                    f.amplitude
                ));
            }
            if !f.frequency.is_finite() || f.frequency < 0.0 {
                return Err(format!(
                    "flicker frequency {} must be finite and >= 0",
                    f.frequency
                ));
            }
        }
        Ok(())
    }

    /// Checks that `base` stays within the documented limits (`scene::ranges`) at every
    /// time: its positions within ±`MAX_COORDINATE` m, its flickering power within
    /// `MAX_LIGHT_POWER`. Call after the parameters' own check. The message names the
    /// field. A path alone is bounded exactly (its points, and a Catmull–Rom segment's
    /// extremes); an orbit alone by its circle; both together by the sphere about the
    /// orbit's centre through the path's farthest place.
    pub fn check_reach(&self, base: &Light) -> Result<(), String> {
        let (lo, hi) = match &self.path {
            Some(p) => p.bounds(),
            None => (Vec3::ZERO, Vec3::ZERO),
        };
        let (lo, hi) = (base.position + lo, base.position + hi);
        let beyond = |v: f32| !(v.is_finite() && v.abs() <= MAX_COORDINATE);
        let axis_name = ["x", "y", "z"];
        match &self.orbit {
            None => {
                for (k, axis) in axis_name.iter().enumerate() {
                    if let Some(v) = [lo[k], hi[k]].into_iter().find(|&v| beyond(v)) {
                        return Err(format!(
                            "path takes the light to {axis} = {v:e} m, beyond ±{MAX_COORDINATE:e} m"
                        ));
                    }
                }
            }
            Some(o) => {
                let a = o.axis.normalize();
                let reach = |k: usize| -> f32 {
                    if self.path.is_none() {
                        // The circle: its centre on the axis, its radius across it.
                        let r = base.position - o.centre;
                        let along = o.centre + a * r.dot(a);
                        let radius = (r - a * r.dot(a)).length();
                        along[k].abs() + radius * (1.0 - a[k] * a[k]).max(0.0).sqrt()
                    } else {
                        let far = (lo - o.centre).abs().max((hi - o.centre).abs());
                        o.centre[k].abs() + far.length()
                    }
                };
                for (k, axis) in axis_name.iter().enumerate() {
                    let v = reach(k);
                    if beyond(v) {
                        return Err(format!(
                            "orbit takes the light to |{axis}| = {v:e} m, beyond ±{MAX_COORDINATE:e} m"
                        ));
                    }
                }
            }
        }
        if let Some(f) = &self.flicker {
            let power = base.intensity * base.color.max_element() * (1.0 + f.amplitude);
            if !(power.is_finite() && power <= MAX_LIGHT_POWER) {
                return Err(format!(
                    "flicker amplitude {} raises the light to {power:e} cd, over the limit of {MAX_LIGHT_POWER:e}",
                    f.amplitude
                ));
            }
        }
        Ok(())
    }

    /// `base` at time `t` seconds; `index` is the light's place in its set (it seeds the
    /// flicker, so lights of one set flicker apart).
    pub fn apply(&self, base: &Light, index: u32, t: f64) -> Light {
        self.apply_phase(base, index, &self.phase(t))
    }

    /// The part of the motion at time `t` that every light of the set shares: the
    /// orbit's rotation, the path's segment, the flicker's lattice cell. Taken once per
    /// set and time, in f64 (long runs keep their precision); what is left per light is
    /// f32 arithmetic without sines ([`apply_phase`](Self::apply_phase)), which the GPU
    /// repeats (`shaders/scene/light_motion.wgsl`).
    pub fn phase(&self, t: f64) -> MotionPhase {
        let mut phase = MotionPhase::default();
        if let Some(o) = &self.orbit {
            let angle = (o.speed_deg as f64).to_radians() * t;
            phase.turn = Quat::from_axis_angle(
                o.axis.normalize(),
                angle.rem_euclid(std::f64::consts::TAU) as f32,
            );
        }
        if let Some(p) = &self.path {
            (phase.segment, phase.along) = p.segment(t);
        }
        if let Some(f) = &self.flicker {
            (phase.cell, phase.blend) = f.cell(t);
        }
        phase
    }

    /// `base` moved by the motion's `phase` (from [`phase`](Self::phase)); `index` is the
    /// light's place in its set.
    pub fn apply_phase(&self, base: &Light, index: u32, phase: &MotionPhase) -> Light {
        let mut l = *base;
        if let Some(p) = &self.path {
            l.position += p.offset_at(phase.segment, phase.along);
        }
        if let Some(o) = &self.orbit {
            l.position = o.centre + phase.turn * (l.position - o.centre);
            if let LightShape::Spot { direction, .. } = &mut l.shape {
                *direction = phase.turn * *direction;
            }
        }
        if let Some(f) = &self.flicker {
            l.intensity *= f.factor(index, phase);
        }
        l
    }
}

/// A motion at one time, shared by all its lights (see [`Motion::phase`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionPhase {
    /// The orbit's rotation (identity without an orbit).
    pub turn: Quat,
    /// The path's segment: it runs from point `segment` to the next.
    pub segment: u32,
    /// How far along the segment, 0..1.
    pub along: f32,
    /// The flicker's lattice cell (`floor(t × frequency)`).
    pub cell: i64,
    /// The smoothstep weight between the cell's lattice value and the next one.
    pub blend: f32,
}

impl Default for MotionPhase {
    fn default() -> Self {
        Self {
            turn: Quat::IDENTITY,
            segment: 0,
            along: 0.0,
            cell: 0,
            blend: 0.0,
        }
    }
}

impl KeyframePath {
    /// The smallest box holding every offset of the path: its points, and for a
    /// Catmull–Rom path each segment's extremes (where a coordinate's cubic turns).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for &p in &self.points {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        let n = self.points.len();
        if self.interpolation == Interpolation::CatmullRom && n >= 2 {
            let at = |k: usize| self.points[k % n];
            for i in 0..n {
                let (p0, p1, p2, p3) = (at(i + n - 1), at(i), at(i + 1), at(i + 2));
                // offset(s) = 0.5 (a + b s + c s² + d s³) per coordinate.
                let b = p2 - p0;
                let c = 2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3;
                let d = 3.0 * p1 - p0 - 3.0 * p2 + p3;
                for k in 0..3 {
                    for s in turning_points(b[k], 2.0 * c[k], 3.0 * d[k]) {
                        let v = 0.5 * (2.0 * p1[k] + b[k] * s + c[k] * s * s + d[k] * s * s * s);
                        lo[k] = lo[k].min(v);
                        hi[k] = hi[k].max(v);
                    }
                }
            }
        }
        (lo, hi)
    }

    /// The offset at time `t`: the path loops every `period` seconds.
    pub fn offset(&self, t: f64) -> Vec3 {
        let (segment, along) = self.segment(t);
        self.offset_at(segment, along)
    }

    /// The segment the path is on at time `t` and how far along it (0..1).
    pub fn segment(&self, t: f64) -> (u32, f32) {
        let n = self.points.len();
        if n < 2 {
            return (0, 0.0);
        }
        let u = (t / self.period as f64).rem_euclid(1.0) * n as f64;
        let i = (u.floor() as usize).min(n - 1);
        (i as u32, (u - i as f64) as f32)
    }

    /// The offset `along` segment `segment` (see [`segment`](Self::segment)).
    pub fn offset_at(&self, segment: u32, along: f32) -> Vec3 {
        let n = self.points.len();
        if n < 2 {
            return self.points.first().copied().unwrap_or(Vec3::ZERO);
        }
        let (i, s) = (segment as usize, along);
        let at = |k: usize| self.points[k % n];
        match self.interpolation {
            Interpolation::Linear => at(i).lerp(at(i + 1), s),
            Interpolation::CatmullRom => {
                let (p0, p1, p2, p3) = (at(i + n - 1), at(i), at(i + 1), at(i + 2));
                let (s2, s3) = (s * s, s * s * s);
                0.5 * (2.0 * p1
                    + (p2 - p0) * s
                    + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * s2
                    + (3.0 * p1 - p0 - 3.0 * p2 + p3) * s3)
            }
        }
    }

    /// The keyframes (offsets from the light's position).
    pub fn points(&self) -> &[Vec3] {
        &self.points
    }

    /// Whether segments are Catmull–Rom splines (else straight).
    pub fn is_catmull_rom(&self) -> bool {
        self.interpolation == Interpolation::CatmullRom
    }
}

impl Flicker {
    /// Value noise in [−1, 1]: hashed lattice values at integer `t × frequency`,
    /// blended with smoothstep.
    pub fn noise(&self, index: u32, t: f64) -> f32 {
        let (cell, blend) = self.cell(t);
        self.noise_at(index, cell, blend)
    }

    /// The lattice cell at time `t` and the smoothstep weight towards the next one.
    pub fn cell(&self, t: f64) -> (i64, f32) {
        let x = t * self.frequency as f64;
        let k = x.floor();
        let f = (x - k) as f32;
        (k as i64, f * f * (3.0 - 2.0 * f))
    }

    /// The noise of light `index` in lattice cell `cell`, `blend` of the way to the next.
    pub fn noise_at(&self, index: u32, cell: i64, blend: f32) -> f32 {
        let lattice = |k: i64| {
            let h = mix64(self.seed ^ mix64(((index as u64) << 32) ^ k as u64));
            (h >> 40) as f32 * (2.0 / 16_777_216.0) - 1.0
        };
        lattice(cell) + (lattice(cell.wrapping_add(1)) - lattice(cell)) * blend
    }

    /// What the intensity of light `index` is multiplied by at `phase` (≥ 0).
    pub fn factor(&self, index: u32, phase: &MotionPhase) -> f32 {
        (1.0 + self.amplitude * self.noise_at(index, phase.cell, phase.blend)).max(0.0)
    }
}

/// The roots in (0, 1) of `a + b s + c s²`.
fn turning_points(a: f32, b: f32, c: f32) -> Vec<f32> {
    let roots = if c.abs() < 1e-12 {
        if b.abs() < 1e-12 {
            vec![]
        } else {
            vec![-a / b]
        }
    } else {
        let disc = b * b - 4.0 * c * a;
        if disc < 0.0 {
            vec![]
        } else {
            let q = disc.sqrt();
            vec![(-b - q) / (2.0 * c), (-b + q) / (2.0 * c)]
        }
    };
    roots.into_iter().filter(|s| *s > 0.0 && *s < 1.0).collect()
}

/// SplitMix64's finaliser: a fixed, platform-independent 64-bit hash.
fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Writes `base` moved to time `t` into `out` (cleared first). No allocation once `out`
/// has room for `base.len()` lights. Motions past the end of `base` (a light count
/// changed after loading) are ignored.
pub fn animate_into(base: &[Light], motions: &[LightMotion], t: f64, out: &mut Vec<Light>) {
    out.clear();
    out.extend_from_slice(base);
    for m in motions {
        let first = (m.first as usize).min(out.len());
        let end = first.saturating_add(m.count as usize).min(out.len());
        let phase = m.motion.phase(t);
        for (i, l) in out[first..end].iter_mut().enumerate() {
            *l = m.motion.apply_phase(l, i as u32, &phase);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point() -> Light {
        Light::point(Vec3::new(2.0, 1.0, 0.0), 3.0, Vec3::ONE, 1.0)
    }

    #[test]
    fn orbit_keeps_radius_and_returns_after_a_turn() {
        let m = Motion {
            orbit: Some(Orbit {
                centre: Vec3::ZERO,
                axis: Vec3::Y,
                speed_deg: 90.0,
            }),
            ..Default::default()
        };
        let quarter = m.apply(&point(), 0, 1.0).position;
        assert!(
            (quarter - Vec3::new(0.0, 1.0, -2.0)).length() < 1e-5,
            "{quarter}"
        );
        let turn = m.apply(&point(), 0, 4.0).position;
        assert!((turn - point().position).length() < 1e-5, "{turn}");
    }

    #[test]
    fn paths_pass_through_their_points_and_loop() {
        for interpolation in [Interpolation::Linear, Interpolation::CatmullRom] {
            let p = KeyframePath {
                points: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 1.0)],
                period: 3.0,
                interpolation,
            };
            for (t, want) in [(0.0, Vec3::ZERO), (1.0, Vec3::X), (5.0, p.points[2])] {
                assert!(
                    (p.offset(t) - want).length() < 1e-5,
                    "{interpolation:?} t={t}"
                );
            }
        }
        let linear = KeyframePath {
            points: vec![Vec3::ZERO, Vec3::X],
            period: 2.0,
            interpolation: Interpolation::Linear,
        };
        assert!((linear.offset(0.5) - Vec3::X * 0.5).length() < 1e-6);
    }

    #[test]
    fn path_bounds_hold_every_offset_and_reach_names_the_field() {
        // A Catmull–Rom path overshoots its points; the bounds hold what it reaches.
        let p = KeyframePath {
            points: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 1.0), Vec3::Z],
            period: 4.0,
            interpolation: Interpolation::CatmullRom,
        };
        let (lo, hi) = p.bounds();
        let mut seen = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for i in 0..4000 {
            let o = p.offset(i as f64 * 1e-3);
            seen = (seen.0.min(o), seen.1.max(o));
        }
        assert!(lo.cmple(seen.0 + 1e-5).all() && hi.cmpge(seen.1 - 1e-5).all());
        assert!(
            (lo - seen.0).abs().max_element() < 1e-3,
            "{lo} vs {}",
            seen.0
        );
        assert!(
            (hi - seen.1).abs().max_element() < 1e-3,
            "{hi} vs {}",
            seen.1
        );
        assert!(hi.x > 1.0 + 1e-3, "overshoot past the points: {hi}");

        let light = Light::point(Vec3::new(0.0, 1.0, 6e4), 3.0, Vec3::ONE, 1.0);
        let orbit = |centre: Vec3| Motion {
            orbit: Some(Orbit {
                centre,
                axis: Vec3::Y,
                speed_deg: 10.0,
            }),
            ..Default::default()
        };
        assert!(orbit(Vec3::ZERO).check_reach(&light).is_ok());
        let e = orbit(Vec3::new(5e4, 0.0, 0.0))
            .check_reach(&light)
            .unwrap_err();
        assert!(e.starts_with("orbit takes the light to |x| = 1.28"), "{e}");
        let flicker = Motion {
            flicker: Some(Flicker {
                amplitude: 0.5,
                frequency: 1.0,
                seed: 0,
            }),
            ..Default::default()
        };
        let mut bright = light;
        bright.intensity = 8e14;
        let e = flicker.check_reach(&bright).unwrap_err();
        assert!(
            e.contains("flicker amplitude 0.5 raises the light to 1.2e15"),
            "{e}"
        );
    }

    #[test]
    fn flicker_is_seeded_bounded_and_varies() {
        let f = Flicker {
            amplitude: 1.0,
            frequency: 10.0,
            seed: 7,
        };
        let values: Vec<f32> = (0..200).map(|i| f.noise(3, i as f64 * 0.013)).collect();
        assert!(values.iter().all(|v| (-1.0..=1.0).contains(v)));
        assert!(values.iter().any(|&v| (v - values[0]).abs() > 0.1));
        assert_eq!(f.noise(3, 1.234), f.noise(3, 1.234));
        assert_ne!(f.noise(3, 1.234), f.noise(4, 1.234));
    }

    #[test]
    fn animate_into_equals_each_lights_own_motion_bit_for_bit() {
        // animate_into takes an orbit's rotation once per set; every light must still
        // come out exactly as `apply` moves it alone, at every time.
        let m = LightMotion {
            first: 0,
            count: 3,
            motion: Motion {
                orbit: Some(Orbit {
                    centre: Vec3::new(1.0, 0.0, -2.0),
                    axis: Vec3::new(0.2, 1.0, 0.1),
                    speed_deg: 37.0,
                }),
                flicker: Some(Flicker {
                    amplitude: 0.5,
                    frequency: 3.0,
                    seed: 7,
                }),
                ..Default::default()
            },
        };
        let base = [
            point(),
            Light::point(Vec3::new(-4.0, 2.0, 3.0), 2.0, Vec3::X, 5.0),
            point(),
        ];
        let mut out = Vec::new();
        for t in [0.0, 0.25, 1.7, 1234.5] {
            animate_into(&base, std::slice::from_ref(&m), t, &mut out);
            for (i, l) in base.iter().enumerate() {
                let alone = m.motion.apply(l, i as u32, t);
                assert_eq!(
                    out[i].position.to_array(),
                    alone.position.to_array(),
                    "t {t}"
                );
                assert_eq!(
                    out[i].intensity.to_bits(),
                    alone.intensity.to_bits(),
                    "t {t}"
                );
            }
            assert!(
                t == 0.0 || out[1].position != base[1].position,
                "t {t}: the orbit moved nothing"
            );
        }
    }

    #[test]
    fn animate_into_ignores_motions_past_the_lights() {
        let m = LightMotion {
            first: 1,
            count: 5,
            motion: Motion {
                path: Some(KeyframePath {
                    points: vec![Vec3::Y],
                    period: 1.0,
                    interpolation: Interpolation::Linear,
                }),
                ..Default::default()
            },
        };
        let mut out = Vec::new();
        animate_into(&[point(), point()], &[m], 0.0, &mut out);
        assert_eq!(out[0].position, point().position);
        assert_eq!(out[1].position, point().position + Vec3::Y);
    }
}
