//! `ComputeRaster`: the scene's opaque triangles rasterized in compute from the merged
//! visibility geometry, resolved per pixel with a 64-bit atomic min of (depth, id), into a
//! depth texture and an R32Uint visibility texture (triangle ids, `NO_TRIANGLE` where
//! nothing covers). Runs `shaders/visibility/compute_raster.wgsl`.

use super::{slot, Access, KindCtx, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::{ResourceDesc, SceneResource, TextureFormat};

pub const VERTICES: &str = "vertices";
pub const TRIANGLES: &str = "triangles";
pub const MATERIAL_TRIANGLES: &str = "material_triangles";
/// Per pixel, the id of the nearest triangle (what visibility-buffer shading reads).
pub const VISIBILITY: &str = "visibility";

pub const SLOTS: &[SlotSpec] = &[
    SlotSpec::new(
        VERTICES,
        SlotType::Import(SceneResource::Vertices),
        Access::Read,
        Usage::Bound,
    ),
    SlotSpec::new(
        TRIANGLES,
        SlotType::Import(SceneResource::Triangles),
        Access::Read,
        Usage::Bound,
    ),
    // Optional: the pass takes each material's range from the CPU copy of this table.
    SlotSpec::new(
        MATERIAL_TRIANGLES,
        SlotType::Import(SceneResource::MaterialTriangles),
        Access::Read,
        Usage::Bound,
    )
    .optional(),
    // Written by the resolve's full-screen draw (compute cannot store depth formats).
    SlotSpec::new(
        slot::DEPTH,
        SlotType::DepthTexture,
        Access::Write,
        Usage::Attachment,
    ),
    SlotSpec::new(
        VISIBILITY,
        SlotType::ColorTexture,
        Access::Write,
        Usage::Attachment,
    ),
];

pub fn check(ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    let format = |name: &str| match ctx.graph.resources.get(name) {
        Some(ResourceDesc::Texture {
            format, samples, ..
        }) => Some((*format, *samples)),
        _ => None,
    };
    if let Some(depth) = ctx.slot(slot::DEPTH) {
        if format(depth) != Some((TextureFormat::Depth32Float, 1)) {
            errors.push(ctx.mismatch(
                depth,
                "ComputeRaster writes 32-bit float depth per pixel: a single-sample Depth32Float texture",
            ));
        }
    }
    if let Some(ids) = ctx.slot(VISIBILITY) {
        if format(ids) != Some((TextureFormat::R32Uint, 1)) {
            errors.push(ctx.mismatch(
                ids,
                "ComputeRaster writes one triangle id per pixel: a single-sample R32Uint texture",
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::{errors, validate};

    const READS: &str = r#"reads: ["vertices", "triangles", "material_triangles"]"#;
    /// A reader of the depth, so the graph has an Rgba32Float output.
    const SHADE: &str = r#"Pass(name: "s", kind: ForwardShading(lights: AllLights), reads: ["depth", "lg", "lp"], writes: ["hdr"])"#;

    #[test]
    fn writes_depth_and_ids() {
        validate(
            &format!(
                r#"Pass(name: "cr", kind: ComputeRaster, {READS}, writes: ["depth", "visibility"]), {SHADE}"#
            ),
            "hdr",
        )
        .unwrap();
        let e = errors(
            &format!(
                r#"Pass(name: "cr", kind: ComputeRaster, {READS}, writes: ["depth"]), {SHADE}"#
            ),
            "hdr",
        );
        assert!(
            e.contains("ComputeRaster needs a colour texture in writes (slot 'visibility')"),
            "{e}"
        );
        let e = errors(
            &format!(
                r#"Pass(name: "cr", kind: ComputeRaster, reads: ["triangles"], writes: ["depth", "visibility"]), {SHADE}"#
            ),
            "hdr",
        );
        assert!(
            e.contains("ComputeRaster needs an Import of Vertices in reads (slot 'vertices')"),
            "{e}"
        );
    }

    #[test]
    fn refuses_other_formats_and_msaa() {
        let e = errors(
            &format!(r#"Pass(name: "cr", kind: ComputeRaster, {READS}, writes: ["depth", "hdr"])"#),
            "hdr",
        );
        assert!(e.contains("resource 'hdr'"), "{e}");
        assert!(e.contains("a single-sample R32Uint texture"), "{e}");
        let e = errors(
            &format!(
                r#"Pass(name: "cr", kind: ComputeRaster, {READS}, writes: ["depth4", "ids4"]), {SHADE}"#
            ),
            "hdr",
        );
        assert!(e.contains("a single-sample Depth32Float texture"), "{e}");
        assert!(e.contains("a single-sample R32Uint texture"), "{e}");
    }
}
