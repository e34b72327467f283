//! Art controls of an indirect light's virtual point lights (`vpl: (...)` on a light in
//! a scene file; lights marked `indirect: true` without it get the defaults).

use serde::{Deserialize, Serialize};

/// `vpl: (intensity: 1.0, range: 4.0, n: 8, clamp: 0.1, material_mask: 0xffffffff)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VplControls {
    /// Scales every VPL's flux (1: the energy the map captured).
    #[serde(default = "one")]
    pub intensity: f32,
    /// Each VPL's range (metres): culling bounds it, the window reaches zero there.
    #[serde(default = "default_range")]
    pub range: f32,
    /// VPLs per side of each map view: n×n blocks of the view's tile, one VPL each. A
    /// power of two no larger than the graph's RSM tile.
    #[serde(default = "default_n")]
    pub n: u32,
    /// Distances below this (metres) count as this in the VPL's 1/d² (bounds the
    /// singularity next to a VPL).
    #[serde(default = "default_clamp")]
    pub clamp: f32,
    /// Material type bits that receive this light's VPLs.
    #[serde(default = "all")]
    pub material_mask: u32,
}

fn one() -> f32 {
    1.0
}
fn default_range() -> f32 {
    4.0
}
fn default_n() -> u32 {
    8
}
fn default_clamp() -> f32 {
    0.1
}
fn all() -> u32 {
    u32::MAX
}

impl Default for VplControls {
    fn default() -> Self {
        Self {
            intensity: one(),
            range: default_range(),
            n: default_n(),
            clamp: default_clamp(),
            material_mask: all(),
        }
    }
}

/// Largest n: 32×32 VPLs per view.
pub(crate) const MAX_N: u32 = 32;

impl VplControls {
    /// Checks every field; the message names it.
    pub fn check(&self) -> Result<(), String> {
        if !(self.intensity.is_finite() && (0.0..=1e6).contains(&self.intensity)) {
            return Err(format!(
                "vpl intensity {} must be finite and in [0, 1e6]",
                self.intensity
            ));
        }
        if !(self.range.is_finite() && self.range > 0.0 && self.range <= 1e6) {
            return Err(format!("vpl range {} must be in (0, 1e6]", self.range));
        }
        if !(self.n.is_power_of_two() && self.n <= MAX_N) {
            return Err(format!(
                "vpl n {} must be a power of two in 1..={MAX_N} (n×n VPLs per view)",
                self.n
            ));
        }
        if !(self.clamp.is_finite() && self.clamp > 0.0 && self.clamp < self.range) {
            return Err(format!(
                "vpl clamp {} must be > 0 and below the range {} (the 1/d² singularity needs a bound)",
                self.clamp, self.range
            ));
        }
        Ok(())
    }
}
