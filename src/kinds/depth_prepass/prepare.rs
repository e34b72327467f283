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
    let target = cx.view(&sp.name, depth)?;
    let clear = sp.clears(depth);
    prepare_meshes_into(cx, sp, set, target, clear)
}

/// The depth-only draw of one mesh set into `depth` (cleared first where `clear`): the
/// pass's own depth, or a fallback's internal Depth32Float.
pub(super) fn prepare_meshes_into(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    set: MeshSet,
    depth: wgpu::TextureView,
    clear: bool,
) -> Result<DepthPrepass, RenderError> {
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
        depth,
        clear,
        draws,
    })
}

impl DepthPrepass {
    /// The draws, in one render pass with `timestamps`.
    pub(super) fn record_with(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&self.name),
            color_attachments: &[],
            depth_stencil_attachment: Some(depth_attachment(&self.depth, self.clear)),
            timestamp_writes: timestamps,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        self.draws.record(&mut pass);
    }
}

impl PreparedPass for DepthPrepass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        self.record_with(encoder, ts.render());
    }
}
