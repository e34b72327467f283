//! KHR_lights_punctual: point and spot lights found on nodes, checked and given a range.

use super::Importer;
use crate::scene::error::SceneError;
use crate::scene::types::{Light, LightShape};
use glam::Vec3;

/// Lights without a `range` get the distance where `intensity · max(colour) / d²` falls to
/// this illuminance (lux), capped at twice the scene's diagonal.
pub const INFINITE_RANGE_CUTOFF: f32 = 1e-3;

/// A light found during the node walk; finished once the scene's bounds are known.
pub(super) struct PendingLight {
    pub(super) element: String,
    pub(super) position: Vec3,
    pub(super) direction: Vec3,
    pub(super) color: Vec3,
    pub(super) intensity: f32,
    pub(super) range: Option<f32>,
    pub(super) spot: Option<(f32, f32)>,
}

impl Importer {
    pub(super) fn finish_light(&mut self, l: PendingLight, diag: f32) -> Result<Light, SceneError> {
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
}
