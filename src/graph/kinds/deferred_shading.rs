//! `DeferredShading`: lighting in a compute shader from the G-buffer (tiled deferred
//! with `lights: Culled`), one dispatch per material. Runs `shaders/deferred/deferred_shading.wgsl`.

use super::g_buffer::{G_NORMAL, G_POSITION};
use super::shadow_ray_jobs::SHADOW_MASK;
use super::{check_light_source, Access, KindCtx, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::LightSource;
use serde::{Deserialize, Serialize};

/// `DeferredShading(lights: Culled)`.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(deny_unknown_fields)]
pub struct DeferredShading {
    #[serde(default)]
    pub lights: LightSource,
}

/// The texture it stores into (the shader's binding name).
pub const HDR: &str = "hdr";

pub const SLOTS: &[SlotSpec] = &[
    SlotSpec::new(
        G_POSITION,
        SlotType::ColorTexture,
        Access::Read,
        Usage::Sampled,
    ),
    SlotSpec::new(
        G_NORMAL,
        SlotType::ColorTexture,
        Access::Read,
        Usage::Sampled,
    )
    .optional(),
    super::LIGHT_GEOMETRY_READ,
    super::LIGHT_PROPERTIES_READ,
    super::LIGHT_LISTS_READ,
    SlotSpec::new(HDR, SlotType::ColorTexture, Access::Write, Usage::Storage),
    // Ray-cast shadows: the hit mask of a ShadowRayCast pass.
    SlotSpec::new(SHADOW_MASK, SlotType::Buffer, Access::Read, Usage::Bound).optional(),
    // Shadow maps: a ShadowAtlas pass's atlas and view table.
    super::SHADOW_ATLAS_READ,
    super::SHADOW_VIEWS_READ,
];

pub fn check(p: &DeferredShading, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    check_light_source(ctx, p.lights, errors);
    super::check_shadow_mask(ctx, errors);
    super::check_shadow_atlas(ctx, errors);
    ctx.require_single_rgba32f(
        &[HDR],
        "deferred shading stores into a single-sample Rgba32Float texture",
        errors,
    );
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::{errors, validate};

    const GBUF: &str =
        r#"Pass(name: "g", kind: GBuffer, reads: ["geometry"], writes: ["depth", "pos", "nrm"]),"#;

    #[test]
    fn reads_the_g_buffer_not_depth() {
        validate(
            &format!(r#"{GBUF} Pass(name: "d", kind: DeferredShading(), reads: ["pos", "nrm", "lg", "lp"], writes: ["hdr"])"#),
            "hdr",
        )
        .unwrap();
        let e = errors(
            &format!(
                r#"{GBUF} Pass(name: "d", kind: DeferredShading(), reads: ["pos", "nrm", "depth", "lg", "lp"], writes: ["hdr"])"#
            ),
            "hdr",
        );
        // The only depth slot is a shadow atlas's.
        assert!(
            e.contains("a shadow atlas is sampled through its view table"),
            "{e}"
        );
    }

    #[test]
    fn stores_into_single_sample_rgba32f() {
        let e = errors(
            &format!(
                r#"{GBUF} Pass(name: "d", kind: DeferredShading(), reads: ["pos", "nrm", "lg", "lp"], writes: ["small"])"#
            ),
            "hdr",
        );
        assert!(e.contains("single-sample Rgba32Float"), "{e}");
    }
}
