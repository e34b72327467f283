//! `ShadowRayJobs`: job creation over every pixel, then the one-invocation `finalize`
//! that writes the casting pass's indirect dispatch, in one compute pass; reports the
//! jobs wanted, dropped and the pixels with more casters than the mask holds.

use super::{defines, PrepareCtx, PreparedPass, Timestamps};
use crate::gpu::readback::read_buffer_range;
use crate::graph::kinds::shadow_ray_cast::DEFAULT_NORMAL_OFFSET;
use crate::graph::kinds::shadow_ray_jobs::{self as kind, SHADOW_JOBS, SHADOW_MASK};
use crate::graph::kinds::shadow_ray_jobs::{surface_source, SurfaceSource};
use crate::graph::Name;
use crate::graph::{slot, ScheduledPass, ShadowRayJobs};
use crate::render::pipelines::PipelineKey;
use crate::render::report::{PassReport, ShadowReport};
use crate::render::{RenderError, Renderer};
use std::collections::BTreeMap;
use std::sync::Arc;

pub(super) struct ShadowRayJobsPass {
    name: Name,
    pipeline: Arc<wgpu::ComputePipeline>,
    finalize: Arc<wgpu::ComputePipeline>,
    bind: wgpu::BindGroup,
    groups: [u32; 3],
    jobs: wgpu::Buffer,
    capacity: u64,
    mask_bytes: u64,
    pixels: u64,
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    p: &ShadowRayJobs,
) -> Result<ShadowRayJobsPass, RenderError> {
    let capacity = p.capacity(cx.size.width, cx.size.height);
    let jobs = cx.buffer(&sp.name, sp.required(SHADOW_JOBS))?;
    let mask = cx.buffer(&sp.name, sp.required(SHADOW_MASK))?;
    let mut offered = cx.declared(sp)?;
    let params = cx.list_params(&sp.name, sp.required(slot::LIGHT_LISTS))?;
    offered.buffer("list_params", &params);
    let mut d = vec![
        ("LIGHT_LISTS", "1".into()),
        (
            "JOB_CAPACITY",
            format!("{}u", capacity.min(u32::MAX as u64)),
        ),
        ("SHADOW_NORMAL_OFFSET", format!("{DEFAULT_NORMAL_OFFSET:?}")),
    ];
    d.extend(surface_define(&sp.roles));
    // The hybrid: lights with an atlas map this frame get no job.
    if sp
        .roles
        .slot(crate::graph::kinds::shadow_atlas::SHADOW_VIEWS)
        .is_some()
    {
        d.push(("SHADOW_ATLAS_LIGHTS", "1".into()));
    }
    let key = |state: &str| PipelineKey {
        shader: "shadow/shadow_ray_jobs.wgsl".into(),
        defines: defines(&d),
        virtual_code: BTreeMap::new(),
        state: state.to_string(),
    };
    let (pipeline, bind) = cx.compute_pipeline(&sp.name, key(""), "main", &offered)?;
    let (finalize, _) = cx.compute_pipeline(&sp.name, key("finalize"), "finalize", &offered)?;
    let pixels = cx.size.width as u64 * cx.size.height as u64;
    Ok(ShadowRayJobsPass {
        name: sp.name.clone(),
        pipeline,
        finalize,
        bind,
        groups: [cx.size.width.div_ceil(16), cx.size.height.div_ceil(16), 1],
        jobs,
        capacity,
        mask_bytes: mask.size(),
        pixels,
    })
}

/// The define that makes the shadow shaders rebuild surfaces from visibility-buffer ids
/// (shaders/shadow/surface_source.wgsl) instead of loading the G-buffer.
pub(super) fn surface_define(roles: &crate::graph::PassRoles) -> Option<(&'static str, String)> {
    match surface_source(roles) {
        SurfaceSource::GBuffer => None,
        SurfaceSource::VisibilityBuffer => Some(("VISIBILITY_IDS", "1".into())),
    }
}

impl PreparedPass for ShadowRayJobsPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        // The counters start at zero each frame.
        encoder.clear_buffer(&self.jobs, 0, Some(4 * kind::JOB_HEADER_WORDS));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&self.name),
            timestamp_writes: ts.compute(),
        });
        pass.set_bind_group(0, &self.bind, &[]);
        pass.set_pipeline(&self.pipeline);
        let [x, y, z] = self.groups;
        pass.dispatch_workgroups(x, y, z);
        pass.set_pipeline(&self.finalize);
        pass.dispatch_workgroups(1, 1, 1);
    }

    fn report(&self, r: &Renderer) -> Result<Option<PassReport>, RenderError> {
        let bytes = read_buffer_range(&r.ctx.device, &r.ctx.queue, &self.jobs, 0, 16)?;
        let w: &[u32] = bytemuck::cast_slice(&bytes);
        Ok(Some(PassReport::Shadow(ShadowReport {
            pass: self.name.to_string(),
            jobs_wanted: w[0] as u64,
            jobs_dropped: w[1] as u64,
            overflow_pixels: w[2] as u64,
            capacity: self.capacity,
            job_bytes: self.jobs.size(),
            mask_bytes: self.mask_bytes,
            pixels: self.pixels,
        })))
    }
}
