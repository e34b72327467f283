//! A compiled graph made ready for one scene and output size, executed as often as
//! needed (benchmarks run it many times), with readback of the output and statistics.
//! The loops live here: prepare every pass, record every pass between timestamps, read
//! back. What each pass does lives in its kind's folder (`src/kinds/<kind>/prepare.rs`).

mod light_update;
mod mesh_edit;
mod parallel_builds;
mod readback;

pub(crate) use light_update::LightCount;
pub use light_update::LightUpdateError;
pub use mesh_edit::MeshEditError;

use parallel_builds::prebuild_in_parallel;

use super::light_stats::LightStatsPass;
use super::passes::{self, PrepareCtx, PreparedPass, Timestamps};
use super::prepare_stats::PrepareStats;
use super::report::{FrameResult, PassReport};
use super::resources::FrameResources;
use super::scene_gpu::SceneGpu;
use super::{RenderError, Renderer};
use crate::gpu::readback::{read_buffer, read_rgba32f};
use crate::gpu::structs::GpuFrame;
use crate::graph::Name;
use crate::graph::{CompiledGraph, FrameSize};
use crate::scene::{Camera, Scene};
use glam::Vec3;
use std::time::{Duration, Instant};
use wgpu::util::DeviceExt;

/// GPU milliseconds per pass, where the adapter has timestamps.
pub type PassTimes = Option<Vec<(String, f64)>>;

/// Where the time of one executed (and read back) frame went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderTimings {
    /// Encoding every pass and `queue.submit`.
    pub record_submit: Duration,
    /// From the submit returning to the GPU having finished the frame (a blocking poll):
    /// the GPU's work plus whatever the driver does on the queue (first-use compiles).
    pub gpu_wait: Duration,
    /// When the frame's GPU work was done: what a viewer could present from then on.
    pub gpu_done: Instant,
    /// The GPU's own time, the sum of the passes' timestamps (where the adapter has them).
    pub gpu_frame_ms: Option<f64>,
    /// Reading the timestamps back.
    pub timestamps_read: Duration,
    /// Copying the output image to a staging buffer, mapping it and converting it.
    pub image_readback: Duration,
    /// Reading back what passes counted (culling reports) and light statistics.
    pub reports_readback: Duration,
}

impl Default for RenderTimings {
    fn default() -> Self {
        Self {
            record_submit: Duration::ZERO,
            gpu_wait: Duration::ZERO,
            gpu_done: Instant::now(),
            gpu_frame_ms: None,
            timestamps_read: Duration::ZERO,
            image_readback: Duration::ZERO,
            reports_readback: Duration::ZERO,
        }
    }
}

/// A pass's error, named with the graph file:line that declares the pass.
fn at_pass(graph: &CompiledGraph, sp: &crate::graph::ScheduledPass, e: RenderError) -> RenderError {
    let problem = match e {
        RenderError::Pass { message, .. } => message,
        RenderError::Shader { source, .. } => source.to_string(),
        e => return e,
    };
    RenderError::AtPass {
        at: graph.checked.source.of_declaration(&sp.name),
        pass: sp.name.to_string(),
        problem,
    }
}

/// A compiled graph prepared on the GPU: its resources, pipelines and bind groups, ready to
/// render or record as often as wanted.
pub struct PreparedFrame {
    /// The compiled graph it was prepared from.
    pub graph: CompiledGraph,
    /// The frame size it was prepared for.
    pub size: FrameSize,
    resources: FrameResources,
    frame_uniform: wgpu::Buffer,
    passes: Vec<(Name, Box<dyn PreparedPass>)>,
    absent: Vec<Name>,
    queries: Option<(wgpu::QuerySet, wgpu::Buffer)>,
    stats: Option<LightStatsPass>,
    prepare_stats: PrepareStats,
    /// The light count every pass reads (the frame uniform's): the upload's, then what
    /// the last [`update_lights`](Self::update_lights) wrote.
    light_count: LightCount,
    /// Room in the scene's light buffers.
    light_capacity: u32,
    /// The light features the graph was compiled and its pipelines specialised for.
    light_features: crate::scene::SceneFeatures,
    /// Scene-file light motion evaluated on the GPU before the passes, when set
    /// ([`set_light_motion`](Self::set_light_motion)).
    motion: std::sync::Mutex<Option<super::light_motion::LightMotionStep>>,
}

impl Renderer {
    /// Makes a compiled graph ready to run on `scene` at `size`: resources, pipelines
    /// (through the cache) and bind groups. `light_stats` adds the statistics pass.
    pub fn prepare(
        &mut self,
        graph: CompiledGraph,
        scene: &Scene,
        gpu: &SceneGpu,
        size: FrameSize,
        light_stats: bool,
    ) -> Result<PreparedFrame, RenderError> {
        self.prepare_reusing(graph, scene, gpu, size, light_stats, None)
    }

    /// Like [`prepare`](Self::prepare) for a frame that replaces `previous` (hot reload,
    /// switching graphs): physical textures and buffers whose descriptor and usage did
    /// not change are taken from it instead of created. `previous` stays usable (the
    /// handles are shared), so it can keep running if this frame is never used.
    pub fn prepare_reusing(
        &mut self,
        graph: CompiledGraph,
        scene: &Scene,
        gpu: &SceneGpu,
        size: FrameSize,
        light_stats: bool,
        previous: Option<&PreparedFrame>,
    ) -> Result<PreparedFrame, RenderError> {
        // wgpu reports validation errors (a list buffer over the binding limit, say) as
        // errors here instead of panicking.
        let scope = self
            .ctx
            .device
            .push_error_scope(wgpu::ErrorFilter::Validation);
        let generation = self.pipelines.next_generation();
        let before = self.pipelines.counters();
        self.pipelines.take_built();
        self.pipelines.take_builds();
        let pool = previous.map(|p| &p.resources);
        let file = graph.checked.source.file.clone();
        let result = self.prepare_unscoped(graph, scene, gpu, size, light_stats, pool);
        self.pipelines.settle_prebuilt();
        let build_threads = std::mem::take(&mut self.pipelines.build_threads);
        let build_wall = self.pipelines.take_build_wall();
        let built = self
            .pipelines
            .take_built()
            .iter()
            .map(|k| k.describe())
            .collect();
        let stats = PrepareStats::from_cache(
            self.pipelines.counters() - before,
            built,
            self.pipelines.take_builds(),
            self.pipelines.gpu_state_at_build(),
            generation,
        );
        match pollster::block_on(scope.pop()) {
            Some(e) => Err(RenderError::Wgpu(format!("{}: {e}", file.display()))),
            None => result.map(|mut frame| {
                frame.prepare_stats = PrepareStats {
                    build_wall,
                    build_threads,
                    resources_created: frame.resources.created(),
                    resources_reused: frame.resources.reused(),
                    ..stats
                };
                frame
            }),
        }
    }

    fn prepare_unscoped(
        &mut self,
        graph: CompiledGraph,
        scene: &Scene,
        gpu: &SceneGpu,
        size: FrameSize,
        light_stats: bool,
        pool: Option<&FrameResources>,
    ) -> Result<PreparedFrame, RenderError> {
        let device = self.ctx.device.clone();
        check_output_written(&graph)?;
        if size.lights < gpu.light_capacity {
            return Err(RenderError::LightCapacity {
                compiled: size.lights,
                capacity: gpu.light_capacity,
            });
        }
        super::device_limits::check_plan(&graph, &device.limits())?;
        super::device_limits::check_samples(&graph, &self.ctx.adapter, &device)?;
        let resources = FrameResources::create_reusing(&device, &graph.plan, pool);
        let gpu_frame = GpuFrame::new(
            &scene.camera,
            scene.ambient,
            size.width,
            size.height,
            scene.lights.len() as u32,
            crate::gpu::structs::caster_end(&scene.lights),
        );
        let light_count = LightCount::new(gpu_frame.light_count, gpu_frame.caster_end);
        let frame_uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("frame"),
            contents: bytemuck::bytes_of(&gpu_frame),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let mut cx = PrepareCtx {
            renderer: self,
            graph: &graph,
            gpu,
            resources: &resources,
            frame_uniform: &frame_uniform,
            size,
            scene,
            light_count: &light_count,
        };
        prebuild_in_parallel(&mut cx);
        let mut prepared = Vec::with_capacity(graph.passes.len());
        for sp in &graph.passes {
            cx.renderer.pipelines.set_pass(&sp.name);
            let pass = passes::prepare(&mut cx, sp).map_err(|e| at_pass(&graph, sp, e))?;
            prepared.push((sp.name.clone(), pass));
        }
        let absent = graph
            .plan
            .resources
            .iter()
            .filter(|r| r.absent)
            .map(|r| r.name.clone())
            .collect();
        let queries = self.ctx.has_timestamps.then(|| {
            // A pair per pass, and one for the light-motion step (`set_light_motion`).
            let count = 2 * (prepared.len() as u32 + 1);
            (
                device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("pass timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count,
                }),
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamps"),
                    size: 8 * count as u64,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }),
            )
        });
        let stats = if light_stats {
            self.pipelines.set_pass("light statistics");
            Some(LightStatsPass::prepare(
                self,
                &graph,
                &resources,
                &frame_uniform,
                gpu,
                &gpu_frame,
                size,
            )?)
        } else {
            None
        };
        Ok(PreparedFrame {
            graph,
            size,
            resources,
            frame_uniform,
            passes: prepared,
            absent,
            queries,
            stats,
            prepare_stats: PrepareStats::default(),
            light_count,
            light_capacity: gpu.light_capacity,
            light_features: scene.features(),
            motion: Default::default(),
        })
    }
}

impl PreparedFrame {
    /// What preparing this frame built, reused and created.
    pub fn stats(&self) -> &PrepareStats {
        &self.prepare_stats
    }

    /// Records and submits one frame; returns GPU milliseconds per pass when the
    /// adapter has timestamps.
    pub fn execute(&self, r: &Renderer) -> Result<Option<Vec<(String, f64)>>, RenderError> {
        self.execute_timed(r).map(|(ms, _)| ms)
    }

    /// Like [`execute`](Self::execute), also saying where the time went.
    pub fn execute_timed(&self, r: &Renderer) -> Result<(PassTimes, RenderTimings), RenderError> {
        let scope = r.ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let result = self.execute_unscoped(r);
        match pollster::block_on(scope.pop()) {
            Some(e) => Err(RenderError::Wgpu(e.to_string())),
            None => result,
        }
    }

    /// Records and submits one frame without waiting for it (a viewer's frame in flight).
    pub fn submit(&self, r: &Renderer) -> Result<(), RenderError> {
        let scope = r.ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
        r.ctx.queue.submit([self.encode(r)]);
        match pollster::block_on(scope.pop()) {
            Some(e) => Err(RenderError::Wgpu(e.to_string())),
            None => Ok(()),
        }
    }

    fn encode(&self, r: &Renderer) -> wgpu::CommandBuffer {
        let mut encoder = r.ctx.device.create_command_encoder(&Default::default());
        self.record(&mut encoder);
        encoder.finish()
    }

    /// Records one frame into the caller's encoder (an engine's frame with its own passes
    /// before and after): the caller submits. The graph's output is then
    /// [`output_texture`](Self::output_texture), or draw it into any colour target with a
    /// [`Presenter`](crate::render::Presenter) on the same encoder. Per-pass timestamps are
    /// recorded but only [`execute`](Self::execute) reads them back.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder) {
        let plan = &self.graph.plan;
        // Resources whose writers were culled read as zero.
        for name in &self.absent {
            if let Some(b) = self.resources.buffer(plan, name) {
                encoder.clear_buffer(b, 0, None);
            } else if let Some(t) = self.resources.texture(plan, name) {
                match self.resources.view(plan, name) {
                    // clear_texture needs a feature for depth formats; a render pass's
                    // clear does not.
                    Some(view) if t.format().is_depth_stencil_format() => {
                        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                            label: Some(name),
                            color_attachments: &[],
                            depth_stencil_attachment: Some(
                                wgpu::RenderPassDepthStencilAttachment {
                                    view,
                                    depth_ops: Some(wgpu::Operations {
                                        load: wgpu::LoadOp::Clear(0.0),
                                        store: wgpu::StoreOp::Store,
                                    }),
                                    stencil_ops: None,
                                },
                            ),
                            timestamp_writes: None,
                            occlusion_query_set: None,
                            multiview_mask: None,
                        });
                    }
                    _ => encoder.clear_texture(t, &Default::default()),
                }
            }
        }
        // Moving lights first: every pass reads the light buffers it writes. Timed in the
        // query pair after the passes'.
        let moving = self.motion.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(step) = moving.as_ref() {
            let n = self.passes.len() as u32;
            step.record(
                encoder,
                Timestamps(self.queries.as_ref().map(|(q, _)| (q, n))),
            );
        }
        let timed = self.passes.len() as u32 + moving.is_some() as u32;
        drop(moving);
        for (i, (_, pass)) in self.passes.iter().enumerate() {
            let ts = Timestamps(self.queries.as_ref().map(|(q, _)| (q, i as u32)));
            pass.record(encoder, ts);
            if let Some(stats) = self.stats.as_ref().filter(|s| s.after == i) {
                stats.record(encoder);
            }
        }
        if let Some((q, buf)) = &self.queries {
            encoder.resolve_query_set(q, 0..2 * timed, buf, 0);
        }
    }

    fn execute_unscoped(&self, r: &Renderer) -> Result<(PassTimes, RenderTimings), RenderError> {
        let device = &r.ctx.device;
        let start = Instant::now();
        r.ctx.queue.submit([self.encode(r)]);
        let submitted = Instant::now();
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| RenderError::Wgpu(e.to_string()))?;
        let gpu_done = Instant::now();
        let mut timings = RenderTimings {
            record_submit: submitted - start,
            gpu_wait: gpu_done - submitted,
            gpu_done,
            ..Default::default()
        };
        let Some((_, buf)) = &self.queries else {
            return Ok((None, timings));
        };
        let bytes = read_buffer(device, &r.ctx.queue, buf)?;
        let ticks: &[u64] = bytemuck::cast_slice(&bytes);
        let period = r.ctx.queue.get_timestamp_period() as f64;
        let ms = |i: usize| ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f64 * period / 1e6;
        let mut pass_ms: Vec<(String, f64)> = self
            .passes
            .iter()
            .enumerate()
            .map(|(i, (n, _))| (n.to_string(), ms(i)))
            .collect();
        if self.has_light_motion() {
            pass_ms.push((super::light_motion::STEP.to_string(), ms(self.passes.len())));
        }
        timings.gpu_frame_ms = Some(pass_ms.iter().map(|(_, ms)| ms).sum());
        timings.timestamps_read = gpu_done.elapsed();
        Ok((Some(pass_ms), timings))
    }

    /// Runs one frame and reads back the output, culling reports and statistics.
    pub fn render(&self, r: &Renderer) -> Result<FrameResult, RenderError> {
        self.render_timed(r).map(|(frame, _)| frame)
    }

    /// Like [`render`](Self::render), also saying where the time went: recording and
    /// submitting, waiting for the GPU, the GPU's own time, and the readbacks.
    pub fn render_timed(&self, r: &Renderer) -> Result<(FrameResult, RenderTimings), RenderError> {
        let (pass_ms, mut timings) = self.execute_timed(r)?;
        let start = Instant::now();
        let image = read_rgba32f(&r.ctx.device, &r.ctx.queue, self.output_texture())?;
        timings.image_readback = start.elapsed();
        let start = Instant::now();
        let mut fallbacks = Vec::new();
        let (mut culling, mut shadows, mut atlases) = (Vec::new(), Vec::new(), Vec::new());
        let (mut shadow_compare, mut links, mut vpls) = (Vec::new(), Vec::new(), Vec::new());
        let mut rasters = Vec::new();
        for report in self.pass_reports(r)? {
            match report {
                PassReport::Fallback(f) => fallbacks.push(f),
                PassReport::Culling(c) => culling.push(c),
                PassReport::Shadow(s) => shadows.push(s),
                PassReport::Atlas(a) => atlases.push(a),
                PassReport::ShadowCompare(c) => shadow_compare.push(c),
                PassReport::Links(l) => links.push(l),
                PassReport::Vpl(v) => vpls.push(v),
                PassReport::Raster(c) => rasters.push(c),
            }
        }
        let light_stats = self.read_light_stats(r)?;
        timings.reports_readback = start.elapsed();
        let frame = FrameResult {
            width: self.size.width,
            height: self.size.height,
            image,
            pass_ms,
            fallbacks,
            culling,
            links,
            shadows,
            atlases,
            shadow_compare,
            vpls,
            rasters,
            light_stats,
        };
        Ok((frame, timings))
    }

    /// The graph's output texture (Rgba32Float; sampled by the viewer). Planned for every
    /// prepared frame: `check_output_written`.
    pub fn output_texture(&self) -> &wgpu::Texture {
        self.resources
            .texture(&self.graph.plan, self.graph.output())
            .expect("validation makes the output a planned texture")
    }

    /// Moves the camera without re-preparing (benchmarks, the viewer).
    pub fn set_camera(&self, r: &Renderer, scene: &Scene) {
        self.set_view(r, &scene.camera, scene.ambient);
    }

    /// Writes the frame uniform for `camera`: the next `execute` renders from there. The
    /// light count stays the frame's own (see [`update_lights`](Self::update_lights)).
    pub fn set_view(&self, r: &Renderer, camera: &Camera, ambient: Vec3) {
        let f = GpuFrame::new(
            camera,
            ambient,
            self.size.width,
            self.size.height,
            self.light_count(),
            self.light_count.caster_end(),
        );
        r.ctx
            .queue
            .write_buffer(&self.frame_uniform, 0, bytemuck::bytes_of(&f));
        for (_, pass) in &self.passes {
            pass.set_view(r, camera);
        }
    }
}

/// The output must have a writer that runs for this scene: where `when:` skipped every
/// pass that writes it, nothing would plan it (and a black image would say nothing).
fn check_output_written(graph: &CompiledGraph) -> Result<(), RenderError> {
    let output = graph.output();
    if graph.plan.resources.iter().any(|r| &*r.name == output) {
        return Ok(());
    }
    let writers: Vec<&crate::graph::CulledPass> = graph
        .culled
        .iter()
        .filter(|c| {
            graph
                .checked
                .desc
                .passes
                .iter()
                .any(|p| p.name == c.name && p.writes.iter().any(|w| &**w == output))
        })
        .collect();
    let skipped: Vec<String> = writers
        .iter()
        .map(|c| match &c.reason {
            crate::graph::CullReason::WhenFalse(feature) => {
                format!("'{}' (when: {feature} is false for this scene)", c.name)
            }
            crate::graph::CullReason::Unreachable => format!("'{}'", c.name),
        })
        .collect();
    let pass = writers
        .first()
        .map_or_else(|| output.to_string(), |c| c.name.to_string());
    Err(RenderError::AtPass {
        at: graph.checked.source.in_pass(&pass, output),
        pass,
        problem: format!(
            "output '{output}' has no writer in this scene: its writers {} are skipped",
            skipped.join(", ")
        ),
    })
}
