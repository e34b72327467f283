//! `VisibilityBuffer`: every opaque mesh's depth and, per pixel, the id of the triangle
//! drawn there (R32Uint: `GpuMesh::first_triangle` + the primitive index; `u32::MAX`
//! where nothing is). Alpha-masked geometry discards. Runs `shaders/forward/forward.wgsl`
//! with `VISIBILITY`.

use super::{slot, Access, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::{ResourceDesc, TextureFormat};

/// The triangle-id texture (also the binding name `VisibilityShading` reads it by).
pub const VISIBILITY: &str = "visibility";

pub(crate) const SLOTS: &[SlotSpec] = &[
    super::GEOMETRY_READ,
    SlotSpec::new(
        slot::DEPTH,
        SlotType::DepthTexture,
        Access::ReadOrWrite,
        Usage::Attachment,
    ),
    SlotSpec::new(
        VISIBILITY,
        SlotType::ColorTexture,
        Access::Write,
        Usage::Attachment,
    ),
];

pub(crate) fn check(ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    check_ids(ctx, errors);
    if let Some(depth) = ctx.slot(slot::DEPTH) {
        if ctx.samples(depth) > 1 {
            errors.push(ctx.mismatch(
                depth,
                "the visibility buffer is single-sample (one triangle id a pixel): MSAA is not supported",
            ));
        }
    }
}

/// The id texture is a single-sample R32Uint texture (both kinds check it).
pub(crate) fn check_ids(ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    let Some(ids) = ctx.slot(VISIBILITY) else {
        return;
    };
    let ok = matches!(
        ctx.graph.resources.get(ids),
        Some(ResourceDesc::Texture {
            format: TextureFormat::R32Uint,
            samples: 1,
            ..
        })
    );
    if !ok {
        errors.push(ctx.mismatch(
            ids,
            "triangle ids are a single-sample R32Uint texture (MSAA is not supported)",
        ));
    }
}

/// `VisibilityBuffer` has no parameters: this names it for its rules.
pub struct VisibilityBuffer;

impl KindRules for VisibilityBuffer {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(ctx, errors)
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::errors;

    #[test]
    fn writes_depth_and_single_sample_r32uint_ids() {
        // (Accepted with "depth" and "vis": see visibility_shading's tests.)
        let e = errors(
            r#"Pass(name: "v", kind: VisibilityBuffer, reads: ["geometry"], writes: ["depth", "hdr"])"#,
            "hdr",
        );
        assert!(
            e.contains(
                "pass 'v', resource 'hdr': triangle ids are a single-sample R32Uint texture"
            ),
            "{e}"
        );
        let e = errors(
            r#"Pass(name: "v", kind: VisibilityBuffer, reads: ["geometry"], writes: ["depth4", "vis4"])"#,
            "hdr",
        );
        assert!(
            e.contains("resource 'vis4': triangle ids are a single-sample R32Uint"),
            "{e}"
        );
        assert!(
            e.contains("resource 'depth4': the visibility buffer is single-sample"),
            "{e}"
        );
    }
}
