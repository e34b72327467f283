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

use super::shadow_atlas_raster_input::{
    list_capacity, merge_casters, MergedCasters, Work, ENTRY_BYTES, RECORD_BYTES, STORE_CELL,
};
use super::{grid, pass_error, PrepareCtx, Timestamps};
use crate::gpu::readback::read_buffer;
use crate::render::pipelines::{Pipeline, PipelineKey};
use crate::render::{RenderError, Renderer};
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use wgpu::util::DeviceExt;

const SHADER: &str = "shadow/atlas_raster.wgsl";
/// Threads per setup workgroup (a thread per view and triangle).
const GROUP: u32 = 64;
/// Counter words (the shader's RECORDS..SERIAL_CELLS).
const COUNTERS: u64 = 4;
/// Grown buffers and the bind groups over them.
struct Bound {
    jobs: wgpu::Buffer,
    rects: wgpu::Buffer,
    pieces: wgpu::Buffer,
    setup: wgpu::BindGroup,
    /// The IDS pass's setup (with [`RasterTarget::Buffers`]).
    setup_ids: Option<wgpu::BindGroup>,
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

/// The IDS pass: its pipelines, its own counters and arguments (the two passes run in
/// one compute pass, so neither clears the other's), and the ids.
struct IdsPass {
    setup: Arc<wgpu::ComputePipeline>,
    raster: Arc<wgpu::ComputePipeline>,
    raster_bind: wgpu::BindGroup,
    counters: wgpu::Buffer,
    args: wgpu::Buffer,
    ids: wgpu::Buffer,
    /// Per merged triangle, its visibility id.
    tri_ids: wgpu::Buffer,
}

pub(super) struct ComputeAtlas {
    setup: Arc<wgpu::ComputePipeline>,
    raster: Arc<wgpu::ComputePipeline>,
    store: Option<Arc<wgpu::ComputePipeline>>,
    ids_pass: Option<IdsPass>,
    raster_bind: wgpu::BindGroup,
    params: wgpu::Buffer,
    store_params: wgpu::Buffer,
    positions: wgpu::Buffer,
    indices: wgpu::Buffer,
    depth: wgpu::Buffer,
    records: wgpu::Buffer,
    cells: wgpu::Buffer,
    counters: wgpu::Buffer,
    args: wgpu::Buffer,
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
    /// The first index of each caster draw in the merged index buffer.
    pub(super) index_base: Vec<u32>,
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

fn storage(
    device: &wgpu::Device,
    label: &str,
    bytes: u64,
    extra: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(16),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | extra,
        mapped_at_creation: false,
    })
}

/// A raster run's counters (read back for the report) and its indirect arguments.
fn counters_and_args(device: &wgpu::Device, what: &str) -> [wgpu::Buffer; 2] {
    [
        storage(
            device,
            &format!("{what} counters"),
            4 * COUNTERS,
            wgpu::BufferUsages::COPY_SRC,
        ),
        storage(
            device,
            &format!("{what} arguments"),
            16,
            wgpu::BufferUsages::INDIRECT,
        ),
    ]
}

impl ComputeAtlas {
    /// The rasterizer for `casters` (scene GPU mesh indices, in draw order) into
    /// `target`, reading view-projections from `table` (`view_vec4s` words a view, after
    /// a header vec4).
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
        let ids = matches!(target, RasterTarget::Buffers { .. });
        let MergedCasters {
            positions,
            indices,
            index_base,
            tri_ids,
        } = merge_casters(cx, pass, casters, ids);
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
        // The far depth everywhere: `store` puts it back after each drawn view.
        let far = vec![1.0f32.to_bits(); (side as usize) * (rows as usize)];
        let depth = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("atlas depth (atomic)"),
            contents: bytemuck::cast_slice(&far),
            usage: wgpu::BufferUsages::STORAGE,
        });
        drop(far);
        let capacity =
            list_capacity(side as u64 * rows as u64, limit).map_err(|m| pass_error(pass, m))?;
        let records_buf = storage(
            &device,
            "atlas raster records",
            RECORD_BYTES * capacity[0] as u64,
            wgpu::BufferUsages::empty(),
        );
        let cells_buf = storage(
            &device,
            "atlas raster cells",
            ENTRY_BYTES * capacity[1] as u64,
            wgpu::BufferUsages::empty(),
        );
        let [counters, args] = counters_and_args(&device, "atlas raster");
        let uniform = |label: &str| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 32,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let params = uniform("atlas raster parameters");
        let store_params = uniform("atlas store parameters");
        let max_groups = device.limits().max_compute_workgroups_per_dimension;
        let pipeline = |cx: &mut PrepareCtx,
                        stage: &str,
                        entry: &str,
                        ids: bool|
         -> Result<Arc<wgpu::ComputePipeline>, RenderError> {
            let mut d = vec![
                (stage.to_string(), "1".to_string()),
                ("GROUP".into(), GROUP.to_string()),
                ("STORE_CELL".into(), STORE_CELL.to_string()),
                ("DEPTH_BIAS".into(), format!("{:?}", depth_bias as f32)),
                ("VIEW_VEC4S".into(), format!("{view_vec4s}u")),
                ("SLOPE_BIAS".into(), format!("{slope_bias:?}")),
            ];
            if ids {
                d.push(("IDS".into(), "1".into()));
            }
            let key = PipelineKey {
                shader: SHADER.into(),
                defines: d.into_iter().collect(),
                virtual_code: BTreeMap::new(),
                state: String::new(),
            };
            let device = cx.device();
            let layouts = cx.renderer.layouts.clone();
            let (p, _) = cx
                .renderer
                .pipelines
                .get_or_build_reflected(
                    &cx.renderer.shaders,
                    key,
                    |_, module, bindings| {
                        let bgl = layouts.get(
                            &device,
                            crate::render::bind::layout_entries(
                                bindings,
                                0,
                                wgpu::ShaderStages::COMPUTE,
                            ),
                        );
                        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                            label: Some(entry),
                            bind_group_layouts: &[Some(&*bgl)],
                            immediate_size: 0,
                        });
                        Pipeline::compute(&device, entry, Some(&pl), &module, entry)
                    },
                    &device,
                )
                .map_err(|source| RenderError::Shader {
                    pass: pass.to_string(),
                    source,
                })?;
            match p {
                Pipeline::Compute(p) => Ok(p),
                _ => Err(pass_error(pass, "expected a compute pipeline".into())),
            }
        };
        let setup = pipeline(cx, "SETUP", "setup", false)?;
        let raster = pipeline(cx, "RASTER", "raster", false)?;
        let store = match atlas {
            Some(_) => Some(pipeline(cx, "STORE", "store", false)?),
            None => None,
        };
        let ids_pass = match atlas {
            Some(_) => None,
            None => {
                let setup = pipeline(cx, "SETUP", "setup", true)?;
                let raster = pipeline(cx, "RASTER", "raster", true)?;
                let [counters, args] = counters_and_args(&device, "rsm raster id");
                // Zero: no triangle (the reader puts it back to zero after reading).
                let ids = storage(
                    &device,
                    "rsm raster nearest triangles",
                    depth_bytes,
                    wgpu::BufferUsages::empty(),
                );
                let raster_bind = bind(
                    &device,
                    &raster,
                    &[
                        (0, params.as_entire_binding()),
                        (6, depth.as_entire_binding()),
                        (7, records_buf.as_entire_binding()),
                        (8, cells_buf.as_entire_binding()),
                        (9, counters.as_entire_binding()),
                        (12, ids.as_entire_binding()),
                    ],
                );
                let tri_ids = init("rsm raster visibility ids", bytemuck::cast_slice(&tri_ids));
                Some(IdsPass {
                    tri_ids,
                    setup,
                    raster,
                    raster_bind,
                    counters,
                    args,
                    ids,
                })
            }
        };
        let raster_bind = bind(
            &device,
            &raster,
            &[
                (0, params.as_entire_binding()),
                (6, depth.as_entire_binding()),
                (7, records_buf.as_entire_binding()),
                (8, cells_buf.as_entire_binding()),
                (9, counters.as_entire_binding()),
            ],
        );
        let this = ComputeAtlas {
            setup,
            raster,
            store,
            ids_pass,
            raster_bind,
            params,
            store_params,
            positions,
            indices,
            depth,
            records: records_buf,
            cells: cells_buf,
            counters,
            args,
            table: table.clone(),
            atlas,
            capacity,
            side,
            max_groups,
            bound: Mutex::new(None),
            pending: Mutex::new((0, 0)),
            index_base,
            queue: cx.renderer.ctx.queue.clone(),
            device,
        };
        let first = this.bind_lists(16, 16, 16);
        *this.bound.lock().unwrap_or_else(|e| e.into_inner()) = Some(first);
        Ok(this)
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
        let setup_bind = |pipeline: &wgpu::ComputePipeline,
                          counters: &wgpu::Buffer,
                          args: &wgpu::Buffer,
                          ids: Option<&IdsPass>| {
            let mut entries = vec![
                (0, self.params.as_entire_binding()),
                (1, self.table.as_entire_binding()),
                (2, self.positions.as_entire_binding()),
                (3, self.indices.as_entire_binding()),
                (4, jobs.as_entire_binding()),
                (5, rects.as_entire_binding()),
                (6, self.depth.as_entire_binding()),
                (7, self.records.as_entire_binding()),
                (8, self.cells.as_entire_binding()),
                (9, counters.as_entire_binding()),
                (10, args.as_entire_binding()),
            ];
            if let Some(p) = ids {
                entries.push((12, p.ids.as_entire_binding()));
                entries.push((13, p.tri_ids.as_entire_binding()));
            }
            bind(&self.device, pipeline, &entries)
        };
        let setup = setup_bind(&self.setup, &self.counters, &self.args, None);
        let setup_ids = self
            .ids_pass
            .as_ref()
            .map(|p| setup_bind(&p.setup, &p.counters, &p.args, Some(p)));
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
            setup,
            setup_ids,
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
        let params = [
            work.pairs,
            work.jobs.len() as u32,
            self.max_groups,
            self.side,
            self.capacity[0],
            self.capacity[1],
            0,
            0,
        ];
        self.queue
            .write_buffer(&self.params, 0, bytemuck::cast_slice(&params));
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
            (work.pairs, work.pieces.len() as u32);
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
        encoder.clear_buffer(&self.counters, 0, None);
        encoder.clear_buffer(&self.args, 0, None);
        if let Some(ids) = &self.ids_pass {
            encoder.clear_buffer(&ids.counters, 0, None);
            encoder.clear_buffer(&ids.args, 0, None);
        }
    }

    /// The uploaded work's dispatches into `pass`: setup and raster (then again with
    /// IDS), then the store.
    pub(super) fn record_into(&self, pass: &mut wgpu::ComputePass<'_>) {
        let (pairs, pieces) = *self.pending.lock().unwrap_or_else(|e| e.into_inner());
        let guard = self.bound.lock().unwrap_or_else(|e| e.into_inner());
        let Some(bound) = guard.as_ref() else {
            return;
        };
        if pairs > 0 {
            let [x, y, z] = grid(pairs, GROUP, self.max_groups);
            pass.set_pipeline(&self.setup);
            pass.set_bind_group(0, &bound.setup, &[]);
            pass.dispatch_workgroups(x, y, z);
            pass.set_pipeline(&self.raster);
            pass.set_bind_group(0, &self.raster_bind, &[]);
            pass.dispatch_workgroups_indirect(&self.args, 0);
            if let (Some(ids), Some(setup_ids)) = (&self.ids_pass, &bound.setup_ids) {
                pass.set_pipeline(&ids.setup);
                pass.set_bind_group(0, setup_ids, &[]);
                pass.dispatch_workgroups(x, y, z);
                pass.set_pipeline(&ids.raster);
                pass.set_bind_group(0, &ids.raster_bind, &[]);
                pass.dispatch_workgroups_indirect(&ids.args, 0);
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
        self.ids_pass.as_ref().map(|p| &p.ids)
    }

    /// The lists' fill and serial fallbacks of the last frame that drew.
    pub(super) fn report(&self, r: &Renderer) -> Result<AtlasRasterReport, RenderError> {
        let bytes = read_buffer(&r.ctx.device, &r.ctx.queue, &self.counters)?;
        let c: &[u32] = bytemuck::cast_slice(&bytes);
        Ok(AtlasRasterReport {
            records: c[0].min(self.capacity[0]),
            records_capacity: self.capacity[0],
            cells: c[1].min(self.capacity[1]),
            cells_capacity: self.capacity[1],
            serial_triangles: c[2],
            serial_cells: c[3],
        })
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
