//! `TransparentShading`: every blended mesh through its material and the light loop,
//! back to front by the view depth of its bounds' centre, alpha-blended over the colour
//! target, tested against the opaque depth (not written): as a read-only depth
//! attachment, or (an R32Float depth, a compute resolve's) in the fragment shader, with
//! no depth attachment. The order follows the camera (`set_view`). Reading the BVH, each
//! fragment traces its own shadow rays.

use super::{pass_error, PrepareCtx, PreparedPass, Timestamps};
use crate::graph::Name;
use crate::graph::{slot, ScheduledPass, TransparentShading};
use crate::render::draws::{color_attachment, depth_attachment, DrawMode, MeshDraws, MeshSet};
use crate::render::scene_gpu::SceneGpu;
use crate::render::{RenderError, Renderer};
use crate::scene::Camera;
use std::sync::Mutex;

pub(super) struct TransparentShadingPass {
    name: Name,
    color: wgpu::TextureView,
    /// The depth attachment; None where the shader tests an R32Float depth itself.
    depth: Option<wgpu::TextureView>,
    clear: bool,
    draws: MeshDraws,
    gpu: SceneGpu,
    /// Draw indices, back to front for the current camera.
    order: Mutex<Vec<usize>>,
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    p: &TransparentShading,
) -> Result<TransparentShadingPass, RenderError> {
    let color = sp.required(slot::COLOR);
    let depth = sp.required(slot::DEPTH);
    if !cx
        .device()
        .features()
        .contains(wgpu::Features::FLOAT32_BLENDABLE)
    {
        return Err(pass_error(
            &sp.name,
            "blending into an Rgba32Float target needs the adapter's FLOAT32_BLENDABLE feature, which it lacks".into(),
        ));
    }
    let mut offered = cx.declared(sp)?;
    let lists = cx.shading_lists(sp, p.lights, &mut offered)?;
    // Validation keeps an R32Float depth single-sample, as the colour target.
    let float_depth = cx.float_depth(depth);
    // Validation admits the BVH (traced in the light loop) as the only shadow source.
    let shadows = cx.shading_shadows(sp, &mut offered);
    let mode = DrawMode::Shade {
        lists,
        blend: true,
        shadows,
        float_depth,
        vpl_visibility: None,
        vpls: cx.scene.features().has_indirect_lights,
    };
    let draws = cx.renderer.mesh_draws(
        cx.gpu,
        mode,
        MeshSet::Transparent,
        sp.samples,
        &sp.name,
        &offered,
    )?;
    let order = draws.back_to_front(cx.gpu, &cx.scene.camera.view());
    Ok(TransparentShadingPass {
        name: sp.name.clone(),
        color: cx.view(&sp.name, color)?,
        depth: if float_depth {
            None
        } else {
            Some(cx.view(&sp.name, depth)?)
        },
        clear: sp.clears(color),
        draws,
        gpu: cx.gpu.clone(),
        order: Mutex::new(order),
    })
}

impl PreparedPass for TransparentShadingPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        let clear = self.clear.then_some(wgpu::Color::TRANSPARENT);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&self.name),
            color_attachments: &[Some(color_attachment(&self.color, clear, None))],
            depth_stencil_attachment: self.depth.as_ref().map(|d| depth_attachment(d, false)),
            timestamp_writes: ts.render(),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let order = self.order.lock().unwrap_or_else(|e| e.into_inner()).clone();
        self.draws.record_in_order(&mut pass, order);
    }

    fn set_view(&self, _r: &Renderer, camera: &Camera) {
        let order = self.draws.back_to_front(&self.gpu, &camera.view());
        *self.order.lock().unwrap_or_else(|e| e.into_inner()) = order;
    }
}
