//! `ForwardShading`: every opaque mesh through its material and the light loop, over
//! the prepass depth (tested, not written).

use super::{PrepareCtx, PreparedPass, Timestamps};
use crate::graph::Name;
use crate::graph::{slot, ForwardShading, ScheduledPass};
use crate::render::draws::{color_attachment, depth_attachment, DrawMode, MeshDraws, MeshSet};
use crate::render::RenderError;

pub(super) struct ForwardShadingPass {
    name: Name,
    color: wgpu::TextureView,
    depth: wgpu::TextureView,
    clear: bool,
    draws: MeshDraws,
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    p: &ForwardShading,
) -> Result<ForwardShadingPass, RenderError> {
    let color = sp.required(slot::COLOR);
    let depth = sp.required(slot::DEPTH);
    let mut offered = cx.declared(sp)?;
    let lists = cx.shading_lists(sp, p.lights, &mut offered)?;
    let shadows = cx.shading_shadows(sp, &mut offered);
    let mode = DrawMode::Shade {
        lists,
        blend: false,
        shadows,
        float_depth: false,
        vpl_visibility: super::VplLookup::of(cx, sp),
        vpls: cx.scene.features().has_indirect_lights,
    };
    let draws = cx.renderer.mesh_draws(
        cx.gpu,
        mode,
        MeshSet::Opaque,
        sp.samples,
        &sp.name,
        &offered,
    )?;
    Ok(ForwardShadingPass {
        name: sp.name.clone(),
        color: cx.view(&sp.name, color)?,
        depth: cx.view(&sp.name, depth)?,
        clear: sp.clears(color),
        draws,
    })
}

impl PreparedPass for ForwardShadingPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        let clear = self.clear.then_some(wgpu::Color::TRANSPARENT);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&self.name),
            color_attachments: &[Some(color_attachment(&self.color, clear, None))],
            depth_stencil_attachment: Some(depth_attachment(&self.depth, false)),
            timestamp_writes: ts.render(),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        self.draws.record(&mut pass);
    }
}
