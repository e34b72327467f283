//! `VisibilityShading`: one compute dispatch per material with triangles over the frame,
//! rebuilding each pixel's surface from its triangle id (shaders/visibility/
//! visibility_shading.wgsl). Textured materials sample with explicit derivatives
//! (`MaterialProgram::compute_wgsl`) and bind their textures in group 2.

use super::{defines, PrepareCtx, PreparedPass, Timestamps};
use crate::graph::Name;
use crate::graph::{ScheduledPass, VisibilityShading};
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
        groups: [cx.size.width.div_ceil(8), cx.size.height.div_ceil(8), 1],
    })
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
