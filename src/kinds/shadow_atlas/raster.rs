//! `ShadowAtlas(raster: Compute)`: the atlas's views rasterized in compute
//! (`shaders/shadow/atlas_raster.wgsl`). The casters are merged once into one position
//! and one index buffer (each mesh's triangles in its shadow chunk order, as the
//! hardware path draws them); per frame the CPU lists the views to draw as jobs (a run of
//! one view's consecutive triangles) and their tiles; `setup` (a thread per view and
//! triangle), `raster` (indirect, a workgroup per 32² cell of a large triangle) and
//! `store` (the depth buffer into the R32Float atlas, and back to far) run in one
//! compute pass. What the CPU hands it (the merged casters, the work lists, their
//! capacities) is in raster_input.rs.
//!
//! The reflective shadow maps' compute raster (`ReflectiveShadowMaps(raster: Compute)`)
//! runs the same rasterizer over its own views ([`RasterTarget::Buffers`]): no store,
//! and a second `setup` and `raster` (IDS) that keep each texel's nearest triangle by
//! its visibility id (`tri_ids`: the merged triangles are in shadow chunk order).
//!
//! Alpha-masked casters are drawn by raster runs of their material's own after the
//! solid casters' (raster_runs.rs), alpha-testing each texel they could win.

use super::shadow_atlas_raster_input::{
    list_capacity, merge_casters, JobLists, MergedCasters, Work, ENTRY_BYTES, RECORD_BYTES,
    STORE_CELL,
};
use super::shadow_atlas_raster_runs::{plain_pipeline, prepare_runs, storage, uniform, Run};
use super::{grid, pass_error, PrepareCtx, Timestamps};
use crate::gpu::readback::read_buffer;
use crate::render::bind::BindingSet;
use crate::render::{RenderError, Renderer};
use std::sync::{Arc, Mutex};
use wgpu::util::DeviceExt;

/// Threads per setup workgroup (a thread per view and triangle).
const GROUP: u32 = 64;

/// Grown buffers and the bind groups over them.
struct Bound {
    jobs: wgpu::Buffer,
    rects: wgpu::Buffer,
    pieces: wgpu::Buffer,
    /// Per raster run, its passes' (depth, then ids) setup and raster bind groups.
    runs: Vec<Vec<[wgpu::BindGroup; 2]>>,
    store: Option<wgpu::BindGroup>,
}

/// Where the rasterized depth goes.
pub(super) enum RasterTarget {
    /// `store` writes the drawn views' depth into this `side`² R32Float atlas.
    Atlas { atlas: wgpu::TextureView, side: u32 },
    /// The depth (and, from the IDS pass, one more than each texel's nearest triangle's
    /// visibility id: the casters must be the opaque draws) stay in the buffers, `width`
    /// texels a row, for the caller to read and put back to far and zero:
    /// [`ComputeAtlas::depth`], [`ComputeAtlas::ids`].
    Buffers { width: u32, height: u32 },
}

pub(super) struct ComputeAtlas {
    store: Option<Arc<wgpu::ComputePipeline>>,
    runs: Vec<Run>,
    store_params: wgpu::Buffer,
    positions: wgpu::Buffer,
    indices: wgpu::Buffer,
    depth: wgpu::Buffer,
    /// One more than each texel's nearest triangle's visibility id (the IDS passes').
    ids: Option<wgpu::Buffer>,
    /// Per merged triangle, its visibility id (with IDS or masked casters).
    tri_ids: wgpu::Buffer,
    /// The merged visibility geometry the alpha test rebuilds triangles from (with
    /// masked casters).
    geometry: Option<(wgpu::Buffer, wgpu::Buffer)>,
    records: wgpu::Buffer,
    cells: wgpu::Buffer,
    table: wgpu::Buffer,
    atlas: Option<wgpu::TextureView>,
    capacity: [u32; 2],
    /// Texels a row of the depth buffer.
    side: u32,
    max_groups: u32,
    bound: Mutex<Option<Bound>>,
    /// The uploaded work's pairs and pieces, drawn by every frame until the next upload
    /// (zero after `drawn`: the cache keeps what the last frame drew).
    pending: Mutex<(u32, u32)>,
    /// The uploaded work's pairs per raster run.
    run_pairs: Mutex<Vec<u32>>,
    /// The first index of each caster draw in the merged index buffer.
    index_base: Vec<u32>,
    /// Each caster draw's raster run.
    run_of_draw: Vec<usize>,
    device: wgpu::Device,
    queue: wgpu::Queue,
}

/// The compute raster's share of the atlas report: its lists' fill and what was drawn
/// serially because a list was full, in the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AtlasRasterReport {
    /// Records of large triangles listed (at most the capacity).
    pub records: u32,
    /// Room for records.
    pub records_capacity: u32,
    /// 32×32 cell entries listed (at most the capacity).
    pub cells: u32,
    /// Room for cell entries.
    pub cells_capacity: u32,
    /// Fan triangles a setup thread rasterized itself (the record list was full).
    pub serial_triangles: u32,
    /// Cells a setup thread rasterized itself (the cell list was full).
    pub serial_cells: u32,
}

impl ComputeAtlas {
    /// The rasterizer for `casters` (scene GPU mesh indices, in draw order) into
    /// `target`, reading view-projections from `table` (`view_vec4s` words a view, after
    /// a header vec4). Alpha-masked casters are drawn by a run of their material's own.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn prepare(
        cx: &mut PrepareCtx,
        pass: &str,
        casters: &[usize],
        target: RasterTarget,
        table: &wgpu::Buffer,
        view_vec4s: u64,
        depth_bias: u32,
        slope_bias: f32,
    ) -> Result<Self, RenderError> {
        let with_ids = matches!(target, RasterTarget::Buffers { .. });
        let MergedCasters {
            positions,
            indices,
            index_base,
            tri_ids,
            run_of_draw,
            masked,
        } = merge_casters(cx, casters, with_ids);
        let (side, rows, atlas) = match target {
            RasterTarget::Atlas { atlas, side } => (side, side, Some(atlas)),
            RasterTarget::Buffers { width, height } => (width, height, None),
        };
        let device = cx.device();
        let limit = device.limits().max_storage_buffer_binding_size;
        let depth_bytes = side as u64 * rows as u64 * 4;
        for (what, bytes) in [
            ("the depth buffer", depth_bytes),
            ("the casters' vertices", 16 * positions.len() as u64),
            ("the casters' indices", 4 * indices.len() as u64),
        ] {
            if bytes > limit {
                return Err(pass_error(
                    pass,
                    format!("raster: Compute needs {what} in one binding of {bytes} bytes; the device binds at most {limit}: use a smaller atlas or raster: Hardware"),
                ));
            }
        }
        let init = |label: &str, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: if contents.is_empty() {
                    &[0u8; 16]
                } else {
                    contents
                },
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let positions = init("atlas caster positions", bytemuck::cast_slice(&positions));
        let indices = init("atlas caster indices", bytemuck::cast_slice(&indices));
        let tri_ids = init(
            "atlas caster visibility ids",
            bytemuck::cast_slice(&tri_ids),
        );
        // The far depth everywhere: `store` puts it back after each drawn view.
        let far = vec![1.0f32.to_bits(); (side as usize) * (rows as usize)];
        let depth = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("atlas depth (atomic)"),
            contents: bytemuck::cast_slice(&far),
            usage: wgpu::BufferUsages::STORAGE,
        });
        drop(far);
        // Zero: no triangle (the reader puts it back to zero after reading).
        let ids = with_ids.then(|| {
            storage(
                &device,
                "rsm raster nearest triangles",
                depth_bytes,
                wgpu::BufferUsages::empty(),
            )
        });
        let geometry = match masked.is_empty() {
            true => None,
            false => {
                let g = cx
                    .gpu
                    .visibility_geometry(&device, cx.scene)
                    .map_err(|m| pass_error(pass, m))?;
                Some((g.vertices.clone(), g.triangles.clone()))
            }
        };
        let capacity =
            list_capacity(side as u64 * rows as u64, limit).map_err(|m| pass_error(pass, m))?;
        let records = storage(
            &device,
            "atlas raster records",
            RECORD_BYTES * capacity[0] as u64,
            wgpu::BufferUsages::empty(),
        );
        let cells = storage(
            &device,
            "atlas raster cells",
            ENTRY_BYTES * capacity[1] as u64,
            wgpu::BufferUsages::empty(),
        );
        let store_params = uniform(&device, "atlas store parameters");
        let max_groups = device.limits().max_compute_workgroups_per_dimension;
        let base_defines = |stage: &str| {
            vec![
                (stage.to_string(), "1".to_string()),
                ("GROUP".into(), GROUP.to_string()),
                ("STORE_CELL".into(), STORE_CELL.to_string()),
                ("DEPTH_BIAS".into(), format!("{:?}", depth_bias as f32)),
                ("VIEW_VEC4S".into(), format!("{view_vec4s}u")),
                ("SLOPE_BIAS".into(), format!("{slope_bias:?}")),
            ]
        };
        let store = match atlas {
            Some(_) => Some(plain_pipeline(cx, pass, base_defines("STORE"), "store")?),
            None => None,
        };
        // Every buffer under its shader name, for the masked runs' reflected layouts
        // (their bind groups are made in `bind_lists`, over the grown lists).
        let mut offered = BindingSet::default();
        let lists = [16u64; 2].map(|n| {
            storage(
                &device,
                "atlas raster lists",
                16 * n,
                wgpu::BufferUsages::empty(),
            )
        });
        for (name, buffer) in [
            ("shadow_views", table),
            ("positions", &positions),
            ("indices", &indices),
            ("jobs", &lists[0]),
            ("rects", &lists[1]),
            ("depth", &depth),
            ("records", &records),
            ("cells", &cells),
            ("tri_ids", &tri_ids),
        ] {
            offered.buffer(name, buffer);
        }
        if let Some(ids) = &ids {
            offered.buffer("ids", ids);
        }
        if let Some((vertices, triangles)) = &geometry {
            offered.buffer("vertices", vertices);
            offered.buffer("triangles", triangles);
        }
        let runs = prepare_runs(cx, pass, &masked, with_ids, &base_defines, &offered)?;
        let this = ComputeAtlas {
            store,
            runs,
            store_params,
            positions,
            indices,
            depth,
            ids,
            tri_ids,
            geometry,
            records,
            cells,
            table: table.clone(),
            atlas,
            capacity,
            side,
            max_groups,
            bound: Mutex::new(None),
            pending: Mutex::new((0, 0)),
            run_pairs: Mutex::new(Vec::new()),
            index_base,
            run_of_draw,
            queue: cx.renderer.ctx.queue.clone(),
            device,
        };
        let first = this.bind_lists(16, 16, 16);
        *this.bound.lock().unwrap_or_else(|e| e.into_inner()) = Some(first);
        Ok(this)
    }

    /// A frame's job lists, each caster's jobs into its raster run.
    pub(super) fn job_lists(&self) -> JobLists<'_> {
        JobLists::new(&self.run_of_draw, &self.index_base, self.runs.len())
    }

    /// Lists of room for `jobs`, `rects` and `pieces` entries, bound.
    fn bind_lists(&self, jobs: usize, rects: usize, pieces: usize) -> Bound {
        let list = |label: &str, n: usize| {
            storage(
                &self.device,
                label,
                16 * n as u64,
                wgpu::BufferUsages::empty(),
            )
        };
        let jobs = list("atlas raster jobs", jobs);
        let rects = list("atlas raster tiles", rects);
        let pieces = list("atlas store pieces", pieces);
        let runs = self
            .runs
            .iter()
            .map(|run| {
                run.passes
                    .iter()
                    .map(|p| {
                        let mut setup = vec![
                            (0, run.params.as_entire_binding()),
                            (1, self.table.as_entire_binding()),
                            (2, self.positions.as_entire_binding()),
                            (3, self.indices.as_entire_binding()),
                            (4, jobs.as_entire_binding()),
                            (5, rects.as_entire_binding()),
                            (6, self.depth.as_entire_binding()),
                            (7, self.records.as_entire_binding()),
                            (8, self.cells.as_entire_binding()),
                            (9, p.counters.as_entire_binding()),
                            (10, p.args.as_entire_binding()),
                        ];
                        let mut raster = vec![
                            (0, run.params.as_entire_binding()),
                            (6, self.depth.as_entire_binding()),
                            (7, self.records.as_entire_binding()),
                            (8, self.cells.as_entire_binding()),
                            (9, p.counters.as_entire_binding()),
                        ];
                        if let (true, Some(ids)) = (p.ids, &self.ids) {
                            setup.push((12, ids.as_entire_binding()));
                            raster.push((12, ids.as_entire_binding()));
                        }
                        if p.ids || run.masked {
                            setup.push((13, self.tri_ids.as_entire_binding()));
                        }
                        if let (true, Some((vertices, triangles))) = (run.masked, &self.geometry) {
                            for entries in [&mut setup, &mut raster] {
                                entries.push((14, vertices.as_entire_binding()));
                                entries.push((15, triangles.as_entire_binding()));
                            }
                            raster.push((1, self.table.as_entire_binding()));
                            raster.push((5, rects.as_entire_binding()));
                        }
                        [
                            bind(&self.device, &p.setup, &setup),
                            bind(&self.device, &p.raster, &raster),
                        ]
                    })
                    .collect()
            })
            .collect();
        let store = match (&self.store, &self.atlas) {
            (Some(store), Some(atlas)) => Some(bind(
                &self.device,
                store,
                &[
                    (0, self.store_params.as_entire_binding()),
                    (5, pieces.as_entire_binding()),
                    (6, self.depth.as_entire_binding()),
                    (11, wgpu::BindingResource::TextureView(atlas)),
                ],
            )),
            _ => None,
        };
        Bound {
            jobs,
            rects,
            pieces,
            runs,
            store,
        }
    }

    /// Uploads a frame's work (written before the next submission).
    pub(super) fn upload(&self, work: &Work) {
        let mut guard = self.bound.lock().unwrap_or_else(|e| e.into_inner());
        let room = |b: &wgpu::Buffer| (b.size() / 16) as usize;
        let bound = match guard.take() {
            Some(b)
                if work.jobs.len() <= room(&b.jobs)
                    && work.rects.len() <= room(&b.rects)
                    && work.pieces.len() <= room(&b.pieces) =>
            {
                b
            }
            had => {
                let grow = |n: usize, had: Option<&wgpu::Buffer>| {
                    n.max(had.map_or(16, room)).next_power_of_two()
                };
                self.bind_lists(
                    grow(work.jobs.len(), had.as_ref().map(|b| &b.jobs)),
                    grow(work.rects.len(), had.as_ref().map(|b| &b.rects)),
                    grow(work.pieces.len(), had.as_ref().map(|b| &b.pieces)),
                )
            }
        };
        let bound = &*guard.insert(bound);
        for (buffer, list) in [
            (&bound.jobs, &work.jobs),
            (&bound.rects, &work.rects),
            (&bound.pieces, &work.pieces),
        ] {
            if !list.is_empty() {
                self.queue
                    .write_buffer(buffer, 0, bytemuck::cast_slice(list));
            }
        }
        let mut pairs = self.run_pairs.lock().unwrap_or_else(|e| e.into_inner());
        pairs.clear();
        for (run, &[first_job, jobs, run_pairs]) in self.runs.iter().zip(&work.runs) {
            let params = [
                run_pairs,
                jobs,
                self.max_groups,
                self.side,
                self.capacity[0],
                self.capacity[1],
                first_job,
                0,
            ];
            self.queue
                .write_buffer(&run.params, 0, bytemuck::cast_slice(&params));
            pairs.push(run_pairs);
        }
        let store = [
            work.pieces.len() as u32,
            0,
            self.max_groups,
            self.side,
            0,
            0,
            0,
            0,
        ];
        self.queue
            .write_buffer(&self.store_params, 0, bytemuck::cast_slice(&store));
        *self.pending.lock().unwrap_or_else(|e| e.into_inner()) =
            (work.pairs(), work.pieces.len() as u32);
    }

    /// The atlas holds the uploaded work's views: later frames draw none until the next
    /// upload (`cache: true`).
    pub(super) fn drawn(&self) {
        *self.pending.lock().unwrap_or_else(|e| e.into_inner()) = (0, 0);
    }

    /// Draws the uploaded work: one compute pass.
    pub(super) fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        ts: Timestamps<'_>,
    ) {
        self.clear_lists(encoder);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: ts.compute(),
        });
        self.record_into(&mut pass);
    }

    /// Resets the lists' counters and arguments (outside any pass) before
    /// [`Self::record_into`].
    pub(super) fn clear_lists(&self, encoder: &mut wgpu::CommandEncoder) {
        let (pairs, _) = *self.pending.lock().unwrap_or_else(|e| e.into_inner());
        if pairs == 0 {
            return;
        }
        for p in self.runs.iter().flat_map(|r| &r.passes) {
            encoder.clear_buffer(&p.counters, 0, None);
            encoder.clear_buffer(&p.args, 0, None);
        }
    }

    /// The uploaded work's dispatches into `pass`: each run's setup and raster (then
    /// again with IDS; the masked runs after the solid one), then the store.
    pub(super) fn record_into(&self, pass: &mut wgpu::ComputePass<'_>) {
        let (pairs, pieces) = *self.pending.lock().unwrap_or_else(|e| e.into_inner());
        let guard = self.bound.lock().unwrap_or_else(|e| e.into_inner());
        let Some(bound) = guard.as_ref() else {
            return;
        };
        let run_pairs = self.run_pairs.lock().unwrap_or_else(|e| e.into_inner());
        // The depth passes of every run before any IDS pass: the ids need the nearest
        // depth of all casters.
        for ids in [false, true] {
            if pairs == 0 {
                break;
            }
            for ((run, binds), &n) in self.runs.iter().zip(&bound.runs).zip(run_pairs.iter()) {
                if n == 0 {
                    continue;
                }
                if let Some(t) = &run.textures {
                    pass.set_bind_group(2, t, &[]);
                }
                let [x, y, z] = grid(n, GROUP, self.max_groups);
                for (p, [setup, raster]) in
                    run.passes.iter().zip(binds).filter(|(p, _)| p.ids == ids)
                {
                    pass.set_pipeline(&p.setup);
                    pass.set_bind_group(0, setup, &[]);
                    pass.dispatch_workgroups(x, y, z);
                    pass.set_pipeline(&p.raster);
                    pass.set_bind_group(0, raster, &[]);
                    pass.dispatch_workgroups_indirect(&p.args, 0);
                }
            }
        }
        if let (true, Some(store), Some(bind)) = (pieces > 0, &self.store, &bound.store) {
            let [x, y, z] = grid(pieces, 1, self.max_groups);
            pass.set_pipeline(store);
            pass.set_bind_group(0, bind, &[]);
            pass.dispatch_workgroups(x, y, z);
        }
    }

    /// The depth buffer (`width` u32 depth bits a row; far where nothing was drawn).
    pub(super) fn depth(&self) -> &wgpu::Buffer {
        &self.depth
    }

    /// With [`RasterTarget::Buffers`]: each texel's nearest triangle's visibility id + 1
    /// (0: none), as the depth buffer is laid out.
    pub(super) fn ids(&self) -> Option<&wgpu::Buffer> {
        self.ids.as_ref()
    }

    /// The lists' fill (the fullest run's) and serial fallbacks (all runs') of the last
    /// frame that drew.
    pub(super) fn report(&self, r: &Renderer) -> Result<AtlasRasterReport, RenderError> {
        let mut report = AtlasRasterReport {
            records_capacity: self.capacity[0],
            cells_capacity: self.capacity[1],
            ..Default::default()
        };
        for run in &self.runs {
            let Some(p) = run.passes.first() else {
                continue;
            };
            let bytes = read_buffer(&r.ctx.device, &r.ctx.queue, &p.counters)?;
            let c: &[u32] = bytemuck::cast_slice(&bytes);
            report.records = report.records.max(c[0].min(self.capacity[0]));
            report.cells = report.cells.max(c[1].min(self.capacity[1]));
            report.serial_triangles += c[2];
            report.serial_cells += c[3];
        }
        Ok(report)
    }
}

fn bind(
    device: &wgpu::Device,
    pipeline: &wgpu::ComputePipeline,
    entries: &[(u32, wgpu::BindingResource<'_>)],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = entries
        .iter()
        .map(|(binding, resource)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: resource.clone(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("shadow atlas raster"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    })
}
