//! `DeferredShading`: lighting in a compute shader from the G-buffer (tiled deferred
//! with `lights: Culled`), one dispatch per material. Runs `shaders/deferred/deferred_shading.wgsl`.

use super::g_buffer::{G_NORMAL, G_POSITION};
use super::shadow_ray_jobs::SHADOW_MASK;
use super::{check_light_source, Access, Contents, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::LightSource;
use serde::{Deserialize, Serialize};

/// `DeferredShading(lights: Culled)`.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(deny_unknown_fields)]
pub struct DeferredShading {
    /// Where the light lists come from: every light (`AllLights`, the default) or a culling
    /// pass's lists (`Culled`).
    #[serde(default)]
    pub lights: LightSource,
}

/// The texture it stores into (the shader's binding name).
pub const HDR: &str = "hdr";

pub(crate) const SLOTS: &[SlotSpec] = &[
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
    SlotSpec::new(SHADOW_MASK, SlotType::Buffer, Access::Read, Usage::Bound)
        .optional()
        .needs(&[Contents::ShadowMask]),
    // Shadow maps: a ShadowAtlas pass's atlas and view table.
    super::SHADOW_ATLAS_READ,
    super::SHADOW_VIEWS_READ,
    // Textured and anisotropic materials: the surface the material samples.
    super::g_buffer::G_SURFACE_READ,
    super::g_buffer::G_UV_GRAD_READ,
    // Materials that sample with TEXCOORD_1: the second uv set.
    super::g_buffer::G_UV1_READ,
    super::g_buffer::G_UV1_GRAD_READ,
    super::VPL_VISIBILITY_READ,
];

pub(crate) fn check(p: &DeferredShading, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    check_light_source(ctx, p.lights, errors);
    super::check_shadow_mask(ctx, errors);
    super::check_shadow_atlas(ctx, errors, Some(super::shadow_ray_jobs::SHADOW_MASK));
    ctx.require_single_rgba32f(
        &[HDR],
        "deferred shading stores into a single-sample Rgba32Float texture",
        errors,
    );
    super::g_buffer::check_surface_pair(ctx, errors);
    check_msaa(ctx, errors);
}

/// A multisampled G-buffer (MSAA): both textures at one sample count, the two-texture
/// layout, and no per-pixel shadow mask (its bits are per pixel, not per sample). The
/// pass shades every distinct sample and stores their mean: the output stays single-sample.
fn check_msaa(ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    let Some(position) = ctx.slot(G_POSITION) else {
        return;
    };
    let ps = ctx.samples(position);
    // Every G-buffer texture it names (g_geometric is not among its slots).
    for normal in super::g_buffer::TARGETS[1..]
        .iter()
        .filter_map(|s| ctx.slot(s))
    {
        let ns = ctx.samples(normal);
        if ns != ps {
            errors.push(ctx.mismatch(
                normal,
                format!("G-buffer texture has {ns} sample(s) but '{position}' has {ps}: all are read sample by sample"),
            ));
        }
    }
    if ps > 1 {
        super::g_buffer::check_msaa_layout(ctx, position, errors);
        if let Some(mask) = ctx.slot(SHADOW_MASK) {
            errors.push(ctx.mismatch(
                mask,
                "the ray-cast shadow mask holds one pixel's bits, not each sample's: a multisampled G-buffer is shadowed from a shadow atlas",
            ));
        }
    }
}

impl KindRules for DeferredShading {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(self, ctx, errors)
    }
    fn check_inputs(&self, ctx: &super::contracts::InputsCtx, errors: &mut Vec<GraphError>) {
        super::check_hybrid_jobs(ctx, errors)
    }
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

    const GBUF4: &str = r#"Pass(name: "g", kind: GBuffer, reads: ["geometry"], writes: ["depth4", "pos4", "nrm4"]),"#;

    #[test]
    fn reads_a_multisampled_g_buffer_at_one_count() {
        validate(
            &format!(r#"{GBUF4} Pass(name: "d", kind: DeferredShading(), reads: ["pos4", "nrm4", "lg", "lp"], writes: ["hdr"])"#),
            "hdr",
        )
        .unwrap();
        // Reads of textures another pass wrote at a different count.
        let e = errors(
            &format!(
                r#"{GBUF4} Pass(name: "g1", kind: GBuffer, reads: ["geometry"], writes: ["depth", "pos", "nrm"]), Pass(name: "d", kind: DeferredShading(), reads: ["pos4", "nrm", "lg", "lp"], writes: ["hdr"])"#
            ),
            "hdr",
        );
        assert!(
            e.contains(
                "pass 'd', resource 'nrm': G-buffer texture has 1 sample(s) but 'pos4' has 4"
            ),
            "{e}"
        );
        let e = errors(
            &format!(
                r#"{GBUF4} Pass(name: "d", kind: DeferredShading(), reads: ["pos4", "nrm4", "lg", "lp"], writes: ["hdr4"])"#
            ),
            "hdr",
        );
        assert!(e.contains("single-sample Rgba32Float"), "{e}");
        let e = errors(
            &format!(
                r#"{GBUF4} Pass(name: "d", kind: DeferredShading(), reads: ["pos4", "lg", "lp"], writes: ["hdr"])"#
            ),
            "hdr",
        );
        assert!(
            e.contains(
                "pass 'd', resource 'pos4': a multisampled G-buffer is the two-texture layout"
            ),
            "{e}"
        );
    }
}
