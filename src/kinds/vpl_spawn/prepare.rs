//! `VplSpawn`: four dispatches in one compute pass (copy the scene's lights, gather one
//! candidate per block of each map view, select against the room, append), then the
//! light counter is copied into the frame uniform's `light_count`, so every later pass
//! of the frame loops over and culls the VPLs with no CPU round trip. Reports what it
//! made, kept and dropped (read after the frame). A light update lays the map views out
//! again on the CPU (as the maps' pass does) and writes the spawn parameters and the
//! dispatch sizes: the VPLs of the next frame come from the moved lights.

use super::reflective_shadow_maps::{rsm_layout_rules, RsmLayoutRules};
use super::{pass_error, PrepareCtx, PreparedPass, Timestamps};
use crate::gpu::readback::read_buffer;
use crate::graph::kinds::reflective_shadow_maps::{RSM_FLUX, RSM_VIEWS};
use crate::graph::Name;
use crate::graph::{slot, PassKind, ScheduledPass, VplFalloff, VplSpawn};
use crate::indirect::rsm_views::RsmLayout;
use crate::render::pipelines::PipelineKey;
use crate::render::report::{PassReport, VplReport};
use crate::render::{RenderError, Renderer};
use crate::scene::Light;
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use wgpu::util::DeviceExt;

/// Bytes of one candidate (`Candidate` in vpl_spawn.wgsl).
const CANDIDATE_BYTES: u64 = 64;
/// Words of the control buffer (`control` in vpl_spawn.wgsl).
const CONTROL_WORDS: u64 = 12;
/// The dispatches, in order: copy, gather, merge, select, append.
const DISPATCHES: usize = 5;

pub(super) struct VplSpawnPass {
    name: Name,
    pipelines: [Arc<wgpu::ComputePipeline>; DISPATCHES],
    bind: wgpu::BindGroup,
    /// The maps' layout rules, to lay their views out again for new lights.
    rules: RsmLayoutRules,
    /// VPL candidates the candidate buffer holds room for (the prepared layout's).
    candidate_room: u32,
    spawn: VplSpawn,
    params: wgpu::Buffer,
    groups: Mutex<[[u32; 3]; DISPATCHES]>,
    control: wgpu::Buffer,
    frame_uniform: wgpu::Buffer,
    report: Mutex<VplReport>,
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
    let (w, h, layout) = super::reflective_shadow_maps::rsm_layout(cx, &sp.name, &rsm.0, &rsm.1)?;
    let rules = rsm_layout_rules(cx, &rsm.0, w, h);
    let scene_lights = cx.light_count.get();
    // Room for every light an update may write, then the VPLs.
    let most_lights = cx.gpu.light_capacity;
    let need = (most_lights as u64 + p.max_vpls as u64) * crate::gpu::structs::LIGHT_BYTES;
    for s in [slot::LIGHT_GEOMETRY, slot::LIGHT_PROPERTIES] {
        let b = cx.buffer(&sp.name, sp.required(s))?;
        if b.size() < need {
            return Err(pass_error(
                &sp.name,
                format!(
                    "buffer '{}' holds {} bytes; {most_lights} scene lights and room for {} VPLs need {need} (size: Auto)",
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
    let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("vpl spawn params"),
        contents: bytemuck::cast_slice(&spawn_params(scene_lights, &layout, p)),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
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
    let (merge, _) = build("merge")?;
    let (select, _) = build("select_room")?;
    let (append, _) = build("append")?;
    Ok(VplSpawnPass {
        name: sp.name.clone(),
        pipelines: [copy, gather, merge, select, append],
        bind,
        rules,
        candidate_room: layout.candidates,
        spawn: *p,
        params,
        groups: Mutex::new(dispatch_groups(scene_lights, &layout, p.merge)),
        control,
        frame_uniform: cx.frame_uniform.clone(),
        report: Mutex::new(layout_report(&sp.name, scene_lights, &layout, p)),
    })
}

/// `SpawnParams` of vpl_spawn.wgsl.
fn spawn_params(scene_lights: u32, layout: &RsmLayout, p: &VplSpawn) -> [u32; 8] {
    let falloff = match p.falloff {
        VplFalloff::Clamp => 0,
        VplFalloff::Disc => 2,
        VplFalloff::AreaClamp => 4,
    };
    let flags = u32::from(p.redistribute) | falloff;
    [
        scene_lights,
        layout.views.len() as u32,
        layout.candidates,
        p.max_vpls,
        p.merge,
        p.merge_cos.to_bits(),
        p.min_flux.to_bits(),
        flags,
    ]
}

/// The dispatches' sizes: copy the scene's lights, gather each view's blocks, merge
/// each view's groups (none when `merge` is 1), select, append every candidate.
fn dispatch_groups(scene_lights: u32, layout: &RsmLayout, merge: u32) -> [[u32; 3]; DISPATCHES] {
    let most_blocks = layout
        .views
        .iter()
        .map(|v| v.controls.n * v.controls.n)
        .max()
        .unwrap_or(0);
    let most_groups = layout
        .views
        .iter()
        .map(|v| (v.controls.n / merge.min(v.controls.n)).pow(2))
        .max()
        .unwrap_or(0);
    let merge_groups = if merge > 1 {
        most_groups.div_ceil(64)
    } else {
        0
    };
    [
        [scene_lights.div_ceil(64), 1, 1],
        [most_blocks.div_ceil(64), layout.views.len() as u32, 1],
        [merge_groups, layout.views.len() as u32, 1],
        [1, 1, 1],
        [layout.candidates.div_ceil(64), 1, 1],
    ]
}

/// What the layout says before the GPU counts anything.
fn layout_report(pass: &str, scene_lights: u32, layout: &RsmLayout, p: &VplSpawn) -> VplReport {
    VplReport {
        pass: pass.to_string(),
        lights: layout.lights,
        views: layout.views.len() as u32,
        dropped_lights: layout.dropped.clone(),
        candidates: layout.candidates,
        with_flux: 0,
        spawned: 0,
        dropped: 0,
        merged: 0,
        negligible: 0,
        negligible_flux: 0.0,
        total_flux: 0.0,
        min_flux: p.min_flux,
        redistributed: p.redistribute,
        room: p.max_vpls,
        scene_lights,
    }
}

/// Where the frame uniform keeps the light count.
const LIGHT_COUNT_OFFSET: u64 =
    std::mem::offset_of!(crate::gpu::structs::GpuFrame, light_count) as u64;

impl PreparedPass for VplSpawnPass {
    fn can_follow_lights(&self, lights: &[Light]) -> Result<(), String> {
        let candidates = self.rules.layout(lights).candidates;
        if candidates > self.candidate_room {
            return Err(format!(
                "the lights' map views make {candidates} VPL candidates; the candidate buffer was prepared for {}: prepare the frame again for more or larger indirect lights",
                self.candidate_room
            ));
        }
        Ok(())
    }

    fn follow_lights(&self, r: &Renderer, lights: &[Light]) {
        let layout = self.rules.layout(lights);
        let scene_lights = lights.len() as u32;
        r.ctx.queue.write_buffer(
            &self.params,
            0,
            bytemuck::cast_slice(&spawn_params(scene_lights, &layout, &self.spawn)),
        );
        *self.groups.lock().unwrap_or_else(|e| e.into_inner()) =
            dispatch_groups(scene_lights, &layout, self.spawn.merge);
        *self.report.lock().unwrap_or_else(|e| e.into_inner()) =
            layout_report(&self.name, scene_lights, &layout, &self.spawn);
    }

    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&self.name),
                timestamp_writes: ts.compute(),
            });
            pass.set_bind_group(0, &self.bind, &[]);
            let groups = *self.groups.lock().unwrap_or_else(|e| e.into_inner());
            for (pipeline, [x, y, z]) in self.pipelines.iter().zip(groups) {
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
        let mut report = self
            .report
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone();
        report.spawned = w[0].saturating_sub(report.scene_lights);
        report.dropped = w[1];
        report.with_flux = w[5];
        report.negligible = w[7];
        report.negligible_flux = f32::from_bits(w[8]);
        report.total_flux = f32::from_bits(w[9]);
        report.merged = w[11];
        Ok(Some(PassReport::Vpl(report)))
    }
}
