//! `TransparentDepth`: the nearest depth of the scene's blended meshes (glTF
//! `alphaMode: BLEND`), both faces, into its own depth texture: the near end of the
//! transparent culling range (AMD's TiledLighting11 sample). Runs `shaders/forward/forward.wgsl` with
//! `DEPTH_ONLY`.

use super::{slot, Access, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::roles::PassRoles;

pub(crate) const SLOTS: &[SlotSpec] = &[
    super::GEOMETRY_READ,
    SlotSpec::new(
        slot::DEPTH,
        SlotType::DepthTexture,
        Access::Write,
        Usage::Attachment,
    ),
];

/// `TransparentDepth` has no parameters: this names it for its rules.
pub struct TransparentDepth;

impl KindRules for TransparentDepth {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn writes_transparency(&self, _roles: &PassRoles) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::{errors, validate};

    #[test]
    fn writes_one_depth_texture() {
        validate(
            r#"Pass(name: "t", kind: TransparentDepth, reads: ["geometry"], writes: ["depth"])"#,
            "hdr",
        )
        .unwrap();
        let e = errors(
            r#"Pass(name: "t", kind: TransparentDepth, reads: ["geometry"])"#,
            "hdr",
        );
        assert!(
            e.contains("TransparentDepth needs a depth texture in writes (slot 'depth')"),
            "{e}"
        );
    }
}
