//! `Fullscreen`: a fragment shader the graph names over a full-screen triangle, into
//! the pass's one render target; bound by reflected binding names (auto layout).

use super::compute::bind_generic;
use super::{pass_error, PrepareCtx, PreparedPass, Timestamps};
use crate::graph::Name;
use crate::graph::{ResourceDesc, ScheduledPass};
use crate::render::draws::color_attachment;
use crate::render::pipelines::{Pipeline, PipelineKey};
use crate::render::RenderError;
use std::collections::BTreeMap;
use std::sync::Arc;

pub(super) struct FullscreenPass {
    name: Name,
    pipeline: Arc<wgpu::RenderPipeline>,
    bind: wgpu::BindGroup,
    target: wgpu::TextureView,
    clear: bool,
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    shader: &str,
    entry: &str,
) -> Result<FullscreenPass, RenderError> {
    let target = sp
        .roles
        .target
        .clone()
        .ok_or_else(|| pass_error(&sp.name, "no render target was resolved".into()))?;
    let (format, samples) = cx
        .graph
        .checked
        .desc
        .resources
        .iter()
        .find_map(|r| match r {
            ResourceDesc::Texture {
                name,
                format,
                samples,
                ..
            } if *name == target => Some((format.to_wgpu(), *samples)),
            _ => None,
        })
        .ok_or_else(|| pass_error(&sp.name, format!("'{target}' is not a texture")))?;
    let device = cx.device();
    let key = PipelineKey {
        shader: shader.to_string(),
        defines: BTreeMap::new(),
        virtual_code: BTreeMap::new(),
        state: format!("fullscreen entry={entry} format={format:?} samples={samples}"),
    };
    // The user's fragment shader, with the built-in full-screen triangle appended.
    let vs_text = cx
        .renderer
        .shaders
        .read_source("common/fullscreen_vs.wgsl")
        .map_err(|e| pass_error(&sp.name, e.to_string()))?;
    let (pipeline, bindings) = cx.render_pipeline(&sp.name, key, |c, _, _| {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(shader),
            source: wgpu::ShaderSource::Wgsl(format!("{}\n{vs_text}", c.text).into()),
        });
        Pipeline::Render(Arc::new(device.create_render_pipeline(
            &wgpu::RenderPipelineDescriptor {
                label: Some(&sp.name),
                layout: None,
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("lightgraph_fullscreen_vs"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: Default::default(),
                depth_stencil: None,
                multisample: wgpu::MultisampleState {
                    count: samples,
                    ..Default::default()
                },
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    targets: &[Some(format.into())],
                }),
                multiview_mask: None,
                cache: crate::render::pipelines::driver_cache().as_ref(),
            },
        )))
    })?;
    let bind = bind_generic(cx, sp, &pipeline.get_bind_group_layout(0), &bindings)?;
    Ok(FullscreenPass {
        name: sp.name.clone(),
        pipeline,
        bind,
        target: cx.view(&sp.name, &target)?,
        clear: sp.clears(&target),
    })
}

impl PreparedPass for FullscreenPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        let clear = self.clear.then_some(wgpu::Color::TRANSPARENT);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&self.name),
            color_attachments: &[Some(color_attachment(&self.target, clear, None))],
            depth_stencil_attachment: None,
            timestamp_writes: ts.render(),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind, &[]);
        pass.draw(0..3, 0..1);
    }
}
