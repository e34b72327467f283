//! `ComputeRaster`: the scene's opaque triangles rasterized in compute from the merged
//! visibility geometry, resolved per pixel with a 64-bit atomic min of (depth, id), into a
//! depth texture and an R32Uint visibility texture (triangle ids, `NO_TRIANGLE` where
//! nothing covers). The depth is Depth32Float (resolved by a full-screen draw, for later
//! passes that test against it) or R32Float (resolved in compute: a frame without vertex
//! or fragment work, read by LightCulling, LightLinkedList and TransparentShading).
//! Optionally the blended triangles' nearest (and farthest) depth too, drawn in the same
//! dispatches (what `TransparentDepth` writes, without its pass). Runs
//! `shaders/visibility/compute_raster.wgsl` and `compute_raster_resolve.wgsl`.

use super::{slot, Access, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::{ResourceDesc, SceneResource, TextureFormat};

pub(crate) const VERTICES: &str = "vertices";
pub(crate) const TRIANGLES: &str = "triangles";
pub(crate) const MATERIAL_TRIANGLES: &str = "material_triangles";
/// Per pixel, the id of the nearest triangle (what visibility-buffer shading reads).
pub const VISIBILITY: &str = "visibility";

pub(crate) const SLOTS: &[SlotSpec] = &[
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
    // Depth32Float: written by the resolve's full-screen draw (compute cannot store
    // depth formats). R32Float: stored by a compute resolve, so the frame has no draw.
    // The hardware fallback draws the ids (and a Depth32Float depth).
    SlotSpec::new(
        slot::DEPTH,
        SlotType::DepthValues,
        Access::Write,
        Usage::AttachmentOrStorage,
    ),
    SlotSpec::new(
        VISIBILITY,
        SlotType::ColorTexture,
        Access::Write,
        Usage::AttachmentOrStorage,
    ),
    // Optional: the blended triangles' nearest depth (what `TransparentDepth` writes),
    // rasterized in the same dispatches as the opaque ones, so a frame with glass runs
    // no rasterizer pass of its own for it.
    SlotSpec::new(
        slot::TRANSPARENT_DEPTH,
        SlotType::DepthValues,
        Access::Write,
        Usage::AttachmentOrStorage,
    )
    .optional(),
    // Optional, beside the transparent depth: the blended triangles' farthest depth, the
    // far end of the transparent culling range where nearer than the opaque surface.
    SlotSpec::new(
        slot::TRANSPARENT_FAR,
        SlotType::DepthValues,
        Access::Write,
        Usage::AttachmentOrStorage,
    )
    .optional(),
];

pub(crate) fn check(ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    let format = |name: &str| match ctx.graph.resources.get(name) {
        Some(ResourceDesc::Texture {
            format, samples, ..
        }) => Some((*format, *samples)),
        _ => None,
    };
    if let Some(depth) = ctx.slot(slot::DEPTH) {
        if !matches!(
            format(depth),
            Some((TextureFormat::Depth32Float | TextureFormat::R32Float, 1))
        ) {
            errors.push(ctx.mismatch(
                depth,
                "ComputeRaster writes 32-bit float depth per pixel: a single-sample Depth32Float texture (resolved by a draw) or R32Float (resolved in compute)",
            ));
        }
    }
    if let Some(glass) = ctx.slot(slot::TRANSPARENT_DEPTH) {
        let float_depth = ctx
            .slot(slot::DEPTH)
            .is_some_and(|d| format(d) == Some((TextureFormat::R32Float, 1)));
        if format(glass) != Some((TextureFormat::R32Float, 1)) || !float_depth {
            errors.push(ctx.mismatch(
                glass,
                "ComputeRaster writes the blended triangles' depth in its compute resolve: a single-sample R32Float texture, beside an R32Float depth",
            ));
        }
    }
    if let Some(far) = ctx.slot(slot::TRANSPARENT_FAR) {
        if format(far) != Some((TextureFormat::R32Float, 1))
            || ctx.slot(slot::TRANSPARENT_DEPTH).is_none()
        {
            errors.push(ctx.mismatch(
                far,
                "ComputeRaster writes the blended triangles' farthest depth beside their nearest: a single-sample R32Float texture, with a transparent depth in its writes",
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

/// `ComputeRaster` has no parameters: this names it for its rules.
pub struct ComputeRaster;

impl KindRules for ComputeRaster {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(ctx, errors)
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

    /// ComputeRaster with an R32Float depth ("fdepth", matched by type), shaded from its
    /// ids with the lists of a culling pass on that depth.
    const FLOAT_FRAME: &str = r#"Pass(name: "cr", kind: ComputeRaster, reads: ["vertices", "triangles", "material_triangles"], writes: ["fdepth", "visibility"]),
        Pass(name: "c", kind: LightCulling(tile: 16), reads: ["fdepth", "lg"], writes: ["lists"]),
        Pass(name: "s", kind: VisibilityShading(lights: Culled), reads: ["visibility", "vertices", "triangles", "material_triangles", "lg", "lp", "lists"], writes: ["hdr"])"#;

    #[test]
    fn writes_an_r32float_depth_that_culling_reads() {
        validate(FLOAT_FRAME, "hdr").unwrap();
        let linked = format!(
            r#"{FLOAT_FRAME}, Pass(name: "ll", kind: LightLinkedList(scale: 1), reads: ["fdepth", "lg", "lists"], writes: ["links"])"#
        );
        validate(&linked, "hdr").unwrap();
    }

    #[test]
    fn an_r32float_depth_is_single_sample_and_read_only_where_supported() {
        let msaa = FLOAT_FRAME.replace("fdepth", "fdepth4");
        let e = errors(&msaa, "hdr");
        assert!(
            e.contains("pass 'cr', resource 'fdepth4': ComputeRaster writes 32-bit float depth per pixel: a single-sample Depth32Float texture (resolved by a draw) or R32Float"),
            "{e}"
        );
        assert!(
            e.contains("pass 'c', resource 'fdepth4': an R32Float depth is single-sample"),
            "{e}"
        );
        // Forward shading tests its fragments against the depth: a depth format only.
        let e = errors(
            &format!(
                r#"{FLOAT_FRAME}, Pass(name: "f", kind: ForwardShading(lights: AllLights), reads: ["fdepth", "lg", "lp"], writes: ["small"])"#
            ),
            "hdr",
        );
        assert!(e.contains("t.ron:"), "{e}");
        // The R32Float fits the optional shadow-atlas slot (a compute atlas is R32Float),
        // so what is missing is the depth.
        assert!(
            e.contains(
                "pass 'f': ForwardShading needs a depth texture in reads or writes (slot 'depth')"
            ),
            "{e}"
        );
        assert!(
            e.contains(
                "an R32Float depth is read by LightCulling, LightLinkedList and TransparentShading"
            ),
            "{e}"
        );
    }

    #[test]
    fn writes_the_blended_triangles_depth_beside_an_r32float_depth_only() {
        let glass = FLOAT_FRAME.replace(
            r#"writes: ["fdepth", "visibility"]"#,
            r#"writes: ["fdepth", "visibility", "transparent_depth=tdepth_f"]"#,
        );
        validate(&glass, "hdr").unwrap();
        let e = errors(
            &glass.replace("transparent_depth=tdepth_f", "transparent_depth=depth"),
            "hdr",
        );
        assert!(
            e.contains("pass 'cr', resource 'depth': ComputeRaster writes the blended triangles' depth in its compute resolve: a single-sample R32Float texture, beside an R32Float depth"),
            "{e}"
        );
        let e = errors(
            &format!(
                r#"Pass(name: "cr", kind: ComputeRaster, {READS}, writes: ["depth", "visibility", "transparent_depth=tdepth_f"]), {SHADE}"#
            ),
            "hdr",
        );
        assert!(
            e.contains("resource 'tdepth_f': ComputeRaster writes the blended triangles' depth"),
            "{e}"
        );
        // The farthest beside the nearest only, R32Float.
        let far = glass.replace(
            "\"transparent_depth=tdepth_f\"]",
            "\"transparent_depth=tdepth_f\", \"transparent_far=fdepth2\"]",
        );
        assert_ne!(far, glass);
        let far = far.replace(
            "Pass(name: \"c\"",
            "Pass(name: \"c2\", kind: LightCulling(tile: 16), reads: [\"fdepth\", \"transparent_depth=tdepth_f\", \"transparent_far=fdepth2\", \"lg\"], writes: [\"lists2\"]), Pass(name: \"c\"",
        );
        validate(&far, "hdr").unwrap();
        let e = errors(&far.replace("\"transparent_depth=tdepth_f\", ", ""), "hdr");
        assert!(
            e.contains("resource 'fdepth2': ComputeRaster writes the blended triangles' farthest depth beside their nearest"),
            "{e}"
        );
        assert!(
            e.contains(
                "resource 'fdepth2': the farthest transparent depth bounds the nearest one's range"
            ),
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
