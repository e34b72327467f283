//! `ShadowAtlas`: allocates the atlas for the current view on the CPU
//! (`shadow::atlas::allocate`), uploads the view table, and draws every view's visible
//! casters into its tile, all views in one render pass (a viewport each, the view as
//! the instance index), or with the compute raster (`raster: Compute`,
//! `shadow_atlas_raster`). The allocation is redone once before the next frame whenever
//! the camera or the lights moved (a viewer moving both between two frames pays for one).
//! With `cache: true` the lights that kept their tile side keep their place
//! (`shadow::atlas_cache::keep_places`) and only the views the atlas does not hold yet
//! are drawn. The compute raster alpha-tests masked casters in a run of their
//! material's own (`shadow_atlas_raster`).

use super::shadow_atlas_raster::{ComputeAtlas, RasterTarget};
use super::shadow_atlas_raster_input::{pieces, Work};
use super::{pass_error, PrepareCtx, PreparedPass, Timestamps};
use crate::graph::kinds::shadow_atlas::{
    atlas_side, view_table_bytes, AtlasRaster, ShadowAtlas, SHADOW_ATLAS, SHADOW_VIEWS, VIEW_VEC4S,
};
use crate::graph::Name;
use crate::graph::{FrameSize, ResourceDesc, ScheduledPass};
use crate::render::draws::{DrawMode, MeshDraws, MeshSet, ViewDraw};
use crate::render::pipelines::{Pipeline, PipelineKey};
use crate::render::report::{AtlasReport, PassReport};
use crate::render::{RenderError, Renderer};
use crate::scene::{Camera, Light};
use crate::shadow::atlas::{allocate, Allocation, AtlasConfig};
use crate::shadow::atlas_cache::{keep_places, AtlasCache};
use crate::shadow::view_bounds::{box_in_frustum, frustum_planes};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

pub(super) struct ShadowAtlasPass {
    name: Name,
    config: AtlasConfig,
    /// A ShadowRayJobs pass reads the view table: lights without a map are ray-cast.
    rays_for_the_rest: bool,
    /// Room for views in the table (six per light), as the planned layout has it.
    max_views: u64,
    normal_offset: f32,
    size: FrameSize,
    /// The lights and camera allocated for, kept to reallocate when either changes.
    lights: Mutex<Vec<Light>>,
    camera: Mutex<Camera>,
    /// Each draw's mesh: its bounds and triangle chunks, in draw order.
    meshes: Vec<(
        [glam::Vec3; 2],
        std::sync::Arc<[crate::shadow::chunks::Chunk]>,
    )>,
    atlas_bytes: u64,
    views: wgpu::Buffer,
    /// The table as the CPU wrote it for the current view; copied into `views` when
    /// the frame runs (the planned buffer may be shared with passes before this one).
    staging: wgpu::Buffer,
    table_bytes: u64,
    raster: Raster,
    frame: Mutex<Frame>,
    /// What the atlas holds, when the pass keeps views across frames (`cache: true`).
    cache: Option<Mutex<AtlasCache>>,
    /// Views drawn by the last recorded frame.
    rendered: AtomicU32,
    /// The camera or the lights changed since the last allocation: allocate again before
    /// the next frame is recorded or reported.
    stale: AtomicBool,
    /// Allocations made since prepare (reported: `AtlasReport::allocations`).
    allocations: AtomicU64,
    /// Writes the table the allocation makes.
    queue: wgpu::Queue,
}

/// Who draws the views.
enum Raster {
    Hardware {
        draws: MeshDraws,
        /// Writes the far depth over a tile (each view clears its own).
        clear: Arc<wgpu::RenderPipeline>,
        /// The depth attachment drawn into: the atlas.
        target: wgpu::TextureView,
    },
    Compute(Box<ComputeAtlas>),
}

/// The current allocation, each view's culled caster ranges, and the views to draw when
/// the next frame is recorded (all of them without the cache).
#[derive(Default)]
struct Frame {
    allocation: Allocation,
    draws: Vec<ViewDraw>,
    to_draw: Vec<u32>,
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    p: &ShadowAtlas,
) -> Result<ShadowAtlasPass, RenderError> {
    let atlas_name = sp.required(SHADOW_ATLAS);
    let desc = cx
        .graph
        .checked
        .desc
        .resources
        .iter()
        .find(|r| r.name() == atlas_name);
    let side = atlas_side(desc).ok_or_else(|| {
        pass_error(
            &sp.name,
            format!("'{atlas_name}' is not a square power-of-two atlas"),
        )
    })?;
    let format = match desc {
        Some(ResourceDesc::Texture { format, .. }) => format.to_wgpu(),
        _ => wgpu::TextureFormat::Depth32Float,
    };
    // Its side against the device's limit was checked with every planned texture
    // (render/device_limits.rs) before any was created.
    let views = cx.buffer(&sp.name, sp.required(SHADOW_VIEWS))?;
    // Room for every light an update may write.
    let table_bytes = view_table_bytes(cx.gpu.light_capacity, p.max_views());
    if views.size() < table_bytes {
        return Err(pass_error(
            &sp.name,
            format!(
                "buffer '{}' holds {} bytes; the view table for {} lights and {} views needs {table_bytes} (size: Auto)",
                sp.required(SHADOW_VIEWS),
                views.size(),
                cx.gpu.light_capacity,
                p.max_views()
            ),
        ));
    }
    let device = cx.device();
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("shadow view table (upload)"),
        size: table_bytes,
        usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let atlas = cx.view(&sp.name, atlas_name)?;
    let (raster, casters) = match p.raster {
        AtlasRaster::Hardware => {
            let mut offered = cx.declared(sp)?;
            // The vertex stage reads the table it is about to receive.
            offered.buffer("shadow_views", &views);
            let mode = DrawMode::AtlasDepth {
                format,
                depth_bias: p.depth_bias as i32,
                slope_bias_bits: p.slope_bias.to_bits(),
            };
            let draws = cx.renderer.mesh_draws(
                cx.gpu,
                mode,
                MeshSet::ShadowCasters,
                1,
                &sp.name,
                &offered,
            )?;
            let clear = tile_clear_pipeline(cx, &sp.name, format)?;
            let casters: Vec<usize> = draws.meshes().collect();
            let target = atlas.clone();
            (
                Raster::Hardware {
                    draws,
                    clear,
                    target,
                },
                casters,
            )
        }
        AtlasRaster::Compute => {
            // The casters in the order the hardware path draws them.
            let casters = cx.gpu.shadow_caster_draws();
            let compute = ComputeAtlas::prepare(
                cx,
                &sp.name,
                &casters,
                RasterTarget::Atlas {
                    atlas: atlas.clone(),
                    side,
                },
                &views,
                VIEW_VEC4S,
                p.depth_bias,
                p.slope_bias,
            )?;
            (Raster::Compute(Box::new(compute)), casters)
        }
    };
    let meshes = casters
        .iter()
        .map(|&m| (cx.gpu.meshes[m].bounds, cx.gpu.meshes[m].chunks.clone()))
        .collect();
    let bytes_per_texel = format
        .block_copy_size(Some(wgpu::TextureAspect::DepthOnly))
        .unwrap_or(4);
    let pass = ShadowAtlasPass {
        name: sp.name.clone(),
        config: AtlasConfig {
            size: side,
            min_tile: p.min_tile,
            max_tile: p.max_tile,
            importance: p.importance,
            max_lights: p.max_lights,
            policy: p.policy,
            fit: p.fit,
        },
        rays_for_the_rest: rays_read_views(cx, sp.required(SHADOW_VIEWS)),
        max_views: p.max_views(),
        normal_offset: p.normal_offset,
        size: cx.size,
        lights: Mutex::new(cx.scene.lights.clone()),
        camera: Mutex::new(cx.scene.camera),
        meshes,
        atlas_bytes: side as u64 * side as u64 * bytes_per_texel as u64,
        views,
        staging,
        table_bytes,
        raster,
        frame: Mutex::new(Frame::default()),
        cache: p.cache.then(|| Mutex::new(AtlasCache::default())),
        rendered: AtomicU32::new(0),
        stale: AtomicBool::new(false),
        allocations: AtomicU64::new(0),
        queue: cx.renderer.ctx.queue.clone(),
    };
    pass.allocate();
    Ok(pass)
}

/// Whether a ShadowRayJobs pass of the graph reads the view table `views` (and so casts
/// rays for the lights without a map).
fn rays_read_views(cx: &PrepareCtx, views: &str) -> bool {
    let checked = &cx.graph.checked;
    checked
        .desc
        .passes
        .iter()
        .zip(&checked.roles)
        .any(|(p, r)| {
            matches!(p.kind, crate::graph::PassKind::ShadowRayJobs(_))
                && r.slot(SHADOW_VIEWS) == Some(views)
        })
}

/// Depth 1 over the viewport, whatever was there (no bindings, no fragment stage).
fn tile_clear_pipeline(
    cx: &mut PrepareCtx,
    pass: &str,
    format: wgpu::TextureFormat,
) -> Result<Arc<wgpu::RenderPipeline>, RenderError> {
    let device = cx.device();
    let key = PipelineKey {
        shader: "shadow/atlas_clear.wgsl".into(),
        defines: BTreeMap::new(),
        virtual_code: BTreeMap::new(),
        state: format!("format={format:?}"),
    };
    let (pipeline, _) = cx
        .renderer
        .pipelines
        .get_or_build_reflected(
            &cx.renderer.shaders,
            key,
            |_, module, _| {
                let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some(pass),
                    bind_group_layouts: &[],
                    immediate_size: 0,
                });
                Pipeline::Render(Arc::new(device.create_render_pipeline(
                    &wgpu::RenderPipelineDescriptor {
                        label: Some(pass),
                        layout: Some(&layout),
                        vertex: wgpu::VertexState {
                            module: &module,
                            entry_point: Some("vs_main"),
                            compilation_options: Default::default(),
                            buffers: &[],
                        },
                        primitive: Default::default(),
                        depth_stencil: Some(wgpu::DepthStencilState {
                            format,
                            depth_write_enabled: Some(true),
                            depth_compare: Some(wgpu::CompareFunction::Always),
                            stencil: Default::default(),
                            bias: Default::default(),
                        }),
                        multisample: Default::default(),
                        fragment: None,
                        multiview_mask: None,
                        cache: crate::render::pipelines::driver_cache().as_ref(),
                    },
                )))
            },
            &device,
        )
        .map_err(|source| RenderError::Shader {
            pass: pass.to_string(),
            source,
        })?;
    match pipeline {
        Pipeline::Render(p) => Ok(p),
        _ => Err(pass_error(pass, "expected a render pipeline".into())),
    }
}

impl ShadowAtlasPass {
    /// Allocates again if the camera or the lights changed since the last allocation.
    fn allocate_if_stale(&self) {
        if self.stale.swap(false, Ordering::AcqRel) {
            self.allocate();
        }
    }

    /// Allocates for the kept camera and lights, uploads the table (written before the
    /// next submission, so before the frame's copy of it) and culls each view's casters.
    fn allocate(&self) {
        self.allocations.fetch_add(1, Ordering::Relaxed);
        let camera = *self.camera.lock().unwrap_or_else(|e| e.into_inner());
        let lights = self.lights.lock().unwrap_or_else(|e| e.into_inner());
        let a = allocate(
            &lights,
            &camera,
            self.size.width,
            self.size.height,
            &self.config,
        );
        let mut frame = self.frame.lock().unwrap_or_else(|e| e.into_inner());
        let (a, to_draw) = match &self.cache {
            Some(cache) => {
                let a = keep_places(&frame.allocation, a, &self.config);
                let stale = cache
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .stale_views(&a);
                (a, stale)
            }
            None => {
                let all = (0..a.views.len() as u32).collect();
                (a, all)
            }
        };
        let max_views = self.max_views as usize;
        let mut table = vec![[0u32; 4]; (self.table_bytes / 16) as usize];
        table[0] = [
            a.views.len() as u32,
            self.config.size,
            lights.len() as u32,
            max_views as u32,
        ];
        let n = self.config.size as f32;
        for (v, view) in a.views.iter().enumerate() {
            let base = 1 + VIEW_VEC4S as usize * v;
            for (c, col) in view.view_proj.to_cols_array_2d().iter().enumerate() {
                table[base + c] = col.map(f32::to_bits);
            }
            let (x0, y0) = (view.x as f32 / n, view.y as f32 / n);
            let (x1, y1) = (
                (view.x + view.tile) as f32 / n,
                (view.y + view.tile) as f32 / n,
            );
            table[base + 4] = [x0, y0, x1, y1].map(f32::to_bits);
            table[base + 5] = [view.texel_scale, self.normal_offset, 0.0, 0.0].map(f32::to_bits);
        }
        let light_table = 1 + VIEW_VEC4S as usize * max_views;
        for l in &a.lights {
            let entry = (l.first_view + 1) | if l.cube { 1 << 31 } else { 0 };
            let i = l.light as usize;
            table[light_table + i / 4][i % 4] = entry;
        }
        self.queue
            .write_buffer(&self.staging, 0, bytemuck::cast_slice(&table));
        let draws: Vec<ViewDraw> = a
            .views
            .iter()
            .map(|view| {
                let planes = frustum_planes(view.view_proj);
                let mut ranges: Vec<(usize, u32, u32)> = Vec::new();
                for (draw, ([lo, hi], chunks)) in self.meshes.iter().enumerate() {
                    if !box_in_frustum(&planes, *lo, *hi) {
                        continue;
                    }
                    for c in chunks
                        .iter()
                        .filter(|c| box_in_frustum(&planes, c.min, c.max))
                    {
                        // Consecutive visible chunks make one draw.
                        match ranges.last_mut() {
                            Some((d, first, count)) if *d == draw && *first + *count == c.first => {
                                *count += c.count
                            }
                            _ => ranges.push((draw, c.first, c.count)),
                        }
                    }
                }
                ViewDraw {
                    x: view.x,
                    y: view.y,
                    tile: view.tile,
                    ranges,
                }
            })
            .collect();
        if let Raster::Compute(compute) = &self.raster {
            compute.upload(&compute_work(compute, &draws, &to_draw));
        }
        *frame = Frame {
            allocation: a,
            draws,
            to_draw,
        };
    }
}

impl PreparedPass for ShadowAtlasPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        self.allocate_if_stale();
        encoder.copy_buffer_to_buffer(&self.staging, 0, &self.views, 0, self.table_bytes);
        let mut frame = self.frame.lock().unwrap_or_else(|e| e.into_inner());
        match &self.raster {
            Raster::Hardware {
                draws,
                clear,
                target,
            } => {
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some(&self.name),
                    color_attachments: &[],
                    // Tiles are cleared one by one (record_views): loading is free,
                    // clearing the whole atlas is not (about 55 GB/s measured on the H200),
                    // and the cache keeps the tiles not drawn.
                    depth_stencil_attachment: Some(crate::render::draws::depth_attachment(
                        target, false,
                    )),
                    timestamp_writes: ts.render(),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                draws.record_views(&mut pass, &frame.draws, &frame.to_draw, clear);
            }
            Raster::Compute(compute) => compute.record(encoder, &self.name, ts),
        }
        self.rendered
            .store(frame.to_draw.len() as u32, Ordering::Relaxed);
        if let Some(cache) = &self.cache {
            // Once recorded, the atlas holds every view: the next frame draws none unless
            // something changes.
            cache
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .hold(&frame.allocation);
            frame.to_draw.clear();
            if let Raster::Compute(compute) = &self.raster {
                compute.drawn();
            }
        }
    }

    fn report(&self, _r: &Renderer) -> Result<Option<PassReport>, RenderError> {
        self.allocate_if_stale();
        let raster = match &self.raster {
            Raster::Compute(compute) => Some(compute.report(_r)?),
            Raster::Hardware { .. } => None,
        };
        let frame = self.frame.lock().unwrap_or_else(|e| e.into_inner());
        let (a, draws) = (&frame.allocation, &frame.draws);
        Ok(Some(PassReport::Atlas(AtlasReport {
            pass: self.name.to_string(),
            side: self.config.size,
            atlas_bytes: self.atlas_bytes,
            table_bytes: self.table_bytes,
            shadowed: a.lights.clone(),
            dropped: a.dropped.clone(),
            left_by_policy: a.left_by_policy.clone(),
            rays_for_the_rest: self.rays_for_the_rest,
            off_screen: a.off_screen,
            views: a.views.len() as u32,
            halvings: a.halvings,
            used_texels: a.used_texels,
            draws: draws.iter().map(|d| d.ranges.len() as u64).sum(),
            triangles: draws
                .iter()
                .flat_map(|d| d.ranges.iter().map(|r| r.2 as u64 / 3))
                .sum(),
            allocations: self.allocations.load(Ordering::Relaxed),
            views_rendered: self.rendered.load(Ordering::Relaxed),
            raster,
        })))
    }

    fn follow_lights(&self, _r: &Renderer, lights: &[Light]) {
        let mut kept = self.lights.lock().unwrap_or_else(|e| e.into_inner());
        kept.clear();
        kept.extend_from_slice(lights);
        self.stale.store(true, Ordering::Release);
    }

    fn set_view(&self, _r: &Renderer, camera: &Camera) {
        *self.camera.lock().unwrap_or_else(|e| e.into_inner()) = *camera;
        self.stale.store(true, Ordering::Release);
    }
}

/// The compute raster's lists for the views at `to_draw`: a job per culled range (in its
/// caster's raster run), each view's tile, the pieces of the tiles to store.
fn compute_work(compute: &ComputeAtlas, draws: &[ViewDraw], to_draw: &[u32]) -> Work {
    let mut jobs = compute.job_lists();
    let mut stored = Vec::new();
    for &v in to_draw {
        let d = &draws[v as usize];
        for &(draw, first, count) in &d.ranges {
            jobs.push(v, draw, first, count);
        }
        pieces(d.x, d.y, d.tile, &mut stored);
    }
    jobs.finish(
        draws.iter().map(|d| [d.x, d.y, d.tile, 0]).collect(),
        stored,
    )
}
