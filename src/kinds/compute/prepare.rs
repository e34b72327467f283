//! `Compute`: a shader the graph names, dispatched per pixel, tile, light or a fixed
//! grid; bound by reflected binding names (auto layout).

use super::{dispatch, pass_error, PrepareCtx, PreparedPass, Timestamps};
use crate::graph::Name;
use crate::graph::{Dispatch, ScheduledPass};
use crate::render::bind::Bound;
use crate::render::pipelines::{Pipeline, PipelineKey};
use crate::render::RenderError;
use std::collections::BTreeMap;
use std::sync::Arc;

pub(super) struct ComputePass {
    name: Name,
    pipeline: Arc<wgpu::ComputePipeline>,
    bind: wgpu::BindGroup,
    groups: [u32; 3],
    /// For `PerLight` dispatches: the workgroup size and the light count it is run for
    /// now (light updates change it; the dispatch limit was checked at the capacity).
    per_light: Option<(u32, crate::render::LightCount)>,
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    shader: &str,
    entry: &str,
    d: Dispatch,
) -> Result<ComputePass, RenderError> {
    let device = cx.device();
    let key = PipelineKey {
        shader: shader.to_string(),
        defines: BTreeMap::new(),
        virtual_code: BTreeMap::new(),
        state: format!("compute entry={entry}"),
    };
    let (pipeline, bindings) = cx
        .renderer
        .pipelines
        .get_or_build_reflected(
            &cx.renderer.shaders,
            key,
            |_, module, _| Pipeline::compute(&device, &sp.name, None, &module, entry),
            &device,
        )
        .map_err(|source| RenderError::Shader {
            pass: sp.name.to_string(),
            source,
        })?;
    let Pipeline::Compute(pipeline) = pipeline else {
        return Err(pass_error(&sp.name, "expected a compute pipeline".into()));
    };
    let bind = bind_generic(cx, sp, &pipeline.get_bind_group_layout(0), &bindings)?;
    let size = cx.size;
    let groups = match d {
        Dispatch::PerPixel { workgroup: (x, y) } => [
            size.width.div_ceil(x.max(1)),
            size.height.div_ceil(y.max(1)),
            1,
        ],
        Dispatch::PerTile { tile } => [
            size.width.div_ceil(tile.max(1)),
            size.height.div_ceil(tile.max(1)),
            1,
        ],
        Dispatch::PerLight { workgroup } => [
            cx.gpu.light_capacity.div_ceil(workgroup.max(1)).max(1),
            1,
            1,
        ],
        Dispatch::Fixed(x, y, z) => [x, y, z],
    };
    crate::render::device_limits::check_dispatch(cx.graph, &sp.name, groups, &device.limits())?;
    let per_light = match d {
        Dispatch::PerLight { workgroup } => Some((workgroup.max(1), cx.light_count.clone())),
        _ => None,
    };
    Ok(ComputePass {
        name: sp.name.clone(),
        pipeline,
        bind,
        groups,
        per_light,
    })
}

/// A generic pass's group 0 on the auto-derived `layout`: its declared resources plus the
/// samplers every generic shader may use, by reflected name.
pub(super) fn bind_generic(
    cx: &PrepareCtx,
    sp: &ScheduledPass,
    layout: &wgpu::BindGroupLayout,
    bindings: &[crate::shader::ReflectedBinding],
) -> Result<wgpu::BindGroup, RenderError> {
    let device = &cx.renderer.ctx.device;
    let mut set = cx.declared(sp)?;
    set.offer(
        "linear_sampler",
        Bound::Sampler(device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("linear_sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        })),
    );
    set.offer(
        "nearest_sampler",
        Bound::Sampler(device.create_sampler(&Default::default())),
    );
    set.bind(device, &sp.name, layout, bindings, 0)
        .map_err(|m| pass_error(&sp.name, m))
}

impl PreparedPass for ComputePass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        dispatch(
            encoder,
            &self.name,
            ts,
            &self.pipeline,
            &self.bind,
            match &self.per_light {
                Some((w, lights)) => [lights.get().div_ceil(*w).max(1), 1, 1],
                None => self.groups,
            },
        );
    }
}
