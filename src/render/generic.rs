//! Generic passes (Compute, Fullscreen) and the light-statistics pass: bind groups
//! built from reflected bindings, matched by name.

use super::frame::PassExecParts;
use super::pipelines::{Pipeline, PipelineKey};
use super::resources::FrameResources;
use super::scene_gpu::SceneGpu;
use super::{RenderError, Renderer};
use crate::gpu::structs::GpuFrame;
use crate::graph::{CompiledGraph, FrameSize, ResourceDesc, SceneResource, ScheduledPass, Slot};
use std::collections::BTreeMap;
use std::sync::Arc;
use wgpu::util::DeviceExt;

impl Renderer {
    fn bind_generic(
        &self,
        graph: &CompiledGraph,
        sp: &ScheduledPass,
        layout: &wgpu::BindGroupLayout,
        resources: &FrameResources,
        frame_uniform: &wgpu::Buffer,
        gpu: &SceneGpu,
    ) -> Result<wgpu::BindGroup, RenderError> {
        let device = &self.ctx.device;
        let linear = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("linear_sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let nearest = device.create_sampler(&Default::default());
        let plan = &graph.plan;
        let mut entries = Vec::new();
        for (b, name) in &sp.roles.bindings {
            let missing = || RenderError::Pass {
                pass: sp.name.clone(),
                message: format!("binding '{name}' has no physical resource"),
            };
            let resource = match name.as_str() {
                "frame" => frame_uniform.as_entire_binding(),
                "linear_sampler" => wgpu::BindingResource::Sampler(&linear),
                "nearest_sampler" => wgpu::BindingResource::Sampler(&nearest),
                _ => match graph
                    .checked
                    .desc
                    .resources
                    .iter()
                    .find(|r| r.name() == name)
                {
                    Some(ResourceDesc::Import { from, .. }) => match from {
                        SceneResource::LightGeometry => gpu.light_geometry.as_entire_binding(),
                        SceneResource::LightProperties => gpu.light_properties.as_entire_binding(),
                        SceneResource::Geometry => return Err(missing()),
                    },
                    Some(ResourceDesc::Buffer { .. }) => resources
                        .buffer(plan, name)
                        .ok_or_else(missing)?
                        .as_entire_binding(),
                    Some(ResourceDesc::Texture { .. }) => wgpu::BindingResource::TextureView(
                        resources.view(plan, name).ok_or_else(missing)?,
                    ),
                    None => return Err(missing()),
                },
            };
            let _ = &b.kind;
            entries.push(wgpu::BindGroupEntry {
                binding: b.binding,
                resource,
            });
        }
        Ok(device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&sp.name),
            layout,
            entries: &entries,
        }))
    }

    pub(super) fn generic_compute(
        &mut self,
        graph: &CompiledGraph,
        sp: &ScheduledPass,
        resources: &FrameResources,
        frame_uniform: &wgpu::Buffer,
        gpu: &SceneGpu,
    ) -> Result<PassExecParts<wgpu::ComputePipeline>, RenderError> {
        let crate::graph::PassKind::Compute { shader, entry, .. } = &sp.kind else {
            unreachable!()
        };
        let device = self.ctx.device.clone();
        let key = PipelineKey {
            shader: shader.clone(),
            defines: BTreeMap::new(),
            virtual_code: BTreeMap::new(),
            state: format!("compute entry={entry}"),
        };
        let pipeline = self
            .pipelines
            .get_or_build(
                &self.shaders,
                key,
                |_, module| Pipeline::compute(&device, &sp.name, None, &module, entry),
                &device,
            )
            .map_err(|source| RenderError::Shader {
                pass: sp.name.clone(),
                source,
            })?;
        let Pipeline::Compute(pipeline) = pipeline else {
            unreachable!()
        };
        let bind = self.bind_generic(
            graph,
            sp,
            &pipeline.get_bind_group_layout(0),
            resources,
            frame_uniform,
            gpu,
        )?;
        Ok((pipeline, bind))
    }

    pub(super) fn generic_fullscreen(
        &mut self,
        graph: &CompiledGraph,
        sp: &ScheduledPass,
        resources: &FrameResources,
        frame_uniform: &wgpu::Buffer,
        gpu: &SceneGpu,
        target: &str,
    ) -> Result<PassExecParts<wgpu::RenderPipeline>, RenderError> {
        let crate::graph::PassKind::Fullscreen { shader, entry } = &sp.kind else {
            unreachable!()
        };
        let format = graph
            .checked
            .desc
            .resources
            .iter()
            .find_map(|r| match r {
                ResourceDesc::Texture { name, format, .. } if name == target => {
                    Some(format.to_wgpu())
                }
                _ => None,
            })
            .unwrap();
        let device = self.ctx.device.clone();
        // The user's fragment shader, with the built-in full-screen triangle appended.
        let key = PipelineKey {
            shader: shader.clone(),
            defines: BTreeMap::new(),
            virtual_code: BTreeMap::new(),
            state: format!("fullscreen entry={entry} format={format:?}"),
        };
        let vs_text = std::fs::read_to_string(self.shaders.root.join("common/fullscreen_vs.wgsl"))
            .map_err(|e| RenderError::Pass {
                pass: sp.name.clone(),
                message: format!("common/fullscreen_vs.wgsl: {e}"),
            })?;
        let pipeline = self
            .pipelines
            .get_or_build(
                &self.shaders,
                key,
                |c, _| {
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
                            multisample: Default::default(),
                            fragment: Some(wgpu::FragmentState {
                                module: &module,
                                entry_point: Some(entry),
                                compilation_options: Default::default(),
                                targets: &[Some(format.into())],
                            }),
                            multiview_mask: None,
                            cache: None,
                        },
                    )))
                },
                &device,
            )
            .map_err(|source| RenderError::Shader {
                pass: sp.name.clone(),
                source,
            })?;
        let Pipeline::Render(pipeline) = pipeline else {
            unreachable!()
        };
        let bind = self.bind_generic(
            graph,
            sp,
            &pipeline.get_bind_group_layout(0),
            resources,
            frame_uniform,
            gpu,
        )?;
        Ok((pipeline, bind))
    }

    /// The statistics pass reads the depth and light lists of the (last) shading pass.
    pub(super) fn stats_pass(
        &mut self,
        graph: &CompiledGraph,
        resources: &FrameResources,
        frame_uniform: &wgpu::Buffer,
        gpu: &SceneGpu,
        gpu_frame: &GpuFrame,
        size: FrameSize,
    ) -> Result<(Arc<wgpu::ComputePipeline>, wgpu::BindGroup, wgpu::Buffer), RenderError> {
        let device = self.ctx.device.clone();
        let shading = graph
            .passes
            .iter()
            .rev()
            .find(|p| matches!(p.kind, crate::graph::PassKind::ForwardShading { .. }))
            .ok_or_else(|| RenderError::Pass {
                pass: "light statistics".into(),
                message: "the graph has no ForwardShading pass to take statistics of".into(),
            })?;
        let depth = shading.roles.slot(Slot::Depth).unwrap();
        let lists = shading.roles.slot(Slot::LightLists);
        let mut d = BTreeMap::new();
        if lists.is_some() {
            d.insert("LIGHT_LISTS".to_string(), "1".to_string());
        }
        let key = PipelineKey {
            shader: "stats/light_stats.wgsl".into(),
            defines: d,
            virtual_code: BTreeMap::new(),
            state: String::new(),
        };
        let pipeline = self
            .pipelines
            .get_or_build(
                &self.shaders,
                key,
                |_, module| Pipeline::compute(&device, "light statistics", None, &module, "main"),
                &device,
            )
            .map_err(|source| RenderError::Shader {
                pass: "light statistics".into(),
                source,
            })?;
        let Pipeline::Compute(pipeline) = pipeline else {
            unreachable!()
        };
        let counts = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("light counts"),
            size: 8 * size.width as u64 * size.height as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let view_proj = glam::Mat4::from_cols_array_2d(&gpu_frame.view_proj);
        let inv = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("inverse view-projection"),
            contents: bytemuck::cast_slice(&view_proj.inverse().to_cols_array()),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let plan = &graph.plan;
        let depth_view = resources.view(plan, depth).unwrap();
        let mut entries = vec![
            wgpu::BindGroupEntry {
                binding: 0,
                resource: frame_uniform.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: gpu.light_geometry.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: gpu.light_properties.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: wgpu::BindingResource::TextureView(depth_view),
            },
            wgpu::BindGroupEntry {
                binding: 5,
                resource: counts.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 6,
                resource: inv.as_entire_binding(),
            },
        ];
        let list_buffers = match lists {
            Some(lists) => Some(
                super::frame::list_buffers(graph, resources, lists, size, &device).map_err(
                    |message| RenderError::Pass {
                        pass: "light statistics".into(),
                        message,
                    },
                )?,
            ),
            None => None,
        };
        if let Some((buf, params)) = &list_buffers {
            entries.push(wgpu::BindGroupEntry {
                binding: 7,
                resource: buf.as_entire_binding(),
            });
            entries.push(wgpu::BindGroupEntry {
                binding: 4,
                resource: params.as_entire_binding(),
            });
        }
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("light statistics"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        Ok((pipeline, bind, counts))
    }
}
