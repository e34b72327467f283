//! `TransparentShading`: the scene's blended meshes through the light loop, back to
//! front by view depth (per mesh), both faces lit, blended over the colour the opaque
//! shading wrote, tested against (never writing) the opaque depth. Runs
//! `shaders/forward/forward.wgsl` with `SHADE`.

use super::{check_light_source, slot, Access, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::LightSource;
use serde::{Deserialize, Serialize};

/// `TransparentShading(lights: Culled)`.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(deny_unknown_fields)]
pub struct TransparentShading {
    #[serde(default)]
    pub lights: LightSource,
}

pub const SLOTS: &[SlotSpec] = &[
    super::GEOMETRY_READ,
    super::LIGHT_GEOMETRY_READ,
    super::LIGHT_PROPERTIES_READ,
    super::LIGHT_LISTS_READ,
    // The opaque depth: transparent fragments behind it are not drawn.
    SlotSpec::new(
        slot::DEPTH,
        SlotType::DepthTexture,
        Access::Read,
        Usage::Attachment,
    ),
    // Blended over what the opaque pass wrote: in reads (for the order) and writes.
    SlotSpec::new(
        slot::COLOR,
        SlotType::ColorTexture,
        Access::ReadOrWrite,
        Usage::Attachment,
    ),
];

pub fn check(p: &TransparentShading, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    check_light_source(ctx, p.lights, errors);
    if let (Some(c), Some(d)) = (ctx.slot(slot::COLOR), ctx.slot(slot::DEPTH)) {
        let (cs, ds) = (ctx.samples(c), ctx.samples(d));
        if cs != ds {
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
    use crate::graph::kinds::test_support::{errors, validate};

    const OPAQUE: &str = r#"Pass(name: "pre", kind: DepthPrepass, reads: ["geometry"], writes: ["depth"]),
        Pass(name: "s", kind: ForwardShading(), reads: ["depth", "lg", "lp"], writes: ["hdr"]),"#;

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
