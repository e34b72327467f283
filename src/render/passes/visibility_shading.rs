//! `VisibilityShading`: one compute dispatch per material with triangles over the frame,
//! rebuilding each pixel's surface from its triangle id (shaders/visibility/
//! visibility_shading.wgsl). Textured materials sample with explicit derivatives
//! (`MaterialProgram::compute_wgsl`) and bind their textures in group 2.

use super::{defines, PrepareCtx, PreparedPass, ShadeLists, Timestamps};
use crate::graph::kinds::visibility_shading::LightLoop;
use crate::graph::Name;
use crate::graph::{ListLayout, ScheduledPass, VisibilityShading};
use crate::render::pipelines::PipelineKey;
use crate::render::RenderError;
use std::collections::BTreeMap;
use std::sync::Arc;

struct MaterialDispatch {
    pipeline: Arc<wgpu::ComputePipeline>,
    textures: Option<wgpu::BindGroup>,
}

pub(super) struct VisibilityShadingPass {
    name: Name,
    dispatches: Vec<MaterialDispatch>,
    bind: wgpu::BindGroup,
    groups: [u32; 3],
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    p: &VisibilityShading,
) -> Result<VisibilityShadingPass, RenderError> {
    let mut offered = cx.declared(sp)?;
    let lists = cx.shading_lists(sp, p.lights, &mut offered)?;
    let layout = tile_layout(cx, sp, lists);
    let side = p.workgroup_side();
    let light_loop = choose_light_loop(p.light_loop, layout, side);
    let ranges = cx.merged(&sp.name)?.material_ranges.clone();
    // Only materials that own triangles get a dispatch (blended ones never do); the first
    // also clears pixels nothing covers, so one runs even for a scene without triangles.
    let mut shaded: Vec<usize> = (0..cx.gpu.materials.len())
        .filter(|&i| ranges.get(i).is_some_and(|r| r[0] < r[1]))
        .collect();
    if shaded.is_empty() {
        shaded.push(0);
    }
    let mut dispatches = Vec::new();
    let mut bind = None;
    for (k, &index) in shaded.iter().enumerate() {
        let m = &cx.gpu.materials[index];
        let mut d = vec![("MATERIAL_INDEX", index.to_string())];
        if k == 0 {
            d.push(("CLEARS", "1".into()));
        }
        if m.textures.is_some() {
            d.push(("MATERIAL_TEXTURED", "1".into()));
        }
        d.extend(lists.define());
        d.extend(loop_define(light_loop));
        // The shader's `@workgroup_size(SHADING_GROUP, SHADING_GROUP, 1)`.
        d.push(("SHADING_GROUP", format!("{side}u")));
        if light_loop == LightLoop::GroupList {
            d.push(("UNIFORM_LIST", "1".into()));
        }
        let key = PipelineKey {
            shader: "visibility/visibility_shading.wgsl".into(),
            defines: defines(&d),
            virtual_code: BTreeMap::from([(
                "material".to_string(),
                m.wgsl_for_compute().to_string(),
            )]),
            state: String::new(),
        };
        let label = format!("{} (material '{}')", sp.name, m.name);
        let textures = m.textures.clone();
        let (pipeline, b, textures) =
            cx.compute_pipeline_with_material(&label, key, "main", &offered, textures.as_ref())?;
        dispatches.push(MaterialDispatch { pipeline, textures });
        // Every material's shader declares the same group-0 bindings: one group serves all.
        bind.get_or_insert(b);
    }
    Ok(VisibilityShadingPass {
        name: sp.name.clone(),
        dispatches,
        bind: bind.ok_or_else(|| super::pass_error(&sp.name, "no material to shade".into()))?,
        groups: [
            cx.size.width.div_ceil(side),
            cx.size.height.div_ceil(side),
            1,
        ],
    })
}

/// The define that picks the shader's light loop (shaders/visibility/staged_lights.wgsl).
fn loop_define(l: LightLoop) -> Option<(&'static str, String)> {
    match l {
        LightLoop::Forward => None,
        LightLoop::RangeFirst | LightLoop::GroupList => Some(("RANGE_FIRST", "1".into())),
        LightLoop::Staged => Some(("STAGED_LIGHTS", "1".into())),
    }
}

/// The tile lists' layout when the pass reads tile lists.
fn tile_layout(cx: &PrepareCtx, sp: &ScheduledPass, lists: ShadeLists) -> Option<ListLayout> {
    match lists {
        ShadeLists::Tiles => cx
            .graph
            .plan
            .list_layout(sp.required(crate::graph::slot::LIGHT_LISTS)),
        ShadeLists::AllLights | ShadeLists::Links => None,
    }
}

/// `Staged` and `GroupList` only for tile lists with one list per tile (Frustum,
/// DepthMask) whose tile is a multiple of the workgroup's side `side`, so no workgroup
/// straddles two tiles (`RangeFirst` otherwise); `layout` is `None` for linked lists and
/// all lights.
fn choose_light_loop(asked: LightLoop, layout: Option<ListLayout>, side: u32) -> LightLoop {
    let one_list = layout.is_some_and(|l| l.lists_per_tile == 1 && l.tile % side == 0);
    match asked {
        LightLoop::Staged | LightLoop::GroupList if !one_list => LightLoop::RangeFirst,
        other => other,
    }
}

impl PreparedPass for VisibilityShadingPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&self.name),
            timestamp_writes: ts.compute(),
        });
        pass.set_bind_group(0, &self.bind, &[]);
        let [x, y, z] = self.groups;
        for d in &self.dispatches {
            pass.set_pipeline(&d.pipeline);
            if let Some(t) = &d.textures {
                pass.set_bind_group(2, t, &[]);
            }
            pass.dispatch_workgroups(x, y, z);
        }
    }
}

impl super::PrepareKind for crate::graph::kinds::visibility_shading::VisibilityShading {
    fn prepare(
        &self,
        cx: &mut PrepareCtx<'_>,
        sp: &ScheduledPass,
    ) -> Result<Box<dyn super::PreparedPass>, RenderError> {
        Ok(Box::new(prepare(cx, sp, self)?))
    }
}

#[cfg(test)]
mod tests {
    use super::choose_light_loop;
    use crate::graph::kinds::visibility_shading::LightLoop::{
        Forward, GroupList, RangeFirst, Staged,
    };
    use crate::graph::{CullVariant, ListLayout, ListStorage};

    fn layout(tile: u32, variant: CullVariant) -> Option<ListLayout> {
        let storage = ListStorage::Compact {
            max_indices: 1024,
            scratch: 256,
        };
        Some(ListLayout::new(tile, variant, storage, 333, 197))
    }

    #[test]
    fn stages_one_list_per_tile_and_walks_the_rest_per_pixel() {
        for tile in [8, 16] {
            for variant in [CullVariant::Frustum, CullVariant::DepthMask] {
                let l = layout(tile, variant);
                assert_eq!(choose_light_loop(Staged, l, 8), Staged, "{l:?}");
                assert_eq!(choose_light_loop(GroupList, l, 8), GroupList, "{l:?}");
                assert_eq!(choose_light_loop(Forward, l, 8), Forward, "{l:?}");
                assert_eq!(choose_light_loop(RangeFirst, l, 8), RangeFirst, "{l:?}");
            }
            for variant in [CullVariant::HalfZ, CullVariant::Clustered { slices: 16 }] {
                let l = layout(tile, variant);
                assert_eq!(choose_light_loop(Staged, l, 8), RangeFirst, "{l:?}");
                assert_eq!(choose_light_loop(GroupList, l, 8), RangeFirst, "{l:?}");
            }
        }
        // A 16-pixel workgroup straddles two 8-pixel tiles.
        let l = layout(8, CullVariant::Frustum);
        assert_eq!(choose_light_loop(GroupList, l, 16), RangeFirst);
        let l = layout(16, CullVariant::Frustum);
        assert_eq!(choose_light_loop(GroupList, l, 16), GroupList);
        // A tile the workgroup would straddle (the culling pass refuses it today).
        let l = layout(12, CullVariant::Frustum);
        assert_eq!(choose_light_loop(Staged, l, 8), RangeFirst);
        assert_eq!(choose_light_loop(Staged, None, 8), RangeFirst);
        assert_eq!(choose_light_loop(GroupList, None, 8), RangeFirst);
        assert_eq!(choose_light_loop(Forward, None, 8), Forward);
    }
}
