//! `VplSpawn`: four dispatches in one compute pass (copy the scene's lights, gather one
//! candidate per block of each map view, select against the room, append), then the
//! light counter is copied into the frame uniform's `light_count`, so every later pass
//! of the frame loops over and culls the VPLs with no CPU round trip. Reports what it
//! made, kept and dropped (read after the frame).

use super::{pass_error, PrepareCtx, PreparedPass, Timestamps};
use crate::gpu::readback::read_buffer;
use crate::graph::kinds::reflective_shadow_maps::{RSM_FLUX, RSM_VIEWS};
use crate::graph::Name;
use crate::graph::{slot, PassKind, ScheduledPass, VplSpawn};
use crate::render::pipelines::PipelineKey;
use crate::render::report::{PassReport, VplReport};
use crate::render::{RenderError, Renderer};
use std::collections::BTreeMap;
use std::sync::Arc;
use wgpu::util::DeviceExt;

/// Bytes of one candidate (`Candidate` in vpl_spawn.wgsl).
const CANDIDATE_BYTES: u64 = 48;
/// Words of the control buffer (`control` in vpl_spawn.wgsl).
const CONTROL_WORDS: u64 = 8;

pub(super) struct VplSpawnPass {
    name: Name,
    pipelines: [Arc<wgpu::ComputePipeline>; 4],
    bind: wgpu::BindGroup,
    groups: [[u32; 3]; 4],
    control: wgpu::Buffer,
    frame_uniform: wgpu::Buffer,
    report: VplReport,
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    p: &VplSpawn,
) -> Result<VplSpawnPass, RenderError> {
    let views_name = sp.required(RSM_VIEWS);
    // The maps' pass: the scheduled ReflectiveShadowMaps pass writing this view table.
    let rsm = cx
        .graph
        .passes
        .iter()
        .filter(|q| q.roles.slot(RSM_VIEWS) == Some(views_name))
        .find_map(|q| {
            let PassKind::ReflectiveShadowMaps(r) = &q.kind else {
                return None;
            };
            Some((*r, q.required(RSM_FLUX).to_string()))
        })
        .ok_or_else(|| {
            pass_error(
                &sp.name,
                format!("no ReflectiveShadowMaps pass runs that writes '{views_name}'"),
            )
        })?;
    let (_, _, layout) = super::reflective_shadow_maps::rsm_layout(cx, &sp.name, &rsm.0, &rsm.1)?;
    let scene_lights = cx.gpu.light_count;
    let need = (scene_lights as u64 + p.max_vpls as u64) * 32;
    for s in [slot::LIGHT_GEOMETRY, slot::LIGHT_PROPERTIES] {
        let b = cx.buffer(&sp.name, sp.required(s))?;
        if b.size() < need {
            return Err(pass_error(
                &sp.name,
                format!(
                    "buffer '{}' holds {} bytes; {scene_lights} scene lights and room for {} VPLs need {need} (size: Auto)",
                    sp.required(s),
                    b.size(),
                    p.max_vpls
                ),
            ));
        }
    }
    let device = cx.device();
    let candidates = crate::render::device_limits::create_internal_buffer(
        &device,
        &sp.name,
        &wgpu::BufferDescriptor {
            label: Some("vpl candidates"),
            size: CANDIDATE_BYTES * layout.candidates.max(1) as u64,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        },
    )?;
    let control = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("vpl control"),
        size: 4 * CONTROL_WORDS,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let views = layout.views.len() as u32;
    let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("vpl spawn params"),
        contents: bytemuck::cast_slice(&[scene_lights, views, layout.candidates, p.max_vpls]),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let mut offered = cx.declared(sp)?;
    offered.buffer("params", &params);
    offered.buffer("candidates", &candidates);
    offered.buffer("control", &control);
    let key = |entry: &str| PipelineKey {
        shader: "indirect/vpl_spawn.wgsl".into(),
        defines: BTreeMap::new(),
        virtual_code: BTreeMap::new(),
        state: entry.to_string(),
    };
    let mut build = |entry: &str| -> Result<_, RenderError> {
        cx.compute_pipeline(&sp.name, key(entry), entry, &offered)
    };
    let (copy, bind) = build("copy")?;
    let (gather, _) = build("gather")?;
    let (select, _) = build("select_room")?;
    let (append, _) = build("append")?;
    let most_blocks = layout
        .views
        .iter()
        .map(|v| v.controls.n * v.controls.n)
        .max()
        .unwrap_or(0);
    let groups = [
        [scene_lights.div_ceil(64), 1, 1],
        [most_blocks.div_ceil(64), views, 1],
        [1, 1, 1],
        [layout.candidates.div_ceil(64), 1, 1],
    ];
    Ok(VplSpawnPass {
        name: sp.name.clone(),
        pipelines: [copy, gather, select, append],
        bind,
        groups,
        control,
        frame_uniform: cx.frame_uniform.clone(),
        report: VplReport {
            pass: sp.name.to_string(),
            lights: layout.lights,
            views,
            dropped_lights: layout.dropped.clone(),
            candidates: layout.candidates,
            with_flux: 0,
            spawned: 0,
            dropped: 0,
            room: p.max_vpls,
            scene_lights,
        },
    })
}

/// Where the frame uniform keeps the light count.
const LIGHT_COUNT_OFFSET: u64 =
    std::mem::offset_of!(crate::gpu::structs::GpuFrame, light_count) as u64;

impl PreparedPass for VplSpawnPass {
    fn can_follow_lights(&self) -> Result<(), String> {
        Err("it appends VPLs after the scene's light count fixed at prepare: prepare the frame again to move or change lights".into())
    }

    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&self.name),
                timestamp_writes: ts.compute(),
            });
            pass.set_bind_group(0, &self.bind, &[]);
            for (pipeline, [x, y, z]) in self.pipelines.iter().zip(self.groups) {
                if x * y * z == 0 {
                    continue;
                }
                pass.set_pipeline(pipeline);
                pass.dispatch_workgroups(x, y, z);
            }
        }
        encoder.copy_buffer_to_buffer(&self.control, 0, &self.frame_uniform, LIGHT_COUNT_OFFSET, 4);
    }

    fn report(&self, r: &Renderer) -> Result<Option<PassReport>, RenderError> {
        let bytes = read_buffer(&r.ctx.device, &r.ctx.queue, &self.control)?;
        let w: &[u32] = bytemuck::cast_slice(&bytes);
        let mut report = self.report.clone();
        report.spawned = w[0].saturating_sub(report.scene_lights);
        report.dropped = w[1];
        report.with_flux = w[5];
        Ok(Some(PassReport::Vpl(report)))
    }
}

impl super::PrepareKind for crate::graph::kinds::vpl_spawn::VplSpawn {
    fn prepare(
        &self,
        cx: &mut PrepareCtx<'_>,
        sp: &ScheduledPass,
    ) -> Result<Box<dyn super::PreparedPass>, RenderError> {
        Ok(Box::new(prepare(cx, sp, self)?))
    }
}
