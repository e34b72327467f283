//! `TransparentShading`: the scene's blended meshes through the light loop, back to
//! front by view depth (per mesh), both faces lit, blended over the colour the opaque
//! shading wrote, tested against (never writing) the opaque depth. Runs
//! `shaders/forward/forward.wgsl` with `SHADE`. The opaque depth is a depth attachment,
//! or a single-sample R32Float texture (a compute resolve's): then the pass has no depth
//! attachment and each fragment loads the depth at its pixel and is discarded where the
//! attachment's LessEqual test would have failed (`FLOAT_DEPTH`). With the BVH in its
//! reads, the light loop casts a shadow ray per fragment and casting light
//! (`SHADOW_TRACE`); with a shadow atlas and its view table, it samples the atlas
//! (`SHADOW_ATLAS`).

use super::shadow_ray_jobs::SHADOW_MASK;
use super::{
    check_light_source, slot, Access, Contents, KindCtx, KindRules, SlotSpec, SlotType, Usage,
};
use crate::graph::error::GraphError;
use crate::graph::model::LightSource;
use serde::{Deserialize, Serialize};

/// `TransparentShading(lights: Culled)`.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(deny_unknown_fields)]
pub struct TransparentShading {
    /// Where the light lists come from: every light (`AllLights`, the default) or a culling
    /// pass's lists (`Culled`).
    #[serde(default)]
    pub lights: LightSource,
}

pub(crate) const SLOTS: &[SlotSpec] = &[
    super::GEOMETRY_READ,
    super::LIGHT_GEOMETRY_READ,
    super::LIGHT_PROPERTIES_READ,
    super::LIGHT_LISTS_READ,
    // The opaque depth: transparent fragments behind it are not drawn. A depth format
    // is the attachment they are tested against; R32Float is loaded and tested in the
    // fragment shader.
    SlotSpec::new(
        slot::DEPTH,
        SlotType::DepthValues,
        Access::Read,
        Usage::AttachmentOrSampled,
    ),
    // Blended over what the opaque pass wrote: in reads (for the order) and writes.
    SlotSpec::new(
        slot::COLOR,
        SlotType::ColorTexture,
        Access::ReadOrWrite,
        Usage::Attachment,
    ),
    // Ray-cast shadows on glass: each fragment casts its own ray to each caster against
    // the BVH.
    super::BVH_NODES_READ,
    super::BVH_TRIANGLES_READ,
    // Only to refuse it by name: a ShadowRayJobs mask holds the rays of the opaque
    // surface at each pixel, not of the glass in front of it. Before the view table, so
    // a mask read by type lands here.
    SlotSpec::new(SHADOW_MASK, SlotType::Buffer, Access::Read, Usage::Bound)
        .optional()
        .needs(&[Contents::ShadowMask]),
    // Shadow maps on glass: a ShadowAtlas pass's atlas and view table, sampled per
    // fragment.
    super::SHADOW_ATLAS_READ,
    super::SHADOW_VIEWS_READ,
];

pub(crate) fn check(p: &TransparentShading, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    check_light_source(ctx, p.lights, errors);
    super::check_bvh_trace(ctx, errors);
    if let Some(mask) = ctx.slot(SHADOW_MASK) {
        errors.push(ctx.mismatch(
            mask,
            "the shadow mask holds the rays of the opaque surface behind the glass: read bvh_nodes and bvh_triangles instead, and the glass traces its own shadow rays",
        ));
    }
    super::check_shadow_atlas(ctx, errors, Some(super::shadow_ray_cast::BVH_NODES));
    super::check_float_depth_samples(ctx, errors);
    if let (Some(c), Some(d)) = (ctx.slot(slot::COLOR), ctx.slot(slot::DEPTH)) {
        let (cs, ds) = (ctx.samples(c), ctx.samples(d));
        if cs != ds && ctx.is_float_depth(d) {
            errors.push(ctx.mismatch(
                c,
                format!("colour target has {cs} sample(s) but the opaque depth '{d}' is R32Float, which is single-sample: MSAA glass needs a multisampled Depth32Float depth"),
            ));
        } else if cs != ds {
            errors.push(ctx.mismatch(
                c,
                format!("colour target has {cs} sample(s) but depth '{d}' has {ds}: MSAA needs both multisampled"),
            ));
        }
        if !ctx.writes(c) {
            errors.push(ctx.mismatch(
                c,
                "transparent surfaces blend into the colour target: list it in writes too",
            ));
        }
    }
}

impl KindRules for TransparentShading {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(self, ctx, errors)
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::{errors, validate, CULL};

    const OPAQUE: &str = r#"Pass(name: "pre", kind: DepthPrepass, reads: ["geometry"], writes: ["depth"]),
        Pass(name: "s", kind: ForwardShading(), reads: ["depth", "lg", "lp"], writes: ["hdr"]),"#;

    /// The compute-first frame: ComputeRaster's R32Float depth ("fdepth"), culled and
    /// shaded in compute, then glass culled into its own lists.
    const FLOAT_FRAME: &str = r#"Pass(name: "cr", kind: ComputeRaster, reads: ["vertices", "triangles", "material_triangles"], writes: ["fdepth", "visibility"]),
        Pass(name: "s", kind: VisibilityShading(), reads: ["visibility", "vertices", "triangles", "material_triangles", "lg", "lp"], writes: ["HDR"]),
        Pass(name: "tp", kind: TransparentDepth, reads: ["geometry"], writes: ["depth"]),
        Pass(name: "c", kind: LightCulling(tile: 16), reads: ["fdepth", "transparent_depth=depth", "lg"], writes: ["lists"]),"#;

    #[test]
    fn tests_glass_against_an_r32float_opaque_depth() {
        let frame = |hdr: &str, depth: &str| {
            format!(
                r#"{} Pass(name: "t", kind: TransparentShading(lights: Culled), reads: ["geometry", "{depth}", "lg", "lp", "lists", "{hdr}"], writes: ["{hdr}"])"#,
                FLOAT_FRAME.replace("HDR", hdr)
            )
        };
        validate(&frame("hdr", "fdepth"), "hdr")
            .expect("glass over a compute resolve's R32Float depth is valid");
        // MSAA glass needs a multisampled depth attachment: R32Float is single-sample.
        let e = errors(&frame("hdr4", "fdepth"), "hdr");
        assert!(
            e.contains("pass 't', resource 'hdr4': colour target has 4 sample(s) but the opaque depth 'fdepth' is R32Float, which is single-sample: MSAA glass needs a multisampled Depth32Float depth"),
            "{e}"
        );
        let e = errors(&frame("hdr4", "fdepth4"), "hdr");
        assert!(
            e.contains("pass 't', resource 'fdepth4': an R32Float depth is single-sample"),
            "{e}"
        );
        // Other colour formats are no depth: the slot stays empty.
        let e = errors(&frame("hdr", "small"), "hdr");
        assert!(
            e.contains("TransparentShading needs a depth texture (or an R32Float texture of depths) in reads (slot 'depth')"),
            "{e}"
        );
    }

    #[test]
    fn traces_shadows_with_the_whole_bvh_and_refuses_the_mask() {
        let glass = |reads: &str| {
            format!(
                r#"{OPAQUE} Pass(name: "t", kind: TransparentShading(), reads: ["geometry", "depth", "lg", "lp", "hdr", {reads}], writes: ["hdr"])"#
            )
        };
        validate(&glass(r#""bn", "bt""#), "hdr").expect("glass tracing the BVH is valid");
        let e = errors(&glass(r#""bn""#), "hdr");
        assert!(
            e.contains("pass 't': tracing shadows in the light loop needs both bvh_nodes and bvh_triangles"),
            "{e}"
        );
        let e = errors(&glass(r#""bt""#), "hdr");
        assert!(e.contains("needs both bvh_nodes and bvh_triangles"), "{e}");
        let jobs = r#"Pass(name: "g", kind: GBuffer, reads: ["geometry", "depth"], writes: ["pos", "g_geometric=geo"]),
            Pass(name: "j", kind: ShadowRayJobs(), reads: ["pos", "geo", "lg", "lp", "lists"], writes: ["jobs", "mask"]),"#;
        let e = errors(
            &format!(
                r#"{OPAQUE} {CULL} {jobs} Pass(name: "t", kind: TransparentShading(lights: Culled), reads: ["geometry", "depth", "lg", "lp", "lists", "hdr", "mask"], writes: ["hdr"])"#
            ),
            "hdr",
        );
        assert!(
            e.contains("pass 't', resource 'mask': the shadow mask holds the rays of the opaque surface behind the glass"),
            "{e}"
        );
        // Shadow maps instead: the atlas with its view table.
        let atlas = r#"Pass(name: "a", kind: ShadowAtlas(), reads: ["geometry"], writes: ["atlas", "shadow_views"]),"#;
        validate(
            &format!("{atlas} {}", glass(r#""atlas", "shadow_views""#)),
            "hdr",
        )
        .expect("glass sampling the atlas is valid");
        let e = errors(&format!("{atlas} {}", glass(r#""atlas""#)), "hdr");
        assert!(
            e.contains("read the ShadowAtlas pass's shadow_views buffer too"),
            "{e}"
        );
        // The hybrid: the atlas for lights with a map, the BVH traced for the rest.
        validate(
            &format!(
                "{atlas} {}",
                glass(r#""atlas", "shadow_views", "bn", "bt""#)
            ),
            "hdr",
        )
        .expect("glass sampling the atlas and tracing the BVH is valid");
    }

    #[test]
    fn blends_over_the_opaque_colour() {
        validate(
            &format!(
                r#"{OPAQUE} Pass(name: "t", kind: TransparentShading(), reads: ["geometry", "depth", "lg", "lp", "hdr"], writes: ["hdr"])"#
            ),
            "hdr",
        )
        .unwrap();
        // Without reading the colour, nothing orders it after the opaque pass.
        let e = errors(
            &format!(
                r#"{OPAQUE} Pass(name: "t", kind: TransparentShading(), reads: ["depth", "lg", "lp"], writes: ["hdr"])"#
            ),
            "hdr",
        );
        assert!(e.contains("no order between them"), "{e}");
        let e = errors(
            &format!(
                r#"{OPAQUE} Pass(name: "t", kind: TransparentShading(), reads: ["depth", "lg", "lp", "hdr"])"#
            ),
            "hdr",
        );
        assert!(e.contains("list it in writes too"), "{e}");
        let e = errors(
            &format!(
                r#"{OPAQUE} Pass(name: "t", kind: TransparentShading(lights: Culled), reads: ["depth", "lg", "lp", "hdr"], writes: ["hdr"])"#
            ),
            "hdr",
        );
        assert!(e.contains("lights: Culled needs"), "{e}");
    }
}
