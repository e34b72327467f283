//! `VisibilityShading`: every material shaded in a compute shader from a visibility
//! buffer, one dispatch per group of materials that share their code (they differ only in
//! constants, read from a buffer): each pixel whose triangle id lies in one of the group's
//! materials' ranges fetches the triangle, rebuilds its attributes at the pixel centre and
//! runs the light loop. With `materials: Classified` and more than one group the frame is
//! first classified: each workgroup-sized tile is listed under every group it holds, and
//! each group's dispatch runs over its own tiles only. With `shadow_mask` in its reads the
//! light loop shadows each caster from a ray-cast mask (`ShadowRayJobs`,
//! `ShadowRayCast`), numbered as forward and deferred shading number them; with
//! `shadow_atlas` and `shadow_views` it samples a `ShadowAtlas` pass's maps as they do. Runs
//! `shaders/visibility/visibility_shading.wgsl` (and `classify_materials.wgsl`).

use super::contracts::InputsCtx;
use super::deferred_shading::HDR;
use super::light_sampling::LIGHT_SAMPLES;
use super::shadow_atlas::SHADOW_ATLAS;
use super::shadow_ray_cast::{BVH_NODES, BVH_TRIANGLES};
use super::shadow_ray_jobs::SHADOW_MASK;
use super::visibility_buffer::VISIBILITY;
use super::{check_light_source, Access, Contents, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::{LightSource, SceneResource};
use serde::{Deserialize, Serialize};

/// `VisibilityShading(lights: Culled, light_loop: GroupList, workgroup: 16, materials: PerShader)`.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(deny_unknown_fields)]
pub struct VisibilityShading {
    /// Where the light lists come from: every light (`AllLights`, the default) or a culling
    /// pass's lists (`Culled`).
    #[serde(default)]
    pub lights: LightSource,
    /// How a pixel walks its lights (`GroupList` by default).
    #[serde(default)]
    pub light_loop: LightLoop,
    /// Pixels per side of the shading workgroup: 8 or 16 (`Staged` takes 8). Its
    /// invocations run in 8×4-pixel blocks of 32 (a warp on NVIDIA) either way. Unset:
    /// 16, 8 for `Staged` (see [`VisibilityShading::workgroup_side`]).
    #[serde(
        default,
        deserialize_with = "super::plain_some",
        serialize_with = "super::plain_u32",
        skip_serializing_if = "Option::is_none"
    )]
    pub workgroup: Option<u32>,
    /// Which materials each dispatch shades and over which tiles (`PerShader` by
    /// default).
    #[serde(default)]
    pub materials: MaterialDispatch,
}

/// Which materials each dispatch shades and over which tiles.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
pub enum MaterialDispatch {
    /// The default: materials whose generated code is the same but for its constants (a
    /// glTF scene's untextured metallic-roughness materials, say) share one dispatch over
    /// the whole frame, each pixel reading its material's constants from a buffer; a
    /// textured material has a dispatch of its own (its textures are bound per dispatch).
    /// Each dispatch's invocations skip pixels of other groups.
    #[default]
    PerShader,
    /// One dispatch per material over the whole frame: the cost `PerShader` removes, kept
    /// to measure it. The same image to the bit.
    PerMaterial,
    /// `PerShader`'s groups, each over its own tiles: a classification dispatch lists each
    /// tile (a workgroup's pixels) under every group it holds, then each group runs an
    /// indirect dispatch over its tiles only, so a group that covers no pixel costs no
    /// workgroups; the image is the same to the bit. With one group the frame is one
    /// dispatch either way.
    Classified,
}

/// Workgroup sides the shader is built for.
pub(crate) const WORKGROUP_SIDES: [u32; 2] = [8, 16];

impl VisibilityShading {
    /// The workgroup's side in pixels: as asked, else 16 (8 for `Staged`, which needs
    /// it). 16 is never slower than 8 for `RangeFirst` on the H200 and much faster on
    /// textured materials (the Cornell box at 3,072 lights: 0.163 against 0.208 ms of
    /// shading), its tile's texels and lights read by one SM (docs/visibility_buffer.md).
    pub fn workgroup_side(&self) -> u32 {
        match (self.workgroup, self.light_loop) {
            (Some(side), _) => side,
            (None, LightLoop::Staged) => 8,
            (None, _) => 16,
        }
    }
}

/// How a pixel walks its lights. All three give the same image to the bit (tested); they
/// differ only in speed, so a graph can time them side by side.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
pub enum LightLoop {
    /// Forward shading's loop (`common/light_loop.wgsl`), per pixel.
    Forward,
    /// Per pixel, a light's range tested before its properties are read.
    RangeFirst,
    /// A workgroup whose pixels all read one tile list (Frustum and DepthMask lists)
    /// stages it in workgroup memory, a batch at a time; other lists run `RangeFirst`.
    Staged,
    /// `RangeFirst` over the workgroup's one tile list, found from the workgroup id, so
    /// the compiler sees the walk as uniform (Frustum and DepthMask lists whose tile is a
    /// multiple of the workgroup); other lists run `RangeFirst`. On a device with
    /// subgroup operations each subgroup loads a light per invocation and passes them
    /// round by shuffles. The default: the fastest on an NVIDIA H100
    /// (docs/visibility_buffer.md).
    #[default]
    GroupList,
}

pub(crate) const VERTICES: &str = "vertices";
pub(crate) const TRIANGLES: &str = "triangles";
pub(crate) const MATERIAL_TRIANGLES: &str = "material_triangles";

const fn import(name: &'static str, from: SceneResource) -> SlotSpec {
    SlotSpec::new(name, SlotType::Import(from), Access::Read, Usage::Bound)
}

pub(crate) const SLOTS: &[SlotSpec] = &[
    SlotSpec::new(
        VISIBILITY,
        SlotType::ColorTexture,
        Access::Read,
        Usage::Sampled,
    ),
    import(VERTICES, SceneResource::Vertices),
    import(TRIANGLES, SceneResource::Triangles),
    import(MATERIAL_TRIANGLES, SceneResource::MaterialTriangles),
    super::LIGHT_GEOMETRY_READ,
    super::LIGHT_PROPERTIES_READ,
    super::LIGHT_LISTS_READ,
    SlotSpec::new(HDR, SlotType::ColorTexture, Access::Write, Usage::Storage),
    SlotSpec::new(SHADOW_MASK, SlotType::Buffer, Access::Read, Usage::Bound)
        .optional()
        .needs(&[Contents::ShadowMask]),
    // Shadow maps: a ShadowAtlas pass's atlas and view table.
    super::SHADOW_ATLAS_READ,
    super::SHADOW_VIEWS_READ,
    super::VPL_VISIBILITY_READ,
    // Shadows traced in the light loop (every caster, no mask): the exact reference.
    SlotSpec::new(
        BVH_NODES,
        SlotType::Import(SceneResource::BvhNodes),
        Access::Read,
        Usage::Bound,
    )
    .optional(),
    SlotSpec::new(
        BVH_TRIANGLES,
        SlotType::Import(SceneResource::BvhTriangles),
        Access::Read,
        Usage::Bound,
    )
    .optional(),
    // Stochastic direct lighting: a LightSampling pass's exact lights and samples.
    SlotSpec::new(LIGHT_SAMPLES, SlotType::Buffer, Access::Read, Usage::Bound)
        .optional()
        .needs(&[Contents::LightSamples]),
];

pub(crate) fn check(p: &VisibilityShading, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    check_light_source(ctx, p.lights, errors);
    let side = p.workgroup_side();
    if !WORKGROUP_SIDES.contains(&side) {
        errors.push(ctx.bad(format!(
            "workgroup {side} must be 8 or 16 (pixels per side)"
        )));
    } else if p.light_loop == LightLoop::Staged && side != 8 {
        errors.push(ctx.bad(
            "light_loop Staged stages one light per invocation of an 8×8 workgroup: use workgroup 8",
        ));
    }
    super::visibility_buffer::check_ids(ctx, errors);
    ctx.require_single_rgba32f(
        &[HDR],
        "visibility shading stores into a single-sample Rgba32Float texture",
        errors,
    );
    super::check_shadow_mask(ctx, errors);
    super::check_shadow_atlas(ctx, errors, Some(super::shadow_ray_jobs::SHADOW_MASK));
    super::check_bvh_trace(ctx, errors);
    if let Some(nodes) = ctx.slot(BVH_NODES) {
        if ctx.slot(SHADOW_MASK).is_some() || ctx.slot(SHADOW_ATLAS).is_some() {
            errors.push(ctx.mismatch(
                nodes,
                "a pass traces the BVH, or reads a shadow mask or an atlas, not two",
            ));
        }
    }
    if let Some(samples) = ctx.slot(LIGHT_SAMPLES) {
        if p.light_loop != LightLoop::Forward {
            errors.push(ctx.mismatch(
                samples,
                "light samples are shaded by the Forward light loop: set light_loop: Forward",
            ));
        }
        if ctx.slot(SHADOW_MASK).is_some()
            || ctx.slot(SHADOW_ATLAS).is_some()
            || ctx.slot(BVH_NODES).is_some()
        {
            errors.push(ctx.mismatch(
                samples,
                "light samples carry their own shadow rays: read them, a shadow mask, an atlas or the BVH, not two",
            ));
        }
    }
}

impl KindRules for VisibilityShading {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(self, ctx, errors)
    }
    fn check_inputs(&self, ctx: &InputsCtx, errors: &mut Vec<GraphError>) {
        super::check_hybrid_jobs(ctx, errors)
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::{errors, validate, CULL, PREPASS};

    const VIS: &str = r#"Pass(name: "v", kind: VisibilityBuffer, reads: ["geometry"], writes: ["depth", "vis"]),"#;
    const READS: &str = r#""vis", "vertices", "triangles", "material_triangles", "lg", "lp""#;

    #[test]
    fn reads_ids_and_the_merged_geometry() {
        validate(
            &format!(r#"{VIS} Pass(name: "s", kind: VisibilityShading(), reads: [{READS}], writes: ["hdr"])"#),
            "hdr",
        )
        .unwrap();
        let e = errors(
            &format!(
                r#"{VIS} Pass(name: "s", kind: VisibilityShading(), reads: ["vis", "vertices", "lg", "lp"], writes: ["hdr"])"#
            ),
            "hdr",
        );
        assert!(
            e.contains(
                "VisibilityShading needs an Import of Triangles in reads (slot 'triangles')"
            ),
            "{e}"
        );
    }

    #[test]
    fn light_loop_defaults_to_group_list_and_parses_each_kind() {
        use super::{LightLoop, VisibilityShading};
        let parse = |t: &str| ron::from_str::<VisibilityShading>(t).unwrap();
        assert_eq!(parse("(lights: Culled)").light_loop, LightLoop::GroupList);
        assert_eq!(
            VisibilityShading::default().light_loop,
            LightLoop::GroupList
        );
        assert_eq!(
            parse("(light_loop: RangeFirst)").light_loop,
            LightLoop::RangeFirst
        );
        assert_eq!(parse("(light_loop: Staged)").light_loop, LightLoop::Staged);
        assert_eq!(
            parse("(light_loop: Forward)").light_loop,
            LightLoop::Forward
        );
        assert_eq!(
            parse("(light_loop: GroupList)").light_loop,
            LightLoop::GroupList
        );
        assert_eq!(parse("()").workgroup_side(), 16);
        assert_eq!(parse("(light_loop: Staged)").workgroup_side(), 8);
        assert_eq!(parse("(light_loop: GroupList)").workgroup_side(), 16);
        assert_eq!(parse("(workgroup: 8)").workgroup_side(), 8);
        assert_eq!(parse("(workgroup: 16)").workgroup_side(), 16);
        assert!(ron::from_str::<VisibilityShading>("(staging: false)").is_err());
        assert!(ron::from_str::<VisibilityShading>("(light_loop: Fast)").is_err());
    }

    #[test]
    fn refuses_other_workgroups_and_staging_on_16() {
        let pass = |kind: &str| {
            format!(
                r#"{VIS} Pass(name: "s", kind: VisibilityShading({kind}), reads: [{READS}], writes: ["hdr"])"#
            )
        };
        for ok in [
            "workgroup: 8",
            "workgroup: 16",
            "light_loop: GroupList, workgroup: 16",
        ] {
            validate(&pass(ok), "hdr").unwrap();
        }
        let e = errors(&pass("workgroup: 12"), "hdr");
        assert!(e.contains("pass 's': workgroup 12 must be 8 or 16"), "{e}");
        let e = errors(&pass("light_loop: Staged, workgroup: 16"), "hdr");
        assert!(
            e.contains(
                "pass 's': light_loop Staged stages one light per invocation of an 8×8 workgroup"
            ),
            "{e}"
        );
    }

    #[test]
    fn takes_an_atlas_with_its_views_and_one_shadow_source() {
        const ATLAS: &str = r#"Pass(name: "a", kind: ShadowAtlas(), reads: ["geometry"], writes: ["atlas", "views"]),"#;
        let pass = |reads: &str| {
            format!(
                r#"{VIS} {ATLAS} Pass(name: "s", kind: VisibilityShading(), reads: [{READS}, {reads}], writes: ["hdr"])"#
            )
        };
        validate(&pass(r#""atlas", "shadow_views=views""#), "hdr").unwrap();
        let e = errors(&pass(r#""atlas""#), "hdr");
        assert!(
            e.contains(
                "pass 's', resource 'atlas': a shadow atlas is sampled through its view table"
            ),
            "{e}"
        );
    }

    /// The hybrid: the atlas for lights with a map, the mask of jobs that read the same
    /// view table for the rest.
    #[test]
    fn reads_the_atlas_and_the_mask_of_jobs_that_skip_mapped_lights() {
        let graph = |policy: &str, job_views: &str, shading: &str| {
            format!(
                r#"Pass(name: "a", kind: ShadowAtlas(policy: {policy}), reads: ["geometry"], writes: ["atlas", "views"]),
                {VIS} {CULL}
                Pass(name: "j", kind: ShadowRayJobs(), reads: ["visibility=vis", "vertices", "triangles", "lg", "lp", "lists"{job_views}], writes: ["jobs", "mask"]),
                Pass(name: "r", kind: ShadowRayCast(), reads: ["jobs", "visibility=vis", "vertices", "triangles", "lg", "bn", "bt"], writes: ["mask"]),
                Pass(name: "s", kind: {shading}, reads: [{READS}, "lists", "shadow_mask=mask", "atlas", "shadow_views=views"], writes: ["hdr"])"#
            )
        };
        let shading = "VisibilityShading(lights: Culled)";
        let job_views = r#", "shadow_views=views""#;
        for policy in ["All", "Nearest(16)", "ProjectedSize(64.0)", "Within(12.5)"] {
            validate(&graph(policy, job_views, shading), "hdr").unwrap();
        }
        let e = errors(&graph("All", "", shading), "hdr");
        assert!(
            e.contains("pass 's', resource 'mask': the pass samples the atlas for lights with a map in 'views' and reads the mask for the rest, but jobs pass 'j' does not read 'views'"),
            "{e}"
        );
        let e = errors(&graph("Nearest(4)", "", shading), "hdr");
        assert!(
            e.contains("pass 'a': policy Nearest(4) leaves the other shadow-casting lights to ray-cast shadows, but no ShadowRayJobs pass reads 'views'"),
            "{e}"
        );
        for (policy, problem) in [
            (
                "Nearest(0)",
                "policy Nearest(0): the count must be in 1..=65536",
            ),
            (
                "ProjectedSize(-2.0)",
                "policy ProjectedSize(-2): min_pixels must be in (0, 65536]",
            ),
            (
                "Within(0.0)",
                "policy Within(0): the distance must be positive and finite",
            ),
        ] {
            let e = errors(&graph(policy, job_views, shading), "hdr");
            assert!(e.contains(&format!("pass 'a': {problem}")), "{e}");
        }
        // A mask without the mapped lights' rays is read only by VisibilityShading with
        // the same atlas.
        let e = errors(
            &graph("All", job_views, shading).replace(r#", "atlas", "shadow_views=views"]"#, "]"),
            "hdr",
        );
        assert!(
            e.contains("pass 'j', resource 'mask': 's' reads 'mask', whose jobs pass 'j' casts no rays for lights with a map in 'views': read 'views' and its atlas too"),
            "{e}"
        );
    }

    #[test]
    fn takes_a_mask_with_its_lists_and_refuses_multisampled_ids() {
        let e = errors(
            &format!(
                r#"{VIS} {PREPASS} Pass(name: "s", kind: VisibilityShading(), reads: [{READS}, "shadow_mask=mask"], writes: ["hdr"])"#
            ),
            "hdr",
        );
        assert!(
            e.contains("resource 'mask': the shadow mask numbers the lights of the culled lists"),
            "{e}"
        );
        let e = errors(
            &format!(
                r#"{VIS} Pass(name: "s", kind: VisibilityShading(), reads: [{READS}], writes: ["hdr4"])"#
            ),
            "hdr",
        );
        assert!(e.contains("single-sample Rgba32Float"), "{e}");
    }
}
