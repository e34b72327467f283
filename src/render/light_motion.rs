//! Scene-file light motion evaluated on the GPU, a frame step recorded before the graph's
//! passes (`PreparedFrame::set_light_motion`): every light's motion parameters and its
//! place at time 0 are uploaded once; each frame the CPU takes each motion's phase at the
//! new time (one orbit rotation, path segment and flicker cell per motion, in f64) and
//! writes those few bytes, and one dispatch of `shaders/scene/light_motion.wgsl` writes
//! the moved lights over the light buffers that culling and shading read.
//!
//! The CPU still evaluates, with the same code (`Motion::apply_phase`), the moving lights
//! whose places it needs: shadow casters (the shadow atlas allocates tiles and views for
//! them) and indirect lights (reflective shadow maps and VPL spawning lay out views for
//! them). A frame whose moving lights are neither costs the CPU only the phases.

use super::scene_gpu::SceneGpu;
use super::{RenderError, Renderer};
use crate::scene::motion::{LightMotion, MotionPhase};
use crate::scene::{light_flags, Light};
use bytemuck::{Pod, Zeroable};

/// The step's name in pass times and errors.
pub(crate) const STEP: &str = "light_motion";
const SHADER: &str = "shaders/scene/light_motion.wgsl";
/// The shader's workgroup size.
const WORKGROUP: u32 = 64;
/// `motion_of_light` for a light that stands still.
const NO_MOTION: u32 = u32::MAX;

/// Flag bits of [`GpuMotion::flags`] (the shader's constants of the same names).
const ORBIT: u32 = 1;
const PATH: u32 = 2;
const FLICKER: u32 = 4;
const CATMULL_ROM: u32 = 8;

/// One motion's parameters (`Motion` in the shader), uploaded once.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuMotion {
    centre: [f32; 3],
    flags: u32,
    first_light: u32,
    first_point: u32,
    points: u32,
    amplitude: f32,
    seed: [u32; 2],
    _pad: [u32; 2],
}

/// One motion at a frame's time (`Phase` in the shader), written every frame.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuPhase {
    turn: [f32; 4],
    segment: u32,
    along: f32,
    blend: f32,
    _pad0: u32,
    cell: [u32; 2],
    _pad1: [u32; 2],
}

impl From<&MotionPhase> for GpuPhase {
    fn from(p: &MotionPhase) -> Self {
        let cell = p.cell as u64;
        Self {
            turn: p.turn.to_array(),
            segment: p.segment,
            along: p.along,
            blend: p.blend,
            _pad0: 0,
            cell: [cell as u32, (cell >> 32) as u32],
            _pad1: [0; 2],
        }
    }
}

/// A light whose place the CPU needs, and the motion that moves it.
#[derive(Clone, Copy)]
struct Followed {
    light: u32,
    motion: u32,
}

/// The uploaded motion of one scene's lights and the dispatch that applies it.
pub(crate) struct LightMotionStep {
    motions: Vec<LightMotion>,
    /// The lights as placed (time 0).
    placed: Vec<Light>,
    /// The moving lights the CPU evaluates too.
    followed: Vec<Followed>,
    /// `placed` with the followed lights moved to the last time: what passes that keep
    /// per-light CPU state follow.
    lights: Vec<Light>,
    /// Each motion's phase at the last time, reused every frame.
    phases: Vec<MotionPhase>,
    gpu_phases: Vec<GpuPhase>,
    phase_buffer: wgpu::Buffer,
    pipeline: wgpu::ComputePipeline,
    bind: wgpu::BindGroup,
    groups: u32,
}

/// Why motion cannot be evaluated on the GPU.
pub(crate) enum StepError {
    /// Two motions' runs share this light.
    Overlap(usize),
    /// The shader or its pipeline failed.
    Render(RenderError),
}

impl LightMotionStep {
    /// Uploads `lights` (as placed) and `motions` for `gpu`'s light buffers. Motions past
    /// the end of `lights` are ignored, as `animate_into` ignores them.
    pub fn new(
        r: &Renderer,
        gpu: &SceneGpu,
        lights: &[Light],
        motions: &[LightMotion],
    ) -> Result<Self, StepError> {
        let device = &r.ctx.device;
        let mut motion_of_light = vec![NO_MOTION; lights.len()];
        let mut params = Vec::with_capacity(motions.len());
        let mut points: Vec<[f32; 4]> = Vec::new();
        let mut followed = Vec::new();
        for (m, lm) in motions.iter().enumerate() {
            let first = (lm.first as usize).min(lights.len());
            let end = first.saturating_add(lm.count as usize).min(lights.len());
            for (i, slot) in motion_of_light[first..end].iter_mut().enumerate() {
                if *slot != NO_MOTION {
                    return Err(StepError::Overlap(first + i));
                }
                *slot = m as u32;
                let light = first + i;
                let flags = lights[light].flags;
                if flags & (light_flags::CASTS_SHADOW | light_flags::INDIRECT) != 0 {
                    followed.push(Followed {
                        light: light as u32,
                        motion: m as u32,
                    });
                }
            }
            params.push(gpu_motion(lm, first as u32, &mut points));
        }
        let storage = |label: &str, bytes: &[u8], extra: wgpu::BufferUsages| {
            super::scene_gpu::storage_buffer(device, label, bytes, extra)
        };
        let none = wgpu::BufferUsages::empty();
        let motion_of_light = storage(
            "motion of light",
            bytemuck::cast_slice(&motion_of_light),
            none,
        );
        let [placed_geometry, placed_properties] = super::scene_gpu::light_storage(
            device,
            ["placed geometry", "placed properties"],
            lights,
            0,
            none,
        );
        let params = storage("motions", bytemuck::cast_slice(&params), none);
        let points = storage("path points", bytemuck::cast_slice(&points), none);
        let gpu_phases = vec![GpuPhase::zeroed(); motions.len()];
        let phase_buffer = storage(
            "motion phases",
            bytemuck::cast_slice(&gpu_phases),
            wgpu::BufferUsages::COPY_DST,
        );
        let pipeline = pipeline(r).map_err(StepError::Render)?;
        let buffers = [
            &motion_of_light,
            &placed_geometry,
            &placed_properties,
            &params,
            &phase_buffer,
            &points,
            &gpu.light_geometry,
            &gpu.light_properties,
        ];
        let entries: Vec<wgpu::BindGroupEntry> = buffers
            .iter()
            .enumerate()
            .map(|(binding, b)| wgpu::BindGroupEntry {
                binding: binding as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(STEP),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        let groups = (lights.len() as u32).div_ceil(WORKGROUP);
        let most = device.limits().max_compute_workgroups_per_dimension;
        if groups > most {
            return Err(StepError::Render(RenderError::Pass {
                pass: STEP.into(),
                message: format!(
                    "{} lights need {groups} workgroups of {WORKGROUP}, over the device's {most}",
                    lights.len()
                ),
            }));
        }
        Ok(Self {
            motions: motions.to_vec(),
            placed: lights.to_vec(),
            followed,
            lights: lights.to_vec(),
            phases: vec![MotionPhase::default(); motions.len()],
            gpu_phases,
            phase_buffer,
            pipeline,
            bind,
            groups,
        })
    }

    /// Takes every motion's phase at `t` and writes them (one small queue write) for the
    /// next recorded dispatch; moves the followed lights on the CPU. Returns the lights
    /// for passes to follow when any followed light moves, else `None`.
    pub fn move_to(&mut self, queue: &wgpu::Queue, t: f64) -> Option<&[Light]> {
        for ((m, phase), gpu) in self
            .motions
            .iter()
            .zip(&mut self.phases)
            .zip(&mut self.gpu_phases)
        {
            *phase = m.motion.phase(t);
            *gpu = GpuPhase::from(&*phase);
        }
        if !self.gpu_phases.is_empty() {
            queue.write_buffer(
                &self.phase_buffer,
                0,
                bytemuck::cast_slice(&self.gpu_phases),
            );
        }
        if self.followed.is_empty() {
            return None;
        }
        for f in &self.followed {
            let m = &self.motions[f.motion as usize];
            let light = f.light as usize;
            self.lights[light] = m.motion.apply_phase(
                &self.placed[light],
                f.light - m.first,
                &self.phases[f.motion as usize],
            );
        }
        Some(&self.lights)
    }

    /// Records the dispatch that writes every light at the last time.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: super::passes::Timestamps<'_>) {
        if self.groups == 0 {
            return;
        }
        super::passes::dispatch(
            encoder,
            STEP,
            ts,
            &self.pipeline,
            &self.bind,
            [self.groups, 1, 1],
        );
    }
}

/// One motion's parameters; a path's points are appended to `points`.
fn gpu_motion(lm: &LightMotion, first_light: u32, points: &mut Vec<[f32; 4]>) -> GpuMotion {
    let m = &lm.motion;
    let mut g = GpuMotion::zeroed();
    g.first_light = first_light;
    if let Some(o) = &m.orbit {
        g.flags |= ORBIT;
        g.centre = o.centre.to_array();
    }
    if let Some(p) = &m.path {
        g.flags |= PATH;
        if p.is_catmull_rom() {
            g.flags |= CATMULL_ROM;
        }
        g.first_point = points.len() as u32;
        g.points = p.points().len() as u32;
        points.extend(p.points().iter().map(|v| v.extend(0.0).to_array()));
    }
    if let Some(f) = &m.flicker {
        g.flags |= FLICKER;
        g.amplitude = f.amplitude;
        g.seed = [f.seed as u32, (f.seed >> 32) as u32];
    }
    g
}

/// The step's compute pipeline, its bind group layout derived from the shader.
fn pipeline(r: &Renderer) -> Result<wgpu::ComputePipeline, RenderError> {
    let shader_error = |source| RenderError::Shader {
        pass: STEP.into(),
        source,
    };
    let rel = SHADER.trim_start_matches("shaders/");
    let composed = r
        .shaders
        .compose(rel, &Default::default(), &Default::default())
        .map_err(shader_error)?;
    composed.validate().map_err(shader_error)?;
    let device = &r.ctx.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(SHADER),
        source: wgpu::ShaderSource::Wgsl(composed.text.into()),
    });
    Ok(
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(STEP),
            layout: None,
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            // The driver's cache on disk, as every pipeline the renderer builds.
            cache: r.ctx.pipeline_cache.as_deref().map(|c| c.cache()),
        }),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_structs_match_the_shaders_layout() {
        // Offsets as WGSL lays the shader's structs out (vec2<u32> aligned to 8).
        assert_eq!(std::mem::size_of::<GpuMotion>(), 48);
        assert_eq!(std::mem::offset_of!(GpuMotion, seed), 32);
        assert_eq!(std::mem::size_of::<GpuPhase>(), 48);
        assert_eq!(std::mem::offset_of!(GpuPhase, cell), 32);
    }
}
