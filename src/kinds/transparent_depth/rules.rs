//! `TransparentDepth`: the nearest depth of the scene's blended meshes (glTF
//! `alphaMode: BLEND`), both faces, into its own texture: the near end of the
//! transparent culling range (AMD's TiledLighting11 sample). Into a depth texture the
//! raster units draw it (`shaders/forward/forward.wgsl` with `DEPTH_ONLY`); into a
//! single-sample R32Float texture the compute rasterizer does
//! (`shaders/visibility/compute_raster.wgsl` over the blended triangles, resolved with
//! `DEPTH_ONLY`), so a compute-first frame's glass adds no render pass.

use super::{slot, Access, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::roles::PassRoles;

pub(crate) const SLOTS: &[SlotSpec] = &[
    super::GEOMETRY_READ,
    SlotSpec::new(
        slot::DEPTH,
        SlotType::DepthValues,
        Access::Write,
        Usage::AttachmentOrStorage,
    ),
];

/// `TransparentDepth` has no parameters: this names it for its rules.
pub struct TransparentDepth;

impl KindRules for TransparentDepth {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        super::check_float_depth_samples(ctx, errors);
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
            e.contains("TransparentDepth needs a depth texture (or an R32Float texture of depths) in writes (slot 'depth')"),
            "{e}"
        );
    }

    #[test]
    fn writes_a_single_sample_r32float_depth_in_compute() {
        validate(
            r#"Pass(name: "t", kind: TransparentDepth, reads: ["geometry"], writes: ["fdepth"])"#,
            "hdr",
        )
        .unwrap();
        let e = errors(
            r#"Pass(name: "t", kind: TransparentDepth, reads: ["geometry"], writes: ["fdepth4"])"#,
            "hdr",
        );
        assert!(
            e.contains("pass 't', resource 'fdepth4'")
                && e.contains("an R32Float depth is single-sample"),
            "{e}"
        );
    }
}
