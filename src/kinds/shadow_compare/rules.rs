//! `ShadowCompare`: the shadow atlas against ray-cast shadows of the same lights, per
//! (pixel, shadow-casting light) pair in front of the pixel's shading normal: counts the pairs and those whose atlas visibility
//! (both filters) falls on the other side of one half from the ray's answer. A
//! measurement pass for benchmarks (the atlas's error against its reference); runs
//! `shaders/shadow/shadow_compare.wgsl`.

use super::g_buffer::{G_NORMAL, G_POSITION, G_POSITION_READ};
use super::shadow_atlas::{SHADOW_ATLAS, SHADOW_VIEWS};
use super::shadow_ray_jobs::SHADOW_MASK;
use super::{slot, Access, Contents, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;

pub(crate) const SHADOW_ERRORS: &str = "shadow_errors";
/// Counters: pairs, disagreeing pairs with 5×5 PCF, with the 2×2 tap, pairs in a 5×5
/// penumbra (0 < visibility < 1).
pub(crate) const ERROR_WORDS: u64 = 4;

pub(crate) const SLOTS: &[SlotSpec] = &[
    G_POSITION_READ,
    SlotSpec::new(
        G_NORMAL,
        SlotType::ColorTexture,
        Access::Read,
        Usage::Sampled,
    ),
    super::LIGHT_GEOMETRY_READ,
    super::LIGHT_PROPERTIES_READ,
    SlotSpec::new(
        slot::LIGHT_LISTS,
        SlotType::Buffer,
        Access::Read,
        Usage::Bound,
    )
    .needs(&[Contents::LightLists]),
    SlotSpec::new(SHADOW_MASK, SlotType::Buffer, Access::Read, Usage::Bound)
        .needs(&[Contents::ShadowMask]),
    SlotSpec::new(
        SHADOW_ATLAS,
        SlotType::DepthTexture,
        Access::Read,
        Usage::Sampled,
    ),
    SlotSpec::new(SHADOW_VIEWS, SlotType::Buffer, Access::Read, Usage::Bound)
        .needs(&[Contents::ShadowViews]),
    SlotSpec::new(SHADOW_ERRORS, SlotType::Buffer, Access::Write, Usage::Bound),
];

pub(crate) fn check(ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    ctx.require_single_rgba32f(
        &[G_POSITION, G_NORMAL],
        "the comparison reads world positions and shading normals from single-sample Rgba32Float G-buffer textures",
        errors,
    );
    super::check_shadow_atlas_texture(ctx, errors);
}

/// `ShadowCompare` has no parameters: this names it for its rules.
pub struct ShadowCompare;

impl KindRules for ShadowCompare {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(ctx, errors)
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::errors;

    #[test]
    fn needs_the_mask_and_the_atlas() {
        let e = errors(
            r#"Pass(name: "g", kind: GBuffer, reads: ["geometry"], writes: ["depth", "pos", "nrm"]),
               Pass(name: "c", kind: LightCulling(tile: 16), reads: ["depth", "lg"], writes: ["lists"]),
               Pass(name: "x", kind: ShadowCompare, reads: ["pos", "nrm", "lg", "lp", "lists", "atlas"], writes: ["jobs"])"#,
            "pos",
        );
        assert!(
            e.contains("ShadowCompare needs a buffer in reads (slot 'shadow_mask')"),
            "{e}"
        );
        assert!(
            e.contains("ShadowCompare needs a buffer in reads (slot 'shadow_views')"),
            "{e}"
        );
    }
}
