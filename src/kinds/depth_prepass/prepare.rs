//! `DepthPrepass`: every opaque mesh, depth only.

use super::{PrepareCtx, PreparedPass, Timestamps};
use crate::graph::Name;
use crate::graph::{slot, ScheduledPass};
use crate::render::draws::{depth_attachment, DrawMode, MeshDraws, MeshSet};
use crate::render::RenderError;

pub(super) struct DepthPrepass {
    name: Name,
    depth: wgpu::TextureView,
    clear: bool,
    draws: MeshDraws,
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
) -> Result<DepthPrepass, RenderError> {
    prepare_meshes(cx, sp, MeshSet::Opaque)
}

/// The depth-only draw of one mesh set (`TransparentDepth` draws the blended one).
pub(super) fn prepare_meshes(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    set: MeshSet,
) -> Result<DepthPrepass, RenderError> {
    let depth = sp.required(slot::DEPTH);
    let offered = cx.declared(sp)?;
    let draws = cx.renderer.mesh_draws(
        cx.gpu,
        DrawMode::DepthOnly,
        set,
        sp.samples,
        &sp.name,
        &offered,
    )?;
    Ok(DepthPrepass {
        name: sp.name.clone(),
        depth: cx.view(&sp.name, depth)?,
        clear: sp.clears(depth),
        draws,
    })
}

impl PreparedPass for DepthPrepass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&self.name),
            color_attachments: &[],
            depth_stencil_attachment: Some(depth_attachment(&self.depth, self.clear)),
            timestamp_writes: ts.render(),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        self.draws.record(&mut pass);
    }
}
