//! `TransparentDepth`: the nearest depth of the scene's blended meshes (glTF
//! `alphaMode: BLEND`), both faces, into its own depth texture: the near end of the
//! transparent culling range (AMD's TiledLighting11 sample). Runs `shaders/forward/forward.wgsl` with
//! `DEPTH_ONLY`.

use super::{slot, Access, KindCtx, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;

pub const SLOTS: &[SlotSpec] = &[
    super::GEOMETRY_READ,
    SlotSpec::new(
        slot::DEPTH,
        SlotType::DepthTexture,
        Access::Write,
        Usage::Attachment,
    ),
];

pub fn check(_ctx: &KindCtx, _errors: &mut [GraphError]) {}

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
