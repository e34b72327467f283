//! Draws a graph's HDR output into a colour target (the viewer's window, or an embedding
//! application's texture): scaled to the target's size and tonemapped exactly like the
//! CLI's PNG output (`shaders/view/present.wgsl`).

use super::bind::{layout_entries, BindingSet, Bound};
use super::Renderer;
use crate::shader::{reflect_bindings, ReflectedBinding, ShaderError};
use std::collections::BTreeMap;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PresentParams {
    exposure_scale: f32,
    _pad: f32,
    target_size: [f32; 2],
}

/// What the present pass offers its shader, by binding name.
const OFFERED: [&str; 2] = ["hdr", "params"];

/// Draws a graph's HDR output into a colour target, scaled and tonemapped like the PNG
/// output (for windows and embedding applications).
pub struct Presenter {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    bindings: Vec<ReflectedBinding>,
    params: wgpu::Buffer,
}

impl Presenter {
    /// Builds the present pipeline for a target of `format` (a window's, or any colour
    /// texture of the caller's), with the renderer's shaders and driver pipeline cache.
    pub fn new(renderer: &Renderer, format: wgpu::TextureFormat) -> Result<Self, ShaderError> {
        let (device, shaders) = (&renderer.ctx.device, &renderer.shaders);
        let defines =
            BTreeMap::from([("SRGB_ENCODE".to_string(), (!format.is_srgb()).to_string())]);
        let composed = shaders.compose("view/present.wgsl", &defines, &BTreeMap::new())?;
        // Bound by the reflected binding names, as every pass's shader is.
        let bindings = reflect_bindings(&composed.validate()?);
        if let Some(b) = bindings
            .iter()
            .find(|b| !OFFERED.contains(&b.name.as_str()))
        {
            // A project's own present.wgsl may declare anything: name the line.
            let declared = |l: &&str| l.contains("var") && l.contains(&format!(" {}:", b.name));
            let at = composed
                .text
                .lines()
                .position(|l| declared(&l))
                .unwrap_or(0);
            let (file, line) = composed.origin.get(at).cloned().unwrap_or_default();
            return Err(ShaderError::Directive {
                file,
                line,
                message: format!(
                    "the present pass binds '{}'; it offers only {OFFERED:?}",
                    b.name
                ),
            });
        }
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("present"),
            source: wgpu::ShaderSource::Wgsl(composed.text.into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("present"),
            entries: &layout_entries(&bindings, 0, wgpu::ShaderStages::FRAGMENT),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("present"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("present"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("lightgraph_fullscreen_vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("present_fs"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            multiview_mask: None,
            cache: renderer.ctx.pipeline_cache.as_ref().map(|c| c.cache()),
        });
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("present params"),
            size: std::mem::size_of::<PresentParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Self {
            pipeline,
            layout,
            bindings,
            params,
        })
    }

    /// Records the draw of `hdr` (the graph's output) over all of `target`.
    #[allow(clippy::too_many_arguments)]
    pub fn draw(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        hdr: &wgpu::Texture,
        target: &wgpu::TextureView,
        target_size: [u32; 2],
        exposure_ev: f32,
    ) {
        let params = PresentParams {
            exposure_scale: exposure_ev.exp2(),
            _pad: 0.0,
            target_size: [target_size[0] as f32, target_size[1] as f32],
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let mut offered = BindingSet::default();
        offered.offer("hdr", Bound::View(hdr.create_view(&Default::default())));
        offered.buffer("params", &self.params);
        let bind = offered
            .bind(device, "present", &self.layout, &self.bindings, 0)
            .expect("new() refused shaders binding anything but OFFERED");
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("present"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.draw(0..3, 0..1);
    }
}
