//! `VplSpawn`: N×N virtual point lights per reflective-shadow-map view, spawned on the
//! GPU and appended after the scene's lights through an atomic counter, so culling and
//! shading treat them as any other light. Reads the maps and the scene's two light
//! arrays; writes the two light arrays the later passes read (by the slot names
//! `light_geometry` and `light_properties`) and puts the light count in the frame
//! uniform. Past `max_vpls` the lowest-flux VPLs are dropped and counted. Optionally
//! merges neighbouring VPLs that face alike (`merge`, `merge_cos`), drops VPLs of
//! negligible flux (`min_flux`, `redistribute`) and bounds each VPL's 1/d² by the
//! disc of surface it stands for (`falloff: Disc`).
//! Runs `shaders/indirect/vpl_spawn.wgsl`.

use super::reflective_shadow_maps::{RSM_FLUX, RSM_NORMAL, RSM_POSITION, RSM_VIEWS};
use super::{slot, Access, BufferLayout, Contents, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::SceneResource;
use crate::graph::plan::FrameSize;
use serde::{Deserialize, Serialize};

/// `VplSpawn(max_vpls: 16384, merge: 1, merge_cos: 0.9, min_flux: 0.0,
/// redistribute: false, falloff: Clamp)`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct VplSpawn {
    /// Room for virtual lights after the scene's lights in the light arrays.
    #[serde(default = "default_max_vpls")]
    pub max_vpls: u32,
    /// Side of the groups of neighbouring VPLs of a view that may merge into one (a
    /// power of two; 1: none merge).
    #[serde(default = "default_merge")]
    pub merge: u32,
    /// A group merges only when every member's normal is within this cosine of the
    /// group's flux-weighted normal.
    #[serde(default = "default_merge_cos")]
    pub merge_cos: f32,
    /// VPLs whose flux (luminance) is below this fraction of all VPLs' flux are dropped.
    #[serde(default)]
    pub min_flux: f32,
    /// Scale the VPLs kept past `min_flux` so they carry the dropped ones' flux too.
    #[serde(default)]
    pub redistribute: bool,
    /// What bounds a VPL's 1/d² near it.
    #[serde(default)]
    pub falloff: VplFalloff,
}

/// How a VPL's light grows as a receiver nears it.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
pub enum VplFalloff {
    /// `1 / max(d², clamp²)`, the light's `clamp` control.
    #[default]
    Clamp,
    /// `1 / max(d² + r², clamp²)`: r² is the area of the map texels the VPL gathered,
    /// over π. On its axis this is exactly the irradiance of a Lambertian disc of that
    /// area.
    Disc,
    /// `1 / max(d², clamp², r²)`: the clamp grows to the disc's radius r.
    AreaClamp,
}

fn default_max_vpls() -> u32 {
    16384
}
fn default_merge() -> u32 {
    1
}
fn default_merge_cos() -> f32 {
    0.9
}

impl Default for VplSpawn {
    fn default() -> Self {
        Self {
            max_vpls: default_max_vpls(),
            merge: default_merge(),
            merge_cos: default_merge_cos(),
            min_flux: 0.0,
            redistribute: false,
            falloff: VplFalloff::default(),
        }
    }
}

/// Largest merge group side (the largest n of a view).
pub(crate) const MAX_MERGE: u32 = 32;

pub(crate) const SCENE_LIGHT_GEOMETRY: &str = "scene_light_geometry";
pub(crate) const SCENE_LIGHT_PROPERTIES: &str = "scene_light_properties";

/// Most virtual lights a graph may make room for (64 bytes each in the light arrays).
pub(crate) const MAX_VPLS: u32 = 1 << 22;

const fn sampled(name: &'static str) -> SlotSpec {
    SlotSpec::new(name, SlotType::ColorTexture, Access::Read, Usage::Sampled)
}

pub(crate) const SLOTS: &[SlotSpec] = &[
    sampled(RSM_NORMAL),
    sampled(RSM_FLUX),
    sampled(RSM_POSITION),
    SlotSpec::new(RSM_VIEWS, SlotType::Buffer, Access::Read, Usage::Bound)
        .needs(&[Contents::RsmViews]),
    SlotSpec::new(
        SCENE_LIGHT_GEOMETRY,
        SlotType::Import(SceneResource::LightGeometry),
        Access::Read,
        Usage::Bound,
    ),
    SlotSpec::new(
        SCENE_LIGHT_PROPERTIES,
        SlotType::Import(SceneResource::LightProperties),
        Access::Read,
        Usage::Bound,
    ),
    SlotSpec::new(
        slot::LIGHT_GEOMETRY,
        SlotType::Buffer,
        Access::Write,
        Usage::Bound,
    ),
    SlotSpec::new(
        slot::LIGHT_PROPERTIES,
        SlotType::Buffer,
        Access::Write,
        Usage::Bound,
    ),
];

pub(crate) fn check(p: &VplSpawn, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    if !(1..=MAX_VPLS).contains(&p.max_vpls) {
        errors.push(ctx.bad(format!("max_vpls {} must be in 1..={MAX_VPLS}", p.max_vpls)));
    }
    if !p.merge.is_power_of_two() || p.merge > MAX_MERGE {
        errors.push(ctx.bad(format!(
            "merge {} must be a power of two in 1..={MAX_MERGE}",
            p.merge
        )));
    }
    if !(-1.0..=1.0).contains(&p.merge_cos) {
        errors.push(ctx.bad(format!("merge_cos {} must be in [-1, 1]", p.merge_cos)));
    }
    if !(0.0..1.0).contains(&p.min_flux) {
        errors.push(ctx.bad(format!("min_flux {} must be in [0, 1)", p.min_flux)));
    }
    for s in [RSM_NORMAL, RSM_FLUX, RSM_POSITION] {
        if let Some(name) = ctx.slot(s) {
            if !ctx.is_single_rgba32f(name) {
                errors.push(ctx.mismatch(
                    name,
                    format!("slot '{s}' takes a single-sample Rgba32Float texture"),
                ));
            }
        }
    }
}

impl KindRules for VplSpawn {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(self, ctx, errors)
    }
    fn buffer_layout(&self, slot: &str, frame: FrameSize) -> Option<BufferLayout> {
        (slot == slot::LIGHT_GEOMETRY || slot == slot::LIGHT_PROPERTIES).then(|| {
            BufferLayout::Lights {
                lights: frame.lights as u64 + self.max_vpls as u64,
                stride: crate::gpu::structs::LIGHT_BYTES,
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::errors;

    #[test]
    fn checks_room_and_maps() {
        let e = errors(
            r#"Pass(name: "v", kind: VplSpawn(max_vpls: 0), reads: ["rsm_normal", "rsm_flux", "rsm_position", "rsm_views", "lg", "lp"], writes: ["light_geometry", "light_properties"])"#,
            "hdr",
        );
        assert!(e.contains("max_vpls 0 must be in"), "{e}");
        let e = errors(
            r#"Pass(name: "v", kind: VplSpawn(merge: 3, merge_cos: 2.0, min_flux: 1.0), reads: ["rsm_normal", "rsm_flux", "rsm_position", "rsm_views", "lg", "lp"], writes: ["light_geometry", "light_properties"])"#,
            "hdr",
        );
        assert!(e.contains("merge 3 must be a power of two"), "{e}");
        assert!(e.contains("merge_cos 2 must be in [-1, 1]"), "{e}");
        assert!(e.contains("min_flux 1 must be in [0, 1)"), "{e}");
        let e = errors(
            r#"Pass(name: "v", kind: VplSpawn(), reads: ["rsm_normal", "rsm_flux", "small", "rsm_views", "lg", "lp"], writes: ["light_geometry", "light_properties"])"#,
            "hdr",
        );
        assert!(
            e.contains("slot 'rsm_position' takes a single-sample Rgba32Float"),
            "{e}"
        );
    }
}
