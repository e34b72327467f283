//! `LightSampling`: the candidates dispatch (exact lights traced, reservoirs filled and,
//! without reuse, their rays traced), the temporal and spatial reuse dispatches when
//! asked, and a one-invocation dispatch that counts frames and keeps the view for the
//! next frame's reprojection; one compute pass.

use super::{defines, PrepareCtx, PreparedPass, Timestamps};
use crate::graph::kinds::light_sampling::{ExactPer, LightSampling};
use crate::graph::Name;
use crate::graph::{slot, ScheduledPass};
use crate::render::pipelines::PipelineKey;
use crate::render::RenderError;
use std::collections::BTreeMap;
use std::sync::Arc;

const SHADER: &str = "lighting/light_sampling.wgsl";

pub(super) struct LightSamplingPass {
    name: Name,
    candidates: Arc<wgpu::ComputePipeline>,
    temporal: Option<Arc<wgpu::ComputePipeline>>,
    spatial: Option<Arc<wgpu::ComputePipeline>>,
    advance: Arc<wgpu::ComputePipeline>,
    bind: wgpu::BindGroup,
    groups: [u32; 3],
}

/// The shader's defines for `p`.
fn sampling_defines(p: &LightSampling) -> Vec<(&'static str, String)> {
    let mut d = vec![
        ("LIGHT_LISTS", "1".into()),
        ("VISIBILITY_IDS", "1".into()),
        ("SHADOW_NORMAL_OFFSET", format!("{:?}", p.normal_offset)),
        ("SAMPLE_EXACT", format!("{}u", p.exact_lights)),
        ("EXACT_ARRAY", format!("{}u", p.exact_lights.max(1))),
        ("SAMPLE_COUNT", format!("{}u", p.samples)),
        ("SAMPLE_CANDIDATES", format!("{}u", p.candidates)),
        ("SAMPLE_SEED", format!("{}u", p.seed)),
    ];
    if p.exact_per == ExactPer::Block && p.exact_lights > 0 {
        d.push(("EXACT_PER_BLOCK", "1".into()));
    }
    let spatial = u32::from(p.reuse.spatial().is_some());
    d.push((
        "SAMPLE_REGIONS",
        format!("{}u", 1 + spatial + 2 * u32::from(p.history > 0)),
    ));
    if spatial == 0 {
        d.push(if p.history > 0 {
            ("TRACE_TEMPORAL", "1".into())
        } else {
            ("TRACE_CANDIDATES", "1".into())
        });
    }
    if p.history > 0 {
        d.push(("SAMPLE_TEMPORAL", "1".into()));
        d.push(("HISTORY_REGION", format!("{}u", 1 + spatial)));
        d.push((
            "HISTORY_CAP",
            format!("{:?}", (p.history * p.candidates) as f32),
        ));
    }
    if let Some((neighbours, radius, unbiased)) = p.reuse.spatial() {
        d.push(("SAMPLE_SPATIAL", "1".into()));
        d.push(("SPATIAL_NEIGHBOURS", format!("{neighbours}u")));
        d.push(("SPATIAL_RADIUS", format!("{radius}u")));
        if unbiased {
            d.push(("SPATIAL_UNBIASED", "1".into()));
        }
    }
    d
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    p: &LightSampling,
) -> Result<LightSamplingPass, RenderError> {
    let mut offered = cx.declared(sp)?;
    let params = cx.list_params(&sp.name, sp.required(slot::LIGHT_LISTS))?;
    offered.buffer("list_params", &params);
    let d = sampling_defines(p);
    let key = |entry: &str| PipelineKey {
        shader: SHADER.into(),
        defines: defines(&d),
        virtual_code: BTreeMap::new(),
        state: entry.to_string(),
    };
    let (candidates, bind) =
        cx.compute_pipeline(&sp.name, key("candidates"), "candidates", &offered)?;
    let spatial = match p.reuse.spatial() {
        Some(_) => Some(
            cx.compute_pipeline(&sp.name, key("spatial"), "spatial", &offered)?
                .0,
        ),
        None => None,
    };
    let temporal = match p.history {
        0 => None,
        _ => Some(
            cx.compute_pipeline(&sp.name, key("temporal"), "temporal", &offered)?
                .0,
        ),
    };
    let (advance, _) = cx.compute_pipeline(&sp.name, key("advance"), "advance", &offered)?;
    Ok(LightSamplingPass {
        name: sp.name.clone(),
        candidates,
        temporal,
        spatial,
        advance,
        bind,
        groups: [cx.size.width.div_ceil(8), cx.size.height.div_ceil(8), 1],
    })
}

impl PreparedPass for LightSamplingPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&self.name),
            timestamp_writes: ts.compute(),
        });
        pass.set_bind_group(0, &self.bind, &[]);
        let [x, y, z] = self.groups;
        pass.set_pipeline(&self.candidates);
        pass.dispatch_workgroups(x, y, z);
        if let Some(temporal) = &self.temporal {
            pass.set_pipeline(temporal);
            pass.dispatch_workgroups(x, y, z);
        }
        if let Some(spatial) = &self.spatial {
            pass.set_pipeline(spatial);
            pass.dispatch_workgroups(x, y, z);
        }
        pass.set_pipeline(&self.advance);
        pass.dispatch_workgroups(1, 1, 1);
    }
}
