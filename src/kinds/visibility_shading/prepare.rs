//! `VisibilityShading`: one compute dispatch per group of materials that share their code
//! (`render::materials::shared_code_groups`: the same shared code and, if textured, the
//! same images; `PerMaterial` splits the groups into one dispatch a material), rebuilding
//! each pixel's surface from its triangle id (shaders/visibility/visibility_shading.wgsl)
//! and finding its material among the group's (`shading_members`). A material in a group
//! of several runs `MaterialProgram::shared_wgsl`, its per-pixel constants read from
//! `material_constants`; one alone runs its own code. Textured materials sample with
//! explicit derivatives and bind their textures in group 2. With `materials: Classified`
//! and more than one group a classification dispatch first lists every tile under the
//! groups it holds (shaders/visibility/classify_materials.wgsl) and each group's
//! dispatch is indirect, over its own tiles; otherwise each covers the whole frame. A read
//! `shadow_mask` shadows the casters (`SHADOWS`, `SHADOW_MASK`), a read `shadow_atlas`
//! with its `shadow_views` samples their maps (`SHADOW_ATLAS`, as forward shading).

use super::{defines, PrepareCtx, PreparedPass, ShadeLists, Timestamps};
use crate::graph::kinds::visibility_shading::{LightLoop, MaterialDispatch};
use crate::graph::Name;
use crate::graph::{ListLayout, ScheduledPass, VisibilityShading};
use crate::render::device_limits::create_internal_buffer;
use crate::render::materials::{group_label, GroupConstants};
use crate::render::pipelines::PipelineKey;
use crate::render::scene_gpu::storage_buffer;
use crate::render::RenderError;
use std::collections::BTreeMap;
use std::sync::Arc;

struct ShadeDispatch {
    pipeline: Arc<wgpu::ComputePipeline>,
    bind: wgpu::BindGroup,
    textures: Option<wgpu::BindGroup>,
}

/// The classification's buffers and dispatches (see the module doc).
struct Classification {
    classify: Arc<wgpu::ComputePipeline>,
    classify_bind: wgpu::BindGroup,
    args: Arc<wgpu::ComputePipeline>,
    args_bind: wgpu::BindGroup,
    /// Tiles listed per slot, zeroed before every frame.
    counts: wgpu::Buffer,
    /// Three u32 a slot: the indirect arguments of its shading dispatch.
    dispatch: wgpu::Buffer,
    args_groups: u32,
}

pub(super) struct VisibilityShadingPass {
    name: Name,
    dispatches: Vec<ShadeDispatch>,
    classification: Option<Classification>,
    groups: [u32; 3],
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    p: &VisibilityShading,
) -> Result<VisibilityShadingPass, RenderError> {
    let mut offered = cx.declared(sp)?;
    let lists = cx.shading_lists(sp, p.lights, &mut offered)?;
    // A ray-cast mask or an atlas (validation refuses both at once); an atlas's
    // comparison sampler is offered here.
    let shadows = cx.shading_shadows(sp, &mut offered);
    let vpl = super::VplLookup::of(cx, sp);
    let samples = sample_defines(cx, sp);
    let has_indirect_lights = cx.scene.features().has_indirect_lights;
    let layout = tile_layout(cx, sp, lists);
    let side = p.workgroup_side();
    let light_loop = choose_light_loop(p.light_loop, layout, side);
    let ranges = cx.merged(&sp.name)?.material_ranges.clone();
    // Only materials that own triangles are shaded (blended ones never do); the first
    // dispatch also clears pixels nothing covers, so one runs even for a scene without
    // triangles.
    let mut shaded: Vec<usize> = (0..cx.gpu.materials.len())
        .filter(|&i| ranges.get(i).is_some_and(|r| r[0] < r[1]))
        .collect();
    if shaded.is_empty() {
        shaded.push(0);
    }
    let groups = [
        cx.size.width.div_ceil(side),
        cx.size.height.div_ceil(side),
        1,
    ];
    // Which materials share their code decides each material's code (shared, with its
    // constants from the buffer, or its own with them written in) whatever the dispatch
    // mode, so the three modes run the same code and give the same bits; `PerMaterial`
    // then gives each material its own dispatch.
    let sharing = crate::render::materials::shared_code_groups(&cx.gpu.materials, &shaded);
    let shares: std::collections::HashSet<usize> = sharing
        .iter()
        .filter(|g| g.len() > 1)
        .flatten()
        .copied()
        .collect();
    let shader_groups = match p.materials {
        MaterialDispatch::PerMaterial => shaded.iter().map(|&i| vec![i]).collect(),
        MaterialDispatch::PerShader | MaterialDispatch::Classified => sharing,
    };
    let constants = GroupConstants::new(&cx.gpu.materials, &shader_groups);
    let members = Members::new(&shader_groups, &ranges, &constants);
    constants.offer(&cx.device(), &mut offered);
    offered.buffer(
        "shading_members",
        &storage_buffer(
            &cx.device(),
            "shading members",
            bytemuck::cast_slice(&members.table),
            wgpu::BufferUsages::empty(),
        ),
    );
    let classified = p.materials == MaterialDispatch::Classified && shader_groups.len() > 1;
    let tiles = groups[0] * groups[1];
    let classification = if classified {
        Some(classification(
            cx,
            sp,
            &shader_groups,
            &ranges,
            side,
            tiles,
            &mut offered,
        )?)
    } else {
        None
    };
    // GroupList walks its list a subgroup of lights at a time where the device has
    // subgroup operations (shaders/visibility/staged_lights.wgsl's shade_list_subgroup).
    let subgroups = cx.device().features().contains(wgpu::Features::SUBGROUP);
    let mut dispatches = Vec::new();
    for (slot, group) in shader_groups.iter().enumerate() {
        let m = &cx.gpu.materials[group[0]];
        let mut d = vec![
            ("MEMBERS_FIRST", format!("{}u", members.first[slot])),
            ("MEMBERS_COUNT", format!("{}u", group.len())),
        ];
        if classified {
            d.push(("CLASSIFIED", "1".into()));
            d.push(("MATERIAL_SLOT", format!("{slot}u")));
            d.push(("TILES", format!("{tiles}u")));
        } else if slot == 0 {
            d.push(("CLEARS", "1".into()));
        }
        if m.textures.is_some() {
            d.push(("MATERIAL_TEXTURED", "1".into()));
        }
        // A material that shares its code with none keeps its constants in its code:
        // literals let the compiler fold what they feed (harada pays nothing for grouping).
        let shared = shares.contains(&group[0]);
        if shared {
            d.push(("SHARED_CODE", "1".into()));
        }
        d.extend(lists.define());
        d.extend(loop_define(light_loop));
        d.extend(crate::render::draws::shadow_defines(shadows));
        d.extend(crate::render::draws::vpl_defines(has_indirect_lights));
        d.extend(super::VplLookup::defines(vpl));
        d.extend(samples.iter().cloned());
        // The shader's `@workgroup_size(SHADING_GROUP, SHADING_GROUP, 1)`.
        d.push(("SHADING_GROUP", format!("{side}u")));
        if light_loop == LightLoop::GroupList {
            d.push(("UNIFORM_LIST", "1".into()));
            if subgroups {
                d.push(("SUBGROUP_LIST", "1".into()));
            }
        }
        let key = PipelineKey {
            shader: "visibility/visibility_shading.wgsl".into(),
            defines: defines(&d),
            virtual_code: BTreeMap::from([(
                "material".to_string(),
                m.group_code(shared).to_string(),
            )]),
            state: String::new(),
        };
        let label = group_label(&sp.name, &cx.gpu.materials, group);
        let textures = m.textures.clone();
        let (pipeline, bind, textures) =
            cx.compute_pipeline_with_material(&label, key, "main", &offered, textures.as_ref())?;
        dispatches.push(ShadeDispatch {
            pipeline,
            bind,
            textures,
        });
    }
    Ok(VisibilityShadingPass {
        name: sp.name.clone(),
        dispatches,
        classification,
        groups,
    })
}

/// The shading groups' materials as the shader finds them: per material (group by group)
/// its triangle range and first constant (`shading_members`), and each group's first
/// entry.
struct Members {
    /// (first triangle, end, first constant, 0) per material, group by group.
    table: Vec<[u32; 4]>,
    /// Each group's first entry in `table`.
    first: Vec<u32>,
}

impl Members {
    fn new(groups: &[Vec<usize>], ranges: &[[u32; 2]], constants: &GroupConstants) -> Self {
        let mut out = Members {
            table: Vec::new(),
            first: Vec::new(),
        };
        for group in groups {
            out.first.push(out.table.len() as u32);
            for &i in group {
                let [first, end] = ranges.get(i).copied().unwrap_or([0, 0]);
                out.table.push([first, end, constants.first[i], 0]);
            }
        }
        out
    }
}

/// The light loop's defines for a read `light_samples` buffer (common/light_samples.wgsl):
/// its exact lights and samples a pixel and the region of reservoirs to read. None when the
/// scene has no shadow-casting lights: the sampling pass is then culled (`when:
/// ShadowCasters`) and every light is shaded exactly. `SAMPLED_ONLY` when every light the
/// lists can name casts (no light without shadows, no VPLs): the loop then skips the list.
/// A light update cannot add a light without shadows to such a scene (`NewFeature`).
fn sample_defines(cx: &PrepareCtx, sp: &ScheduledPass) -> Vec<(&'static str, String)> {
    use crate::graph::kinds::light_sampling::LIGHT_SAMPLES;
    let features = cx.scene.features();
    if !features.has_shadow_casters {
        return vec![];
    }
    let Some(name) = sp.roles.slot(LIGHT_SAMPLES) else {
        return vec![];
    };
    match cx.graph.plan.get(name).and_then(|r| r.layout) {
        Some(crate::graph::BufferLayout::LightSamples(l)) => {
            let mut d = vec![
                ("LIGHT_SAMPLES", "1".into()),
                ("SAMPLE_EXACT", format!("{}u", l.exact)),
                ("SAMPLE_COUNT", format!("{}u", l.samples)),
                ("SAMPLE_REGION", format!("{}u", u32::from(l.spatial))),
            ];
            if !features.has_unshadowed_lights && !features.has_indirect_lights {
                d.push(("SAMPLED_ONLY", "1".into()));
            }
            d
        }
        _ => vec![],
    }
}

/// The classification of the shading groups (slot k: `groups[k]`) over `tiles` tiles of
/// `side` pixels; offers its buffers to the shading dispatches in `offered`.
fn classification(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    groups: &[Vec<usize>],
    ranges: &[[u32; 2]],
    side: u32,
    tiles: u32,
    offered: &mut crate::render::bind::BindingSet,
) -> Result<Classification, RenderError> {
    let device = cx.device();
    let slots = groups.len() as u32;
    // Every shaded material with its group, ascending by first triangle: draws are sorted
    // by material, so material indices are too.
    let mut slot_triangles: Vec<[u32; 4]> = groups
        .iter()
        .enumerate()
        .flat_map(|(g, group)| group.iter().map(move |&m| (m, g as u32)))
        .map(|(m, g)| [ranges[m][0], ranges[m][1], g, 0])
        .collect();
    slot_triangles.sort_unstable();
    let members = slot_triangles.len() as u32;
    let storage = wgpu::BufferUsages::STORAGE;
    // Checked against the device's limits, naming the pass: the tile lists grow with the
    // materials times the tiles.
    let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
        create_internal_buffer(
            &device,
            &sp.name,
            &wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(4),
                usage,
                mapped_at_creation: false,
            },
        )
    };
    let slot_buffer = storage_buffer(
        &device,
        "material slot triangles",
        bytemuck::cast_slice(&slot_triangles),
        wgpu::BufferUsages::empty(),
    );
    let material_tiles = buffer(
        "material tiles",
        u64::from(slots) * u64::from(tiles) * 4,
        storage,
    )?;
    let counts = buffer(
        "material tile counts",
        u64::from(slots) * 4,
        storage | wgpu::BufferUsages::COPY_DST,
    )?;
    let dispatch = buffer(
        "material dispatch arguments",
        u64::from(slots) * 12,
        storage | wgpu::BufferUsages::INDIRECT,
    )?;
    offered.buffer("slot_triangles", &slot_buffer);
    offered.buffer("material_tiles", &material_tiles);
    offered.buffer("material_tile_counts", &counts);
    offered.buffer("material_dispatch", &dispatch);
    let d = [
        ("SHADING_GROUP", format!("{side}u")),
        ("SLOTS", format!("{slots}u")),
        ("MEMBERS", format!("{members}u")),
        ("TILES", format!("{tiles}u")),
    ];
    let key = |entry: &str| PipelineKey {
        shader: "visibility/classify_materials.wgsl".into(),
        defines: defines(&d),
        virtual_code: BTreeMap::new(),
        state: entry.to_string(),
    };
    let label = format!("{} (classification)", sp.name);
    let (classify, classify_bind) =
        cx.compute_pipeline(&label, key("classify"), "classify", offered)?;
    let (args, args_bind) =
        cx.compute_pipeline(&label, key("dispatch_args"), "dispatch_args", offered)?;
    Ok(Classification {
        classify,
        classify_bind,
        args,
        args_bind,
        counts,
        dispatch,
        args_groups: slots.div_ceil(64),
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
        if let Some(c) = &self.classification {
            encoder.clear_buffer(&c.counts, 0, None);
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&self.name),
            timestamp_writes: ts.compute(),
        });
        let [x, y, z] = self.groups;
        if let Some(c) = &self.classification {
            pass.set_pipeline(&c.classify);
            pass.set_bind_group(0, &c.classify_bind, &[]);
            pass.dispatch_workgroups(x, y, z);
            pass.set_pipeline(&c.args);
            pass.set_bind_group(0, &c.args_bind, &[]);
            pass.dispatch_workgroups(c.args_groups, 1, 1);
        }
        for (slot, d) in self.dispatches.iter().enumerate() {
            pass.set_pipeline(&d.pipeline);
            pass.set_bind_group(0, &d.bind, &[]);
            if let Some(t) = &d.textures {
                pass.set_bind_group(2, t, &[]);
            }
            match &self.classification {
                Some(c) => pass.dispatch_workgroups_indirect(&c.dispatch, slot as u64 * 12),
                None => pass.dispatch_workgroups(x, y, z),
            }
        }
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
