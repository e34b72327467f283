//! `VplSpawn`: N×N virtual point lights per reflective-shadow-map view, spawned on the
//! GPU and appended after the scene's lights through an atomic counter, so culling and
//! shading treat them as any other light. Reads the maps and the scene's two light
//! arrays; writes the two light arrays the later passes read (by the slot names
//! `light_geometry` and `light_properties`) and puts the light count in the frame
//! uniform. Past `max_vpls` the lowest-flux VPLs are dropped and counted.
//! Runs `shaders/indirect/vpl_spawn.wgsl`.

use super::reflective_shadow_maps::{RSM_FLUX, RSM_NORMAL, RSM_POSITION, RSM_VIEWS};
use super::{slot, Access, BufferLayout, Contents, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::SceneResource;
use crate::graph::plan::FrameSize;
use serde::{Deserialize, Serialize};

/// `VplSpawn(max_vpls: 16384)`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(deny_unknown_fields)]
pub struct VplSpawn {
    /// Room for virtual lights after the scene's lights in the light arrays.
    #[serde(default = "default_max_vpls")]
    pub max_vpls: u32,
}

fn default_max_vpls() -> u32 {
    16384
}

impl Default for VplSpawn {
    fn default() -> Self {
        Self {
            max_vpls: default_max_vpls(),
        }
    }
}

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
            r#"Pass(name: "v", kind: VplSpawn(), reads: ["rsm_normal", "rsm_flux", "small", "rsm_views", "lg", "lp"], writes: ["light_geometry", "light_properties"])"#,
            "hdr",
        );
        assert!(
            e.contains("slot 'rsm_position' takes a single-sample Rgba32Float"),
            "{e}"
        );
    }
}
