//! `LightLinkedList`: one compute dispatch over the list pixels builds every pixel's
//! linked list; reports the links wanted and dropped and the longest list.

use super::{defines, pass_error, PrepareCtx, PreparedPass, Timestamps};
use crate::gpu::readback::read_buffer_range;
use crate::gpu::structs::GpuLinkParams;
use crate::graph::kinds::light_linked_list::{LinkLayout, LIGHT_LINKS};
use crate::graph::Name;
use crate::graph::{slot, LightLinkedList, ScheduledPass};
use crate::render::pipelines::PipelineKey;
use crate::render::report::{LinkReport, PassReport};
use crate::render::{RenderError, Renderer};
use std::collections::BTreeMap;
use std::sync::Arc;

pub(super) struct LightLinkedListPass {
    name: Name,
    pipeline: Arc<wgpu::ComputePipeline>,
    bind: wgpu::BindGroup,
    groups: [u32; 3],
    links: wgpu::Buffer,
    layout: LinkLayout,
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    p: &LightLinkedList,
) -> Result<LightLinkedListPass, RenderError> {
    let layout = p.link_layout(cx.size.width, cx.size.height);
    let links = cx.buffer(&sp.name, sp.required(LIGHT_LINKS))?;
    let params = GpuLinkParams::new(&layout).ok_or_else(|| {
        pass_error(
            &sp.name,
            format!(
                "a pool of {} links at {}×{} list pixels is past what u32 link indices address: lower links_per_pixel or raise scale",
                layout.pool, layout.width, layout.height
            ),
        )
    })?;
    let mut offered = cx.declared(sp)?;
    offered.buffer("link_params", &params.buffer(&cx.device()));
    let mut d = vec![("SCALE", format!("{}u", layout.scale))];
    if cx.float_depth(sp.required(slot::DEPTH)) {
        d.push(("FLOAT_DEPTH", "1".into()));
    }
    if let Some(lists) = sp.roles.slot(slot::LIGHT_LISTS) {
        let tiles = cx.graph.plan.list_layout(lists).ok_or_else(|| {
            pass_error(
                &sp.name,
                format!("'{lists}' is not the tile lists of a LightCulling pass: the linked list reads its candidates from them"),
            )
        })?;
        // One list a tile, its tile a multiple of the scale: checked by validation.
        offered.buffer(
            "list_params",
            &crate::gpu::structs::GpuListParams::new(&tiles).buffer(&cx.device()),
        );
        d.push(("LIGHT_LISTS", "1".into()));
    }
    let key = PipelineKey {
        shader: "cull/light_linked_list.wgsl".into(),
        defines: defines(&d),
        virtual_code: BTreeMap::new(),
        state: String::new(),
    };
    let (pipeline, bind) = cx.compute_pipeline(&sp.name, key, "main", &offered)?;
    Ok(LightLinkedListPass {
        name: sp.name.clone(),
        pipeline,
        bind,
        groups: [layout.width.div_ceil(8), layout.height.div_ceil(8), 1],
        links,
        layout,
    })
}

impl PreparedPass for LightLinkedListPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        // The counters start at zero each frame; every head is written by the build.
        encoder.clear_buffer(&self.links, 0, Some(4 * LinkLayout::HEADER_WORDS));
        super::dispatch(
            encoder,
            &self.name,
            ts,
            &self.pipeline,
            &self.bind,
            self.groups,
        );
    }

    fn report(&self, r: &Renderer) -> Result<Option<PassReport>, RenderError> {
        let bytes = read_buffer_range(
            &r.ctx.device,
            &r.ctx.queue,
            &self.links,
            0,
            4 * LinkLayout::HEADER_WORDS,
        )?;
        let w: &[u32] = bytemuck::cast_slice(&bytes);
        Ok(Some(PassReport::Links(LinkReport {
            pass: self.name.to_string(),
            layout: self.layout,
            links_wanted: w[0] as u64,
            links_dropped: w[1] as u64,
            overflow_pixels: w[2] as u64,
            longest_list: w[3],
        })))
    }
}
