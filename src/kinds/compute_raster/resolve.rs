//! The last step of `ComputeRaster`: its per-pixel `u64` buffer (`vis`) into the depth and
//! id textures. A Depth32Float depth is written by a full-screen draw (`frag_depth`:
//! compute cannot store depth formats), for graphs whose later passes test against it;
//! an R32Float depth by a compute dispatch at the end of the rasterizer's compute pass
//! (`shaders/visibility/compute_raster_resolve.wgsl`), so the frame has no vertex or
//! fragment work (the draw alone costs ~0.3 ms on the H200, whose graphics run on few
//! SMs). Both write the same bits: the depth unchanged, 1.0 and `NO_TRIANGLE` where
//! nothing was drawn (`tests/compute_raster.rs`).

use super::{defines, pass_error, BindingSet, PrepareCtx, Timestamps};
use crate::graph::kinds::compute_raster::VISIBILITY;
use crate::graph::{slot, ScheduledPass};
use crate::render::bind::layout_entries;
use crate::render::draws::{color_attachment, depth_attachment};
use crate::render::pipelines::{Pipeline, PipelineKey};
use crate::render::RenderError;
use std::collections::BTreeMap;
use std::sync::Arc;

const COMPUTE_SHADER: &str = "visibility/compute_raster_resolve.wgsl";
/// The compute resolve's workgroup side (8×8 pixels).
const TILE: u32 = 8;

/// What the compute resolve writes of the blended triangles the run drew with the opaque
/// ones.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Glass {
    None,
    /// `glass_depth` into `transparent_depth`.
    Nearest,
    /// And `glass_far` into `transparent_far`.
    NearestAndFarthest,
}

pub(super) enum Resolve {
    /// Depth32Float: a full-screen triangle into the depth and id attachments.
    Draw {
        pipeline: Arc<wgpu::RenderPipeline>,
        bind: wgpu::BindGroup,
        depth: wgpu::TextureView,
        visibility: wgpu::TextureView,
    },
    /// R32Float: one dispatch of 8×8-pixel workgroups storing both textures.
    Compute {
        pipeline: Arc<wgpu::ComputePipeline>,
        bind: wgpu::BindGroup,
        groups: [u32; 3],
    },
}

impl Resolve {
    /// The resolve the pass's depth format asks for; `draw_key` is the rasterizer
    /// shader's full-screen resolve (`RESOLVE`). `offered` holds the pass's slots, the
    /// frame uniform and the `vis` buffer. Without `ids` (the blended triangles' depth)
    /// only the depth is written, and it must be R32Float. With `glass` (an R32Float
    /// depth only) the blended triangles' buffers go into their textures too.
    pub fn prepare(
        cx: &mut PrepareCtx,
        sp: &ScheduledPass,
        draw_key: PipelineKey,
        offered: &BindingSet,
        ids: bool,
        glass: Glass,
    ) -> Result<Self, RenderError> {
        let depth = sp.required(slot::DEPTH);
        if cx.float_depth(depth) {
            let mut options = Vec::new();
            if !ids {
                options.push(("DEPTH_ONLY", "1".to_string()));
            }
            if glass != Glass::None {
                options.push(("GLASS", "1".to_string()));
            }
            if glass == Glass::NearestAndFarthest {
                options.push(("GLASS_FAR", "1".to_string()));
            }
            let key = PipelineKey {
                shader: COMPUTE_SHADER.into(),
                defines: defines(&options),
                virtual_code: BTreeMap::new(),
                state: "resolve".into(),
            };
            let (pipeline, bind) = cx.compute_pipeline(&sp.name, key, "resolve", offered)?;
            return Ok(Resolve::Compute {
                pipeline,
                bind,
                groups: [
                    cx.size.width.div_ceil(TILE),
                    cx.size.height.div_ceil(TILE),
                    1,
                ],
            });
        }
        if glass != Glass::None {
            return Err(pass_error(
                &sp.name,
                format!("the compute rasterizer writes the blended triangles' depth beside an R32Float depth only, and '{depth}' is a depth format"),
            ));
        }
        if !ids {
            return Err(pass_error(
                &sp.name,
                format!("the compute rasterizer resolves a depth of its own into R32Float only, and '{depth}' is a depth format"),
            ));
        }
        let (pipeline, bind) = draw_pipeline(cx, sp, draw_key, offered)?;
        Ok(Resolve::Draw {
            pipeline,
            bind,
            depth: cx.view(&sp.name, depth)?,
            visibility: cx.view(&sp.name, sp.required(VISIBILITY))?,
        })
    }

    /// The rasterizer's compute pass's timestamps: both ends where the resolve is a
    /// dispatch in it, the start only where the draw after it writes the end.
    pub fn compute_timestamps<'a>(
        &self,
        ts: Timestamps<'a>,
    ) -> Option<wgpu::ComputePassTimestampWrites<'a>> {
        match self {
            Resolve::Compute { .. } => ts.compute(),
            Resolve::Draw { .. } => ts.compute().map(|t| wgpu::ComputePassTimestampWrites {
                end_of_pass_write_index: None,
                ..t
            }),
        }
    }

    /// The compute resolve, last in the rasterizer's compute pass (wgpu puts a barrier
    /// between it and the dispatches that wrote `vis`). Nothing for the draw.
    pub fn dispatch(&self, pass: &mut wgpu::ComputePass<'_>) {
        if let Resolve::Compute {
            pipeline,
            bind,
            groups: [x, y, z],
        } = self
        {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, bind, &[]);
            pass.dispatch_workgroups(*x, *y, *z);
        }
    }

    /// The draw resolve, after the rasterizer's compute pass, closing its timestamps.
    /// Nothing for the compute resolve.
    pub fn draw(&self, encoder: &mut wgpu::CommandEncoder, label: &str, ts: Timestamps<'_>) {
        let Resolve::Draw {
            pipeline,
            bind,
            depth,
            visibility,
        } = self
        else {
            return;
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[Some(color_attachment(
                visibility,
                Some(wgpu::Color::TRANSPARENT),
                None,
            ))],
            depth_stencil_attachment: Some(depth_attachment(depth, true)),
            timestamp_writes: ts.render().map(|t| wgpu::RenderPassTimestampWrites {
                beginning_of_pass_write_index: None,
                ..t
            }),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, bind, &[]);
        pass.draw(0..3, 0..1);
    }
}

/// The full-screen draw that writes depth (`frag_depth`) and ids from the buffer.
fn draw_pipeline(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    key: PipelineKey,
    offered: &BindingSet,
) -> Result<(Arc<wgpu::RenderPipeline>, wgpu::BindGroup), RenderError> {
    let device = cx.device();
    let layouts = cx.renderer.layouts.clone();
    let stages = wgpu::ShaderStages::FRAGMENT;
    let (pipeline, bindings) = cx.render_pipeline(&sp.name, key, |_, module, bindings| {
        let bgl = layouts.get(&device, layout_entries(bindings, 0, stages));
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(&sp.name),
            bind_group_layouts: &[Some(&bgl)],
            immediate_size: 0,
        });
        Pipeline::Render(Arc::new(device.create_render_pipeline(
            &wgpu::RenderPipelineDescriptor {
                label: Some(&sp.name),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("resolve_vs"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: Default::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: wgpu::TextureFormat::Depth32Float,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Always),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("resolve_fs"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::TextureFormat::R32Uint.into())],
                }),
                multiview_mask: None,
                cache: crate::render::pipelines::driver_cache().as_ref(),
            },
        )))
    })?;
    let bgl = layouts.get(&device, layout_entries(&bindings, 0, stages));
    let bind = offered
        .bind(&device, &sp.name, &bgl, &bindings, 0)
        .map_err(|m| pass_error(&sp.name, m))?;
    Ok((pipeline, bind))
}
