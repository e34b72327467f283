//! `LightCulling`: per-tile light lists, with an optional coarse stage first in the same
//! compute pass; reports each frame's overflows and longest list. Compact lists run
//! count → scan → fill in that pass too, the fill only for lists longer than their
//! scratch slot (see `shaders/cull/light_culling.wgsl`).

use super::{defines, PrepareCtx, PreparedPass, Timestamps};
use crate::gpu::readback::read_buffer;
use crate::gpu::structs::LIGHT_BYTES;
use crate::graph::Name;
use crate::graph::{slot, LightCulling, ListLayout, ListStorage, ScheduledPass};
use crate::render::device_limits::create_internal_buffer;
use crate::render::pipelines::PipelineKey;
use crate::render::report::{CullingReport, PassReport};
use crate::render::{RenderError, Renderer};
use std::collections::BTreeMap;
use std::sync::Arc;

/// Most lights a coarse culling tile lists; a tile with more sends its fine tiles back
/// to testing every light.
const COARSE_CAPACITY: u64 = 8192;
/// Most lights a wide tile lists; a wide tile with more sends its coarse tiles back to
/// testing every light.
const WIDE_CAPACITY: u64 = 16384;
/// `light_bounds` in `light_culling.wgsl`: four vec4s a light.
const LIGHT_BOUNDS_BYTES: u64 = 64;
/// The bounds dispatch's workgroup size (`bounds` in the shader).
const BOUNDS_GROUP: u32 = 64;

pub(super) struct LightCullingPass {
    name: Name,
    /// Every light's view-space bounds, first: (pipeline, workgroups).
    bounds: (Arc<wgpu::ComputePipeline>, [u32; 3]),
    /// The wide and coarse stages, run first in the same pass.
    wide: Option<(Arc<wgpu::ComputePipeline>, [u32; 3])>,
    coarse: Option<(Arc<wgpu::ComputePipeline>, [u32; 3])>,
    pipeline: Arc<wgpu::ComputePipeline>,
    bind: wgpu::BindGroup,
    groups: [u32; 3],
    /// Compact lists: the scan between the two runs of `pipeline`.
    compact: Option<Compact>,
    lists: wgpu::Buffer,
    /// The header and list entries, copied out after culling: the report reads these,
    /// since a later pass may reuse the lists' memory (aliasing) before it is read.
    report_copy: wgpu::Buffer,
    layout: ListLayout,
    /// Diagnosis: the one dispatch the pass's timestamps bracket (`LIGHTGRAPH_TIME_DISPATCH`:
    /// 0 bounds, then wide, coarse, count, scan_lists, fill, each counted where it runs).
    timed_dispatch: Option<usize>,
}

/// What compact lists add: the fill's bind group (the same pipeline as the count, with
/// `compact.phase` 1), the scan pipeline and the block sums it reads.
struct Compact {
    fill: wgpu::BindGroup,
    scan_lists: Arc<wgpu::ComputePipeline>,
    block_sums: wgpu::Buffer,
    blocks: u32,
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    p: &LightCulling,
) -> Result<LightCullingPass, RenderError> {
    let device = cx.device();
    let layout = p.list_layout(cx.size.width, cx.size.height);
    let lists = cx.buffer(&sp.name, sp.required(slot::LIGHT_LISTS))?;
    let coarse = p.coarse.max(1);
    let coarse_groups = [
        layout.tiles_x.div_ceil(coarse),
        layout.tiles_y.div_ceil(coarse),
        1,
    ];
    // Each coarse tile: a count and up to COARSE_CAPACITY indices (a single unused word
    // without a coarse stage).
    let coarse_words = if coarse > 1 {
        coarse_groups[0] as u64 * coarse_groups[1] as u64 * (COARSE_CAPACITY + 1)
    } else {
        1
    };
    let coarse_lists = create_internal_buffer(
        &device,
        &sp.name,
        &wgpu::BufferDescriptor {
            label: Some("coarse light lists"),
            size: coarse_words * 4,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        },
    )?;
    let mut offered = cx.declared(sp)?;
    offered.buffer(
        "list_params",
        &crate::gpu::structs::GpuListParams::new(&layout).buffer(&device),
    );
    offered.buffer("coarse_lists", &coarse_lists);
    // The wide stage: a count and up to WIDE_CAPACITY indices per wide tile.
    let wide = if coarse > 1 { p.wide.max(1) } else { 1 };
    let wide_groups = [
        coarse_groups[0].div_ceil(wide),
        coarse_groups[1].div_ceil(wide),
        1,
    ];
    if wide > 1 {
        let words = wide_groups[0] as u64 * wide_groups[1] as u64 * (WIDE_CAPACITY + 1);
        let wide_lists = create_internal_buffer(
            &device,
            &sp.name,
            &wgpu::BufferDescriptor {
                label: Some("wide light lists"),
                size: words * 4,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            },
        )?;
        offered.buffer("wide_lists", &wide_lists);
    }
    // Every light's view-space bounds, written by the pass's first dispatch: room for
    // every light the bound light buffer holds (passes before this one, VplSpawn, may
    // add lights to the scene's).
    let light_capacity = offered
        .buffer_size("light_geometry")
        .map_or(cx.gpu.light_capacity as u64, |b| b / LIGHT_BYTES)
        .max(1);
    let light_bounds = create_internal_buffer(
        &device,
        &sp.name,
        &wgpu::BufferDescriptor {
            label: Some("light bounds (view space)"),
            size: LIGHT_BOUNDS_BYTES * light_capacity,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        },
    )?;
    offered.buffer("light_bounds", &light_bounds);
    let mut d = vec![
        ("TILE", format!("{}u", p.tile)),
        ("VARIANT", format!("{}u", p.variant.code())),
        ("COARSE", format!("{coarse}u")),
        ("COARSE_CAPACITY", format!("{COARSE_CAPACITY}u")),
        ("WIDE", format!("{wide}u")),
        ("WIDE_CAPACITY", format!("{WIDE_CAPACITY}u")),
        // Every sample of a multisampled depth bounds the tile.
        ("SAMPLES", format!("{}u", sp.samples)),
    ];
    if sp.samples > 1 {
        d.push(("MSAA", "1".into()));
    }
    if wide > 1 {
        d.push(("WIDE_STAGE", "1".into()));
    }
    // The tile's depth range by subgroup reductions (one barrier instead of two).
    if device.features().contains(wgpu::Features::SUBGROUP) {
        d.push(("SUBGROUPS", "1".into()));
    }
    // A compute resolve's R32Float depth (validation keeps it single-sample).
    if cx.float_depth(sp.required(slot::DEPTH)) {
        d.push(("FLOAT_DEPTH", "1".into()));
    }
    if let Some(t) = sp.roles.slot(slot::TRANSPARENT_DEPTH) {
        d.push(("TRANSPARENT", "1".into()));
        // A compute-rasterized transparent depth (TransparentDepth into R32Float).
        if cx.float_depth(t) {
            d.push(("FLOAT_TRANSPARENT", "1".into()));
        }
        if sp.roles.slot(slot::TRANSPARENT_FAR).is_some() {
            d.push(("TRANSPARENT_FAR", "1".into()));
        }
    }
    let blocks = layout.scan_blocks();
    if let ListStorage::Fixed { capacity } = layout.storage {
        d.push(("CAPACITY", format!("{capacity}u")));
    } else {
        d.push(("COMPACT", "1".into()));
        d.push(("SCAN_BLOCK", format!("{}u", ListLayout::SCAN_BLOCK)));
        // One workgroup per block in x.
        let max = device.limits().max_compute_workgroups_per_dimension;
        if blocks > max {
            return Err(super::pass_error(
                &sp.name,
                format!(
                    "{} lists need {blocks} scan workgroups, over the device's {max}: use larger tiles or fewer clusters",
                    layout.lists()
                ),
            ));
        }
    }
    // Compact lists: a (sum, wrapped) pair per scan block, and per run the uniforms
    // (`CompactParams`: phase, scratch slot).
    let scratch = layout.scratch_per_list();
    let phase = |p: u32| {
        use wgpu::util::DeviceExt;
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("compact list params"),
            contents: bytemuck::cast_slice(&[p, scratch, 0, 0]),
            usage: wgpu::BufferUsages::UNIFORM,
        })
    };
    let block_sums = (blocks > 0)
        .then(|| {
            create_internal_buffer(
                &device,
                &sp.name,
                &wgpu::BufferDescriptor {
                    label: Some("light list block sums"),
                    size: 8 * blocks as u64,
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                },
            )
        })
        .transpose()?;
    if let Some(b) = &block_sums {
        offered.buffer("list_block_sums", b);
        offered.buffer("compact", &phase(0));
    }
    let key_with = |d: &[(&str, String)], state: &str| PipelineKey {
        shader: "cull/light_culling.wgsl".into(),
        defines: defines(d),
        virtual_code: BTreeMap::new(),
        state: state.to_string(),
    };
    let key = |state: &str| key_with(&d, state);
    let (pipeline, bind) = cx.compute_pipeline(&sp.name, key(""), "main", &offered)?;
    let compact = if let Some(block_sums) = block_sums {
        // The same pipeline (a cache hit) bound with the fill phase.
        offered.buffer("compact", &phase(1));
        let (_, fill) = cx.compute_pipeline(&sp.name, key(""), "main", &offered)?;
        let (scan_lists, _) =
            cx.compute_pipeline(&sp.name, key("scan_lists"), "scan_lists", &offered)?;
        Some(Compact {
            fill,
            scan_lists,
            block_sums,
            blocks,
        })
    } else {
        None
    };
    let (bounds_pipeline, _) = cx.compute_pipeline(&sp.name, key("bounds"), "bounds", &offered)?;
    let bounds = (
        bounds_pipeline,
        super::grid(
            u32::try_from(light_capacity).unwrap_or(u32::MAX),
            BOUNDS_GROUP,
            device.limits().max_compute_workgroups_per_dimension,
        ),
    );
    let coarse = if coarse > 1 {
        let (pipeline, _) = cx.compute_pipeline(&sp.name, key("coarse"), "coarse", &offered)?;
        Some((pipeline, coarse_groups))
    } else {
        None
    };
    // The wide stage: the coarse stage's code over wide tiles (WIDE_PASS).
    let wide = if wide > 1 {
        let mut wide_defines = d.clone();
        wide_defines.push(("WIDE_PASS", "1".into()));
        let key = key_with(&wide_defines, "wide");
        let (pipeline, _) = cx.compute_pipeline(&sp.name, key, "coarse", &offered)?;
        Some((pipeline, wide_groups))
    } else {
        None
    };
    let report_copy = create_internal_buffer(
        &device,
        &sp.name,
        &wgpu::BufferDescriptor {
            label: Some("light list entries (report)"),
            size: 4 * layout.pool_offset_words() as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        },
    )?;
    Ok(LightCullingPass {
        bounds,
        wide,
        timed_dispatch: std::env::var("LIGHTGRAPH_TIME_DISPATCH")
            .ok()
            .and_then(|v| v.parse().ok()),
        name: sp.name.clone(),
        report_copy,
        coarse,
        pipeline,
        bind,
        groups: [layout.tiles_x, layout.tiles_y, layout.lists_per_tile],
        compact,
        lists,
        layout,
    })
}

impl PreparedPass for LightCullingPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        // Header words (pool cursor or wanted total, and counters) start at zero.
        encoder.clear_buffer(&self.lists, 0, Some(16));
        if let Some(c) = &self.compact {
            encoder.clear_buffer(&c.block_sums, 0, None);
        }
        // Bounds, wide, coarse, count, then (compact) scan, fill. Each dispatch sees the
        // previous one's writes: wgpu puts a barrier between dispatches that use a buffer
        // read-write. The fill's workgroups of lists that fit their scratch slot return
        // at once. (An indirect fill of only the longer lists was measured on the H200:
        // its empty dispatch, the argument copy and the second pass cost what the early
        // returns do, 0.010 against 0.012 ms, and culling as a whole came out slower.)
        let [x, y, z] = self.groups;
        let mut steps: Vec<(&wgpu::ComputePipeline, &wgpu::BindGroup, [u32; 3])> =
            vec![(&self.bounds.0, &self.bind, self.bounds.1)];
        for (stage, groups) in [&self.wide, &self.coarse].into_iter().flatten() {
            steps.push((stage, &self.bind, *groups));
        }
        steps.push((&self.pipeline, &self.bind, [x, y, z]));
        if let Some(c) = &self.compact {
            steps.push((&c.scan_lists, &self.bind, [c.blocks, 1, 1]));
            steps.push((&self.pipeline, &c.fill, [x, y, z]));
        }
        // One compute pass, timed; or (diagnosis, `LIGHTGRAPH_TIME_DISPATCH=n`) three,
        // the timestamps around dispatch n alone.
        let timed = self.timed_dispatch.filter(|&n| n < steps.len());
        let runs = match timed {
            None => vec![(0..steps.len(), Some(ts))],
            Some(n) => vec![
                (0..n, None),
                (n..n + 1, Some(ts)),
                (n + 1..steps.len(), None),
            ],
        };
        for (range, ts) in runs {
            if range.is_empty() {
                continue;
            }
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&self.name),
                timestamp_writes: ts.and_then(|t| t.compute()),
            });
            for (pipeline, bind, [x, y, z]) in &steps[range] {
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, *bind, &[]);
                pass.dispatch_workgroups(*x, *y, *z);
            }
        }
        encoder.copy_buffer_to_buffer(
            &self.lists,
            0,
            &self.report_copy,
            0,
            self.report_copy.size(),
        );
    }

    fn report(&self, r: &Renderer) -> Result<Option<PassReport>, RenderError> {
        let words = read_buffer(&r.ctx.device, &r.ctx.queue, &self.report_copy)?;
        let words: &[u32] = bytemuck::cast_slice(&words);
        let entry = |l: usize, w: u32| {
            words[(ListLayout::HEADER_WORDS + ListLayout::ENTRY_WORDS * l as u32 + w) as usize]
        };
        let counts: Vec<u32> = (0..self.layout.lists() as usize)
            .map(|l| entry(l, 1))
            .collect();
        let compact = self.compact.is_some();
        // Compact lists: a list of 1..=scratch lights lies in its own scratch slot (slot l
        // at l·scratch); every other list lies after all slots, back to back in list
        // order: its offset is the slots' end plus the kept counts of the lists before it
        // there (also past the bound, where offsets stop at its end).
        let mut misplaced_lists = 0;
        let mut scratch_held = 0u64;
        if compact {
            let scratch = self.layout.scratch_per_list() as u64;
            let slots_end = self.layout.scratch_indices();
            let mut running = slots_end;
            for (l, &c) in counts.iter().enumerate() {
                let (offset, c) = (entry(l, 0) as u64, c as u64);
                if offset < slots_end {
                    misplaced_lists +=
                        (offset != l as u64 * scratch || c == 0 || c > scratch) as u32;
                    scratch_held += c;
                } else {
                    misplaced_lists += (offset != running) as u32;
                    running += c;
                }
            }
            misplaced_lists += (running > self.layout.pool_indices()) as u32;
        }
        Ok(Some(PassReport::Culling(CullingReport {
            pass: self.name.to_string(),
            layout: self.layout,
            overflowed_lists: words[1],
            longest_list: words[2],
            // Header word 0: what the lists past their slots wanted.
            wanted: compact.then_some(words[0] as u64 + scratch_held),
            scratch_held,
            mismatched_lists: if compact { words[3] } else { 0 },
            misplaced_lists,
            counts,
        })))
    }
}
