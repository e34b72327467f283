//! `DeferredShading`: one compute dispatch per material over the frame, reading the
//! G-buffer and storing lit colour; from a multisampled G-buffer, the mean of every
//! sample's colour (shaders/deferred/deferred_msaa.wgsl).

use super::{defines, pass_error, PrepareCtx, PreparedPass, Timestamps};
use crate::graph::kinds::deferred_shading::HDR;
use crate::graph::kinds::g_buffer::G_NORMAL;
use crate::graph::Name;
use crate::graph::{DeferredShading, ScheduledPass};
use crate::render::pipelines::PipelineKey;
use crate::render::RenderError;
use std::collections::BTreeMap;
use std::sync::Arc;

pub(super) struct DeferredShadingPass {
    name: Name,
    pipelines: Vec<Arc<wgpu::ComputePipeline>>,
    bind: Option<wgpu::BindGroup>,
    groups: [u32; 3],
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    p: &DeferredShading,
) -> Result<DeferredShadingPass, RenderError> {
    // Without a normals texture the G-buffer is the packed one.
    let packed = sp.roles.slot(G_NORMAL).is_none();
    let mut offered = cx.declared(sp)?;
    let lists = cx.shading_lists(sp, p.lights, &mut offered)?;
    let shadows = cx.shading_shadows(sp, &mut offered);
    // A multisampled G-buffer: every distinct sample shaded, the mean stored. Pixels whose
    // samples hold several materials sum over the materials' dispatches in `hdr`, which
    // each reads back (read-write storage; the MSAA formats already need the adapter's
    // format features).
    let msaa = sp.samples > 1;
    if msaa {
        let flags = cx
            .renderer
            .ctx
            .adapter
            .get_texture_format_features(wgpu::TextureFormat::Rgba32Float)
            .flags;
        let features = cx.device().features();
        if !features.contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES)
            || !flags.contains(wgpu::TextureFormatFeatureFlags::STORAGE_READ_WRITE)
        {
            return Err(pass_error(
                &sp.name,
                format!(
                    "a multisampled G-buffer needs read-write storage of Rgba32Float for '{}' (samples of several materials are summed there), which this adapter ({}) lacks",
                    sp.required(HDR),
                    cx.renderer.ctx.adapter.get_info().name
                ),
            ));
        }
    }
    let mut pipelines = Vec::new();
    let mut bind = None;
    for (index, m) in cx.gpu.materials.iter().enumerate() {
        if m.textures.is_some() {
            return Err(pass_error(
                &sp.name,
                format!("material '{}' has textures; deferred shading supports untextured materials only (the G-buffer holds no UVs or tangents yet)", m.name),
            ));
        }
        let mut d = vec![("MATERIAL_INDEX", index.to_string())];
        if packed {
            d.push(("G_PACKED", "1".into()));
        }
        if msaa {
            d.push(("G_SAMPLES", sp.samples.to_string()));
        }
        d.extend(lists.define());
        d.extend(crate::render::draws::shadow_defines(shadows));
        let key = PipelineKey {
            shader: "deferred/deferred_shading.wgsl".into(),
            defines: defines(&d),
            virtual_code: BTreeMap::from([("material".to_string(), m.wgsl.clone())]),
            state: String::new(),
        };
        let label = format!("{} (material '{}')", sp.name, m.name);
        let (pipeline, b) = cx.compute_pipeline(&label, key, "main", &offered)?;
        pipelines.push(pipeline);
        // Every material's shader declares the same bindings: one group serves all.
        bind.get_or_insert(b);
    }
    Ok(DeferredShadingPass {
        name: sp.name.clone(),
        pipelines,
        bind,
        groups: [cx.size.width.div_ceil(8), cx.size.height.div_ceil(8), 1],
    })
}

impl PreparedPass for DeferredShadingPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&self.name),
            timestamp_writes: ts.compute(),
        });
        if let Some(bind) = &self.bind {
            pass.set_bind_group(0, bind, &[]);
        }
        let [x, y, z] = self.groups;
        for p in &self.pipelines {
            pass.set_pipeline(p);
            pass.dispatch_workgroups(x, y, z);
        }
    }
}

impl super::PrepareKind for crate::graph::kinds::deferred_shading::DeferredShading {
    fn prepare(
        &self,
        cx: &mut PrepareCtx<'_>,
        sp: &ScheduledPass,
    ) -> Result<Box<dyn super::PreparedPass>, RenderError> {
        Ok(Box::new(prepare(cx, sp, self)?))
    }
}
