//! The opt-in light-statistics pass: per pixel, lights listed against lights that reach
//! it, over the depth and lists of the graph's last forward shading pass.

use super::bind::BindingSet;
use super::passes::{dispatch, pass_error, Timestamps};
use super::pipelines::{Pipeline, PipelineKey};
use super::report::LightStats;
use super::scene_gpu::SceneGpu;
use super::{RenderError, Renderer};
use crate::gpu::readback::read_buffer;
use crate::gpu::structs::{GpuFrame, GpuLinkParams, GpuListParams};
use crate::graph::{slot, CompiledGraph, FrameSize, PassKind};
use std::collections::BTreeMap;
use std::sync::Arc;
use wgpu::util::DeviceExt;

const PASS: &str = "light statistics";

pub(super) struct LightStatsPass {
    pipeline: Arc<wgpu::ComputePipeline>,
    bind: wgpu::BindGroup,
    counts: wgpu::Buffer,
    groups: [u32; 3],
    /// Schedule position of the shading pass it takes statistics of: it runs right
    /// after it, while that pass's depth and lists still hold their contents (a later
    /// pass may reuse their memory, as transparent light lists do).
    pub after: usize,
}

impl LightStatsPass {
    pub fn prepare(
        r: &mut Renderer,
        graph: &CompiledGraph,
        resources: &super::resources::FrameResources,
        frame_uniform: &wgpu::Buffer,
        gpu: &SceneGpu,
        gpu_frame: &GpuFrame,
        size: FrameSize,
    ) -> Result<Self, RenderError> {
        let device = r.ctx.device.clone();
        // The exact count walks every light at every pixel.
        super::device_limits::check_light_loop(
            &r.ctx.driver_limits,
            &r.ctx.adapter.get_info().name,
            PASS,
            gpu.light_capacity as u64,
            "its exact count walks every light",
        )?;
        let after = graph
            .passes
            .iter()
            .rposition(|p| matches!(p.kind, PassKind::ForwardShading(_)));
        let shading = after.map(|i| &graph.passes[i]).ok_or_else(|| {
            pass_error(
                PASS,
                "the graph has no ForwardShading pass to take statistics of".into(),
            )
        })?;
        let lists = shading.roles.slot(slot::LIGHT_LISTS);
        // Tile lists or a light linked list, as the planned buffer's layout says.
        let links = lists.and_then(|l| graph.plan.link_layout(l));
        let mut d = BTreeMap::new();
        if lists.is_some() {
            let define = if links.is_some() {
                "LINKED_LISTS"
            } else {
                "LIGHT_LISTS"
            };
            d.insert(define.to_string(), "1".to_string());
        }
        if shading.samples > 1 {
            // A multisampled depth: statistics of each pixel's first sample.
            d.insert("MSAA".to_string(), "1".to_string());
        }
        let key = PipelineKey {
            shader: "stats/light_stats.wgsl".into(),
            defines: d,
            virtual_code: BTreeMap::new(),
            state: String::new(),
        };
        let (pipeline, bindings) = r
            .pipelines
            .get_or_build_reflected(
                &r.shaders,
                key,
                |_, module, _| Pipeline::compute(&device, PASS, None, &module, "main"),
                &device,
            )
            .map_err(|source| RenderError::Shader {
                pass: PASS.into(),
                source,
            })?;
        let Pipeline::Compute(pipeline) = pipeline else {
            return Err(pass_error(PASS, "expected a compute pipeline".into()));
        };
        let counts = super::device_limits::create_internal_buffer(
            &device,
            PASS,
            &wgpu::BufferDescriptor {
                label: Some("light counts"),
                size: 8 * size.width as u64 * size.height as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            },
        )?;
        let view_proj = glam::Mat4::from_cols_array_2d(&gpu_frame.view_proj);
        let inv = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("inverse view-projection"),
            contents: bytemuck::cast_slice(&view_proj.inverse().to_cols_array()),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let plan = &graph.plan;
        let missing = |name: &str| pass_error(PASS, format!("'{name}' is not planned"));
        let depth = shading.required(slot::DEPTH);
        let mut set = BindingSet::default();
        set.buffer("frame", frame_uniform);
        set.buffer("light_geometry", &gpu.light_geometry);
        set.buffer("light_properties", &gpu.light_properties);
        set.offer(
            "depth",
            super::bind::Bound::View(
                resources
                    .view(plan, depth)
                    .ok_or_else(|| missing(depth))?
                    .clone(),
            ),
        );
        set.buffer("counts", &counts);
        set.buffer("inv_view_proj", &inv);
        if let Some(lists) = lists {
            set.buffer(
                "light_lists",
                resources
                    .buffer(plan, lists)
                    .ok_or_else(|| missing(lists))?,
            );
            match links {
                Some(links) => {
                    let params = GpuLinkParams::new(&links).ok_or_else(|| missing(lists))?;
                    set.buffer("link_params", &params.buffer(&device));
                }
                None => {
                    let layout = plan.list_layout(lists).ok_or_else(|| missing(lists))?;
                    set.buffer("list_params", &GpuListParams::new(&layout).buffer(&device));
                }
            }
        }
        let bind = set
            .bind(
                &device,
                PASS,
                &pipeline.get_bind_group_layout(0),
                &bindings,
                0,
            )
            .map_err(|m| pass_error(PASS, m))?;
        Ok(Self {
            pipeline,
            bind,
            counts,
            groups: [size.width.div_ceil(8), size.height.div_ceil(8), 1],
            after: after.unwrap_or_default(),
        })
    }

    pub fn record(&self, encoder: &mut wgpu::CommandEncoder) {
        dispatch(
            encoder,
            PASS,
            Timestamps(None),
            &self.pipeline,
            &self.bind,
            self.groups,
        );
    }

    pub fn read(&self, r: &Renderer) -> Result<LightStats, RenderError> {
        let bytes = read_buffer(&r.ctx.device, &r.ctx.queue, &self.counts)?;
        Ok(LightStats::from_counts(bytemuck::cast_slice(&bytes)))
    }
}
