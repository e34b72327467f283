//! `DepthPrepass`: the scene's opaque depth, no colour target; alpha-masked geometry
//! discards. Runs `shaders/forward/forward.wgsl` with `DEPTH_ONLY`.

use super::{slot, Access, KindRules, SlotSpec, SlotType, Usage};

pub(crate) const SLOTS: &[SlotSpec] = &[
    super::GEOMETRY_READ,
    SlotSpec::new(
        slot::DEPTH,
        SlotType::DepthTexture,
        Access::Write,
        Usage::Attachment,
    ),
];

/// `DepthPrepass` has no parameters: this names it for its rules.
pub struct DepthPrepass;

impl KindRules for DepthPrepass {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::errors;

    #[test]
    fn needs_depth_in_writes_and_takes_no_lights() {
        let e = errors(
            r#"Pass(name: "p", kind: DepthPrepass, reads: ["geometry"])"#,
            "hdr",
        );
        assert!(
            e.contains("DepthPrepass needs a depth texture in writes (slot 'depth')"),
            "{e}"
        );
        let e = errors(
            r#"Pass(name: "p", kind: DepthPrepass, reads: ["geometry", "lg"], writes: ["depth"])"#,
            "hdr",
        );
        assert!(
            e.contains(
                "resource 'lg': DepthPrepass has no free slot for an Import of LightGeometry"
            ),
            "{e}"
        );
    }
}
