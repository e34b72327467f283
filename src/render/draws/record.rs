//! Recording mesh draws into a render pass: every draw, per tile or view, or back to
//! front; and the attachments the drawing passes share.

use super::{Draw, MeshDraws, MATERIAL_GROUP};
use crate::render::scene_gpu::SceneGpu;
use std::sync::Arc;

/// One view of a multi-view draw: its viewport (a square tile) and what it sees.
pub(in crate::render) struct ViewDraw {
    pub x: u32,
    pub y: u32,
    pub tile: u32,
    /// Index ranges to draw: (draw in [`MeshDraws::meshes`] order, first index, count),
    /// sorted by draw.
    pub ranges: Vec<(usize, u32, u32)>,
}

impl MeshDraws {
    /// The scene mesh of each draw, in draw order.
    pub fn meshes(&self) -> impl Iterator<Item = usize> + '_ {
        self.draws.iter().map(|d| d.mesh)
    }

    /// Clears the viewport of each view at `which` (indices into `views`) with `clear` (a
    /// pipeline without bindings), then draws its visible meshes there with the view's
    /// index as the instance (the shader reads its projection from it).
    pub fn record_views(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        views: &[ViewDraw],
        which: &[u32],
        clear: &wgpu::RenderPipeline,
    ) {
        for &v in which {
            let view = &views[v as usize];
            let (x, y, t) = (view.x, view.y, view.tile);
            pass.set_viewport(x as f32, y as f32, t as f32, t as f32, 0.0, 1.0);
            pass.set_scissor_rect(x, y, t, t);
            pass.set_pipeline(clear);
            pass.draw(0..3, 0..1);
            let mut current: Option<*const wgpu::RenderPipeline> = None;
            if let Some(bind) = &self.bind {
                pass.set_bind_group(0, bind, &[]);
            }
            let instance = v;
            let mut bound: Option<usize> = None;
            for &(draw, first, count) in &view.ranges {
                let d = &self.draws[draw];
                d.switch_pipeline(pass, &mut current);
                if bound != Some(draw) {
                    d.bind_buffers(pass);
                    bound = Some(draw);
                }
                pass.draw_indexed(first..first + count, 0, instance..instance + 1);
            }
        }
    }

    /// Draws every mesh into each `tile`-texel viewport at `origins`, with the view's
    /// index as the instance (reflective shadow maps: a few small views, no culling).
    pub fn record_tiles(&self, pass: &mut wgpu::RenderPass<'_>, origins: &[(u32, u32)], tile: u32) {
        if let Some(bind) = &self.bind {
            pass.set_bind_group(0, bind, &[]);
        }
        let mut current: Option<*const wgpu::RenderPipeline> = None;
        for d in &self.draws {
            d.switch_pipeline(pass, &mut current);
            d.bind_buffers(pass);
            for (v, &(x, y)) in origins.iter().enumerate() {
                pass.set_viewport(x as f32, y as f32, tile as f32, tile as f32, 0.0, 1.0);
                pass.set_scissor_rect(x, y, tile, tile);
                pass.draw_indexed(0..d.index_count, 0, v as u32..v as u32 + 1);
            }
        }
    }

    /// Draws every mesh into `pass`.
    pub fn record(&self, pass: &mut wgpu::RenderPass<'_>) {
        self.record_in_order(pass, 0..self.draws.len());
    }

    /// The draws ordered back to front for `view` (farthest mesh centre first; ties
    /// in scene order, so the same view always blends the same way).
    pub fn back_to_front(&self, gpu: &SceneGpu, view: &glam::Mat4) -> Vec<usize> {
        let depth: Vec<f32> = self
            .draws
            .iter()
            .map(|d| gpu.view_depth(d.mesh, view))
            .collect();
        let mut order: Vec<usize> = (0..self.draws.len()).collect();
        order.sort_by(|&a, &b| depth[b].total_cmp(&depth[a]).then(a.cmp(&b)));
        order
    }

    /// Draws the meshes at `order` (indices into the draws) into `pass`, in that order.
    pub fn record_in_order(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        order: impl IntoIterator<Item = usize>,
    ) {
        if let Some(bind) = &self.bind {
            pass.set_bind_group(0, bind, &[]);
        }
        let mut current: Option<*const wgpu::RenderPipeline> = None;
        for d in order.into_iter().map(|i| &self.draws[i]) {
            // Opaque draws are sorted by material: switch pipelines only when it changes.
            d.switch_pipeline(pass, &mut current);
            d.bind_buffers(pass);
            pass.draw_indexed(0..d.index_count, 0, d.instance..d.instance + 1);
        }
    }
}

impl Draw {
    /// Sets this draw's pipeline and material group unless `current` already is it.
    fn switch_pipeline(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        current: &mut Option<*const wgpu::RenderPipeline>,
    ) {
        let ptr = Arc::as_ptr(&self.pipeline);
        if *current != Some(ptr) {
            pass.set_pipeline(&self.pipeline);
            *current = Some(ptr);
            if let Some(group) = &self.material {
                pass.set_bind_group(MATERIAL_GROUP, group, &[]);
            }
        }
    }

    fn bind_buffers(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
    }
}

/// A depth attachment that clears (first writer) or loads.
pub(in crate::render) fn depth_attachment(
    view: &wgpu::TextureView,
    clear: bool,
) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load: if clear {
                wgpu::LoadOp::Clear(1.0)
            } else {
                wgpu::LoadOp::Load
            },
            store: wgpu::StoreOp::Store,
        }),
        stencil_ops: None,
    }
}

/// A colour attachment that clears to `clear` or loads, resolving into `resolve` (MSAA).
pub(in crate::render) fn color_attachment<'a>(
    view: &'a wgpu::TextureView,
    clear: Option<wgpu::Color>,
    resolve: Option<&'a wgpu::TextureView>,
) -> wgpu::RenderPassColorAttachment<'a> {
    wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: resolve,
        ops: wgpu::Operations {
            load: match clear {
                Some(c) => wgpu::LoadOp::Clear(c),
                None => wgpu::LoadOp::Load,
            },
            store: wgpu::StoreOp::Store,
        },
    }
}
