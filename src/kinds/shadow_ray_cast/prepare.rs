//! `ShadowRayCast`: one invocation per job, dispatched indirectly from the dispatch the
//! job pass wrote into the job buffer's header.

use super::{defines, pass_error, PrepareCtx, PreparedPass, Timestamps};
use crate::graph::kinds::shadow_ray_jobs::SHADOW_JOBS;
use crate::graph::Name;
use crate::graph::{BufferLayout, ScheduledPass, ShadowRayCast};
use crate::render::pipelines::PipelineKey;
use crate::render::RenderError;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Byte offset of the indirect dispatch in the job buffer (after four counters).
const DISPATCH_OFFSET: u64 = 16;

pub(super) struct ShadowRayCastPass {
    name: Name,
    pipeline: Arc<wgpu::ComputePipeline>,
    bind: wgpu::BindGroup,
    jobs: wgpu::Buffer,
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    p: &ShadowRayCast,
) -> Result<ShadowRayCastPass, RenderError> {
    let jobs_name = sp.required(SHADOW_JOBS);
    let jobs = cx.buffer(&sp.name, jobs_name)?;
    // The job pass declared to write this buffer published its capacity on it.
    let capacity = match cx.graph.plan.get(jobs_name).and_then(|r| r.layout) {
        Some(BufferLayout::ShadowJobs { capacity, .. }) => capacity,
        _ => {
            return Err(pass_error(
                &sp.name,
                format!("no ShadowRayJobs pass is declared to write '{jobs_name}'"),
            ))
        }
    };
    let offered = cx.declared(sp)?;
    let key = PipelineKey {
        shader: "shadow/shadow_ray_cast.wgsl".into(),
        // The pixels' surfaces come from the job buffer, whatever source the jobs read.
        defines: defines(&[
            (
                "JOB_CAPACITY",
                format!("{}u", capacity.min(u32::MAX as u64)),
            ),
            ("SHADOW_NORMAL_OFFSET", format!("{:?}", p.normal_offset)),
        ]),
        virtual_code: BTreeMap::new(),
        state: String::new(),
    };
    let (pipeline, bind) = cx.compute_pipeline(&sp.name, key, "main", &offered)?;
    Ok(ShadowRayCastPass {
        name: sp.name.clone(),
        pipeline,
        bind,
        jobs,
    })
}

impl PreparedPass for ShadowRayCastPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&self.name),
            timestamp_writes: ts.compute(),
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind, &[]);
        pass.dispatch_workgroups_indirect(&self.jobs, DISPATCH_OFFSET);
    }
}
