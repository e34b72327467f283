//! `ForwardShading`: the scene's materials through the light loop, into a colour target
//! over the prepass depth. Runs `shaders/forward/forward.wgsl` with `SHADE`.

use super::{check_light_source, slot, Access, KindCtx, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::{LightSource, SceneResource};
use serde::{Deserialize, Serialize};

/// `ForwardShading(lights: Culled)`.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(deny_unknown_fields)]
pub struct ForwardShading {
    #[serde(default)]
    pub lights: LightSource,
}

pub const SLOTS: &[SlotSpec] = &[
    SlotSpec::new(
        slot::GEOMETRY,
        SlotType::Import(SceneResource::Geometry),
        Access::Read,
        Usage::Bound,
    )
    .optional(),
    SlotSpec::new(
        slot::LIGHT_GEOMETRY,
        SlotType::Import(SceneResource::LightGeometry),
        Access::Read,
        Usage::Bound,
    ),
    SlotSpec::new(
        slot::LIGHT_PROPERTIES,
        SlotType::Import(SceneResource::LightProperties),
        Access::Read,
        Usage::Bound,
    ),
    SlotSpec::new(
        slot::LIGHT_LISTS,
        SlotType::Buffer,
        Access::Read,
        Usage::Bound,
    )
    .optional(),
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
];

pub fn check(p: &ForwardShading, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    check_light_source(ctx, p.lights, errors);
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

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::{errors, validate};

    const PREPASS: &str =
        r#"Pass(name: "pre", kind: DepthPrepass, reads: ["geometry"], writes: ["depth"]),"#;
    const CULL: &str = r#"Pass(name: "c", kind: LightCulling(tile: 16), reads: ["depth", "lg"], writes: ["lists"]),"#;

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
