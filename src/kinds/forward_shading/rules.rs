//! `ForwardShading`: the scene's materials through the light loop, into a colour target
//! over the prepass depth. Runs `shaders/forward/forward.wgsl` with `SHADE`.

use super::shadow_ray_cast::BVH_NODES;
use super::shadow_ray_jobs::SHADOW_MASK;
use super::{
    check_light_source, slot, Access, Contents, KindCtx, KindRules, SlotSpec, SlotType, Usage,
};
use crate::graph::error::GraphError;
use crate::graph::model::LightSource;
use serde::{Deserialize, Serialize};

/// `ForwardShading(lights: Culled)`.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(deny_unknown_fields)]
pub struct ForwardShading {
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
    SlotSpec::new(
        slot::DEPTH,
        SlotType::DepthTexture,
        Access::ReadOrWrite,
        Usage::Attachment,
    ),
    SlotSpec::new(
        slot::COLOR,
        SlotType::ColorTexture,
        Access::Write,
        Usage::Attachment,
    ),
    // Ray-cast shadows: the hit mask of a ShadowRayCast pass, or the BVH to trace in the
    // light loop (the naive variant).
    SlotSpec::new(SHADOW_MASK, SlotType::Buffer, Access::Read, Usage::Bound)
        .optional()
        .needs(&[Contents::ShadowMask]),
    super::BVH_NODES_READ,
    super::BVH_TRIANGLES_READ,
    // Shadow maps: a ShadowAtlas pass's atlas and view table.
    super::SHADOW_ATLAS_READ,
    super::SHADOW_VIEWS_READ,
    super::VPL_VISIBILITY_READ,
];

/// How a shading pass shadows its lights, from the slots it filled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Shadows {
    /// No shadows: every light is unshadowed.
    None,
    /// Reads the per-pixel hit mask.
    Mask,
    /// Casts a ray per light in the light loop.
    Trace,
    /// Samples a shadow atlas, filtered as its ShadowAtlas pass says; compared by hand
    /// where its compute raster stored it as R32Float.
    Atlas(
        super::shadow_atlas::ShadowFilter,
        super::shadow_atlas::AtlasRaster,
    ),
    /// Samples the atlas for lights with a map this frame and reads the ray-cast mask
    /// for the rest (forward, deferred and visibility shading).
    Hybrid(
        super::shadow_atlas::ShadowFilter,
        super::shadow_atlas::AtlasRaster,
    ),
    /// Samples the atlas for lights with a map this frame and casts a ray in the light
    /// loop for the rest (glass: no job covers its fragments).
    HybridTrace(
        super::shadow_atlas::ShadowFilter,
        super::shadow_atlas::AtlasRaster,
    ),
}

/// The shadow source of a shading pass's slots; an atlas's filter is published on its
/// view table's planned layout.
pub fn shadows(roles: &crate::graph::PassRoles, plan: &crate::graph::ResourcePlan) -> Shadows {
    use super::shadow_atlas::SHADOW_VIEWS;
    let atlas = |views: &str| {
        plan.get(views)
            .and_then(|r| match r.layout {
                Some(super::BufferLayout::ShadowViews { filter, raster, .. }) => {
                    Some((filter, raster))
                }
                _ => None,
            })
            .unwrap_or_default()
    };
    match (roles.slot(SHADOW_MASK), roles.slot(SHADOW_VIEWS)) {
        (Some(_), Some(views)) => {
            let (filter, raster) = atlas(views);
            Shadows::Hybrid(filter, raster)
        }
        (Some(_), None) => Shadows::Mask,
        (None, Some(views)) if roles.slot(BVH_NODES).is_some() => {
            let (filter, raster) = atlas(views);
            Shadows::HybridTrace(filter, raster)
        }
        _ if roles.slot(BVH_NODES).is_some() => Shadows::Trace,
        (None, Some(views)) => {
            let (filter, raster) = atlas(views);
            Shadows::Atlas(filter, raster)
        }
        (None, None) => Shadows::None,
    }
}

pub(crate) fn check(p: &ForwardShading, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    check_light_source(ctx, p.lights, errors);
    super::check_bvh_trace(ctx, errors);
    if let (Some(n), Some(_)) = (ctx.slot(BVH_NODES), ctx.slot(SHADOW_MASK)) {
        errors.push(ctx.mismatch(
            n,
            "a pass reads the shadow mask or traces the BVH, not both",
        ));
    }
    super::check_shadow_mask(ctx, errors);
    super::check_shadow_atlas(ctx, errors, Some(super::shadow_ray_jobs::SHADOW_MASK));
    if let (Some(c), Some(d)) = (ctx.slot(slot::COLOR), ctx.slot(slot::DEPTH)) {
        let (cs, ds) = (ctx.samples(c), ctx.samples(d));
        if cs != ds {
            errors.push(ctx.mismatch(
                c,
                format!("colour target has {cs} sample(s) but depth '{d}' has {ds}: MSAA needs both multisampled"),
            ));
        }
    }
}

impl KindRules for ForwardShading {
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
    use crate::graph::kinds::test_support::{errors, validate, CULL, PREPASS};

    /// The hybrid: the atlas for lights with a map, the mask of jobs that skip them.
    #[test]
    fn takes_the_atlas_and_the_mask_of_jobs_that_skip_mapped_lights() {
        let graph = |job_views: &str| {
            format!(
                r#"Pass(name: "a", kind: ShadowAtlas(policy: Nearest(4)), reads: ["geometry"], writes: ["atlas", "views"]),
                {PREPASS} {CULL}
                Pass(name: "g", kind: GBuffer, reads: ["geometry", "depth"], writes: ["g_position=pos", "g_geometric=geo"]),
                Pass(name: "j", kind: ShadowRayJobs(), reads: ["g_position=pos", "g_geometric=geo", "lg", "lp", "lists"{job_views}], writes: ["jobs", "mask"]),
                Pass(name: "r", kind: ShadowRayCast(), reads: ["jobs", "g_position=pos", "g_geometric=geo", "lg", "bn", "bt"], writes: ["mask"]),
                Pass(name: "s", kind: ForwardShading(lights: Culled), reads: ["geometry", "depth", "lg", "lp", "lists", "shadow_mask=mask", "atlas", "shadow_views=views"], writes: ["hdr"])"#
            )
        };
        validate(&graph(r#", "shadow_views=views""#), "hdr").unwrap();
        let e = errors(&graph(""), "hdr");
        assert!(
            e.contains("pass 's', resource 'mask': the pass samples the atlas for lights with a map in 'views' and reads the mask for the rest, but jobs pass 'j' does not read 'views'"),
            "{e}"
        );
    }

    #[test]
    fn culled_needs_lists_and_all_lights_takes_none() {
        let e = errors(
            &format!(
                r#"{PREPASS} Pass(name: "s", kind: ForwardShading(lights: Culled), reads: ["depth", "lg", "lp"], writes: ["hdr"])"#
            ),
            "hdr",
        );
        assert!(e.contains("lights: Culled needs"), "{e}");
        let e = errors(
            &format!(
                r#"{PREPASS} {CULL} Pass(name: "s", kind: ForwardShading(lights: AllLights), reads: ["depth", "lg", "lp", "lists"], writes: ["hdr"])"#
            ),
            "hdr",
        );
        assert!(e.contains("lights: AllLights reads no light lists"), "{e}");
        validate(
            &format!(r#"{PREPASS} {CULL} Pass(name: "s", kind: ForwardShading(lights: Culled), reads: ["depth", "lg", "lp", "lists"], writes: ["hdr"])"#),
            "hdr",
        )
        .unwrap();
    }

    #[test]
    fn slots_by_name_and_light_properties_required() {
        // Named slots fill the same roles as inferred ones.
        validate(
            &format!(r#"{PREPASS} Pass(name: "s", kind: ForwardShading(), reads: ["depth=depth", "light_geometry=lg", "lp"], writes: ["color=hdr"])"#),
            "hdr",
        )
        .unwrap();
        let e = errors(
            &format!(
                r#"{PREPASS} Pass(name: "s", kind: ForwardShading(), reads: ["depth", "lg"], writes: ["hdr"])"#
            ),
            "hdr",
        );
        assert!(e.contains("slot 'light_properties'"), "{e}");
        let e = errors(
            &format!(
                r#"{PREPASS} Pass(name: "s", kind: ForwardShading(), reads: ["depth", "lg", "lp"], writes: ["shadow=hdr"])"#
            ),
            "hdr",
        );
        assert!(e.contains("ForwardShading has no slot 'shadow'"), "{e}");
    }

    #[test]
    fn msaa_needs_both_multisampled() {
        let e = errors(
            r#"Pass(name: "pre", kind: DepthPrepass, writes: ["depth4"]), Pass(name: "s", kind: ForwardShading(), reads: ["depth4", "lg", "lp"], writes: ["hdr"])"#,
            "hdr",
        );
        assert!(
            e.contains("colour target has 1 sample(s) but depth 'depth4' has 4"),
            "{e}"
        );
    }
}
