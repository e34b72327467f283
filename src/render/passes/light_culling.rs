//! `LightCulling`: per-tile light lists, with an optional coarse stage first in the same
//! compute pass; reports each frame's overflows and longest list.

use super::{defines, PrepareCtx, PreparedPass, Timestamps};
use crate::gpu::readback::read_buffer;
use crate::graph::Name;
use crate::graph::{slot, LightCulling, ListLayout, ScheduledPass};
use crate::render::pipelines::PipelineKey;
use crate::render::report::{CullingReport, PassReport};
use crate::render::{RenderError, Renderer};
use std::collections::BTreeMap;
use std::sync::Arc;

/// Most lights a coarse culling tile lists; a tile with more sends its fine tiles back
/// to testing every light.
const COARSE_CAPACITY: u64 = 8192;

pub(super) struct LightCullingPass {
    name: Name,
    /// The coarse stage, run first in the same pass.
    coarse: Option<(Arc<wgpu::ComputePipeline>, [u32; 3])>,
    pipeline: Arc<wgpu::ComputePipeline>,
    bind: wgpu::BindGroup,
    groups: [u32; 3],
    lists: wgpu::Buffer,
    /// The header and list entries, copied out after culling: the report reads these,
    /// since a later pass may reuse the lists' memory (aliasing) before it is read.
    report_copy: wgpu::Buffer,
    layout: ListLayout,
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
    let coarse_lists = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("coarse light lists"),
        size: coarse_words * 4,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let mut offered = cx.declared(sp)?;
    offered.buffer(
        "list_params",
        &crate::gpu::structs::GpuListParams::new(&layout).buffer(&device),
    );
    offered.buffer("coarse_lists", &coarse_lists);
    let mut d = vec![
        ("TILE", format!("{}u", p.tile)),
        ("CAPACITY", format!("{}u", p.capacity)),
        ("VARIANT", format!("{}u", p.variant.code())),
        ("COARSE", format!("{coarse}u")),
        ("COARSE_CAPACITY", format!("{COARSE_CAPACITY}u")),
        // Every sample of a multisampled depth bounds the tile.
        ("SAMPLES", format!("{}u", sp.samples)),
    ];
    if sp.samples > 1 {
        d.push(("MSAA", "1".into()));
    }
    if sp.roles.slot(slot::TRANSPARENT_DEPTH).is_some() {
        d.push(("TRANSPARENT", "1".into()));
    }
    let key = |state: &str| PipelineKey {
        shader: "cull/light_culling.wgsl".into(),
        defines: defines(&d),
        virtual_code: BTreeMap::new(),
        state: state.to_string(),
    };
    let (pipeline, bind) = cx.compute_pipeline(&sp.name, key(""), "main", &offered)?;
    let coarse = if coarse > 1 {
        let (pipeline, _) = cx.compute_pipeline(&sp.name, key("coarse"), "coarse", &offered)?;
        Some((pipeline, coarse_groups))
    } else {
        None
    };
    let report_copy = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("light list entries (report)"),
        size: 4 * layout.pool_offset_words() as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    Ok(LightCullingPass {
        name: sp.name.clone(),
        report_copy,
        coarse,
        pipeline,
        bind,
        groups: [layout.tiles_x, layout.tiles_y, layout.lists_per_tile],
        lists,
        layout,
    })
}

impl PreparedPass for LightCullingPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        // Header words (pool cursor and overflow counters) start at zero.
        encoder.clear_buffer(&self.lists, 0, Some(16));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&self.name),
            timestamp_writes: ts.compute(),
        });
        pass.set_bind_group(0, &self.bind, &[]);
        if let Some((coarse, [x, y, z])) = &self.coarse {
            pass.set_pipeline(coarse);
            pass.dispatch_workgroups(*x, *y, *z);
        }
        pass.set_pipeline(&self.pipeline);
        let [x, y, z] = self.groups;
        pass.dispatch_workgroups(x, y, z);
        drop(pass);
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
        let counts = (0..self.layout.lists() as usize)
            .map(|l| {
                words[(ListLayout::HEADER_WORDS + ListLayout::ENTRY_WORDS * l as u32 + 1) as usize]
            })
            .collect();
        Ok(Some(PassReport::Culling(CullingReport {
            pass: self.name.to_string(),
            layout: self.layout,
            overflowed_lists: words[1],
            longest_list: words[2],
            counts,
        })))
    }
}
