//! `ShadowCompare`: one compute dispatch over the frame counting the (pixel, light)
//! pairs where the atlas and the ray-cast mask disagree; read back as a report.

use super::{defines, dispatch, pass_error, PrepareCtx, PreparedPass, Timestamps};
use crate::gpu::readback::read_buffer_range;
use crate::graph::kinds::forward_shading::Shadows;
use crate::graph::kinds::shadow_atlas::ShadowFilter;
use crate::graph::kinds::shadow_compare::{ERROR_WORDS, SHADOW_ERRORS};
use crate::graph::kinds::shadow_ray_cast::DEFAULT_NORMAL_OFFSET;
use crate::graph::Name;
use crate::graph::{slot, ScheduledPass};
use crate::render::pipelines::PipelineKey;
use crate::render::report::{PassReport, ShadowCompareReport};
use crate::render::{RenderError, Renderer};
use std::collections::BTreeMap;
use std::sync::Arc;

pub(super) struct ShadowComparePass {
    name: Name,
    pipeline: Arc<wgpu::ComputePipeline>,
    bind: wgpu::BindGroup,
    groups: [u32; 3],
    errors: wgpu::Buffer,
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
) -> Result<ShadowComparePass, RenderError> {
    let errors = cx.buffer(&sp.name, sp.required(SHADOW_ERRORS))?;
    if errors.size() < 4 * ERROR_WORDS {
        return Err(pass_error(
            &sp.name,
            format!(
                "buffer '{}' holds {} bytes; the counters need {}",
                sp.required(SHADOW_ERRORS),
                errors.size(),
                4 * ERROR_WORDS
            ),
        ));
    }
    let mut offered = cx.declared(sp)?;
    let params = cx.list_params(&sp.name, sp.required(slot::LIGHT_LISTS))?;
    offered.buffer("list_params", &params);
    offered.offer("shadow_sampler", super::comparison_sampler(&cx.device()));
    offered.offer("shadow_gather", super::gather_sampler(&cx.device()));
    // Both filters are compared; the atlas's raster says how it is read.
    let raster = match crate::graph::kinds::forward_shading::shadows(&sp.roles, &cx.graph.plan) {
        Shadows::Atlas(_, raster) => raster,
        _ => Default::default(),
    };
    let mut d = vec![
        ("LIGHT_LISTS", "1".into()),
        ("SHADOW_NORMAL_OFFSET", format!("{DEFAULT_NORMAL_OFFSET:?}")),
    ];
    d.extend(
        crate::render::draws::atlas_defines(ShadowFilter::Hardware2x2, raster)
            .into_iter()
            .filter(|(k, _)| *k != "SHADOW_PCF5"),
    );
    let key = PipelineKey {
        shader: "shadow/shadow_compare.wgsl".into(),
        defines: defines(&d),
        virtual_code: BTreeMap::new(),
        state: String::new(),
    };
    let (pipeline, bind) = cx.compute_pipeline(&sp.name, key, "main", &offered)?;
    Ok(ShadowComparePass {
        name: sp.name.clone(),
        pipeline,
        bind,
        groups: [cx.size.width.div_ceil(8), cx.size.height.div_ceil(8), 1],
        errors,
    })
}

impl PreparedPass for ShadowComparePass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        encoder.clear_buffer(&self.errors, 0, Some(4 * ERROR_WORDS));
        dispatch(
            encoder,
            &self.name,
            ts,
            &self.pipeline,
            &self.bind,
            self.groups,
        );
    }

    fn report(&self, r: &Renderer) -> Result<Option<PassReport>, RenderError> {
        let bytes = read_buffer_range(&r.ctx.device, &r.ctx.queue, &self.errors, 0, 16)?;
        let w: &[u32] = bytemuck::cast_slice(&bytes);
        Ok(Some(PassReport::ShadowCompare(ShadowCompareReport {
            pass: self.name.to_string(),
            pairs: w[0] as u64,
            disagree_pcf5: w[1] as u64,
            disagree_2x2: w[2] as u64,
            penumbra_pcf5: w[3] as u64,
        })))
    }
}
