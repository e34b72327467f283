//! A compiled graph made ready for one scene and output size, executed as often as
//! needed (benchmarks run it many times), with readback of the output and statistics.

use super::pipelines::{Pipeline, PipelineKey};
use super::prepare_stats::PrepareStats;
use super::resources::FrameResources;
use super::scene_gpu::SceneGpu;
use super::{RenderError, Renderer};
use crate::gpu::readback::{read_buffer, read_rgba32f};
use crate::gpu::structs::{GpuFrame, GpuListParams, GpuVertex};
use crate::graph::{
    CompiledGraph, CullVariant, Dispatch, FrameSize, LightSource, ListLayout, PassKind,
    ResourceDesc, Slot, TextureFormat,
};
use crate::scene::{AlphaMode, Camera, Scene};
use glam::Vec3;
use std::collections::BTreeMap;
use std::sync::Arc;
use wgpu::util::DeviceExt;

enum PassExec {
    Prepass {
        depth: String,
        clear: bool,
        draws: Vec<Draw>,
        bind: wgpu::BindGroup,
    },
    Culling {
        /// The coarse stage, run first in the same pass.
        coarse: Option<(Arc<wgpu::ComputePipeline>, [u32; 3])>,
        pipeline: Arc<wgpu::ComputePipeline>,
        bind: wgpu::BindGroup,
        groups: [u32; 3],
        lists: String,
    },
    Shading {
        color: String,
        depth: String,
        clear: bool,
        draws: Vec<Draw>,
        bind: wgpu::BindGroup,
    },
    GBuffer {
        depth: String,
        /// False after a depth prepass: load its depth and only test against it.
        clear_depth: bool,
        /// Positions, or the packed texture when there is no normals texture.
        positions: String,
        normals: Option<String>,
        draws: Vec<Draw>,
        bind: wgpu::BindGroup,
    },
    /// One compute dispatch per material over the frame.
    Deferred {
        pipelines: Vec<Arc<wgpu::ComputePipeline>>,
        bind: wgpu::BindGroup,
        groups: [u32; 3],
    },
    Compute {
        pipeline: Arc<wgpu::ComputePipeline>,
        bind: wgpu::BindGroup,
        groups: [u32; 3],
    },
    Fullscreen {
        pipeline: Arc<wgpu::RenderPipeline>,
        bind: wgpu::BindGroup,
        target: String,
        clear: bool,
    },
}

/// Per culling pass: what its lists held this frame.
#[derive(Clone, Debug)]
pub struct CullingReport {
    pub pass: String,
    pub layout: ListLayout,
    /// Lists (tiles, halves or clusters) that wanted more lights than the capacity.
    pub overflowed_lists: u32,
    /// The longest list wanted (before clamping to the capacity).
    pub longest_list: u32,
    /// Kept count of every list, `lists_per_tile` consecutive entries per tile.
    pub counts: Vec<u32>,
}

impl CullingReport {
    /// Lights listed per tile (all its lists together), row-major.
    pub fn per_tile(&self) -> Vec<u32> {
        self.counts
            .chunks(self.layout.lists_per_tile as usize)
            .map(|c| c.iter().sum())
            .collect()
    }
}

/// Per-pixel light statistics over pixels that hold geometry.
#[derive(Clone, Debug, Default)]
pub struct LightStats {
    pub pixels: u64,
    pub listed_total: u64,
    pub exact_total: u64,
    pub max_listed: u32,
    pub max_exact: u32,
}

impl LightStats {
    pub fn avg_listed(&self) -> f64 {
        self.listed_total as f64 / self.pixels.max(1) as f64
    }
    pub fn avg_exact(&self) -> f64 {
        self.exact_total as f64 / self.pixels.max(1) as f64
    }
    /// Listed over exact: 1 means no false positives.
    pub fn false_positive_ratio(&self) -> f64 {
        self.listed_total as f64 / self.exact_total.max(1) as f64
    }
}

pub struct FrameResult {
    pub width: u32,
    pub height: u32,
    /// Linear HDR RGBA, row-major.
    pub image: Vec<[f32; 4]>,
    /// GPU milliseconds per pass, when the adapter has timestamp queries.
    pub pass_ms: Option<Vec<(String, f64)>>,
    pub culling: Vec<CullingReport>,
    pub light_stats: Option<LightStats>,
}

pub struct PreparedFrame {
    pub graph: CompiledGraph,
    pub size: FrameSize,
    resources: FrameResources,
    frame_uniform: wgpu::Buffer,
    passes: Vec<(String, PassExec)>,
    absent: Vec<String>,
    queries: Option<(wgpu::QuerySet, wgpu::Buffer)>,
    stats: Option<(Arc<wgpu::ComputePipeline>, wgpu::BindGroup, wgpu::Buffer)>,
    prepare_stats: PrepareStats,
}

/// Most lights a coarse culling tile lists; a tile with more sends its fine tiles back
/// to testing every light.
const COARSE_CAPACITY: u64 = 8192;

/// A pipeline and its bind group.
pub(super) type PassExecParts<P> = (Arc<P>, wgpu::BindGroup);

fn defines(pairs: &[(&str, String)]) -> BTreeMap<String, String> {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.clone()))
        .collect()
}

fn variant_code(v: CullVariant) -> u32 {
    match v {
        CullVariant::Frustum => 0,
        CullVariant::HalfZ => 1,
        CullVariant::DepthMask => 2,
        CullVariant::Clustered { .. } => 3,
    }
}

fn storage_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    read_only: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn uniform_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn depth_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Depth,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// The list layout of the culling pass that writes `lists` (even if it was culled).
pub(super) fn list_layout_for(
    graph: &CompiledGraph,
    lists: &str,
    size: FrameSize,
) -> Option<(ListLayout, u32, u32)> {
    graph.checked.desc.passes.iter().find_map(|p| match p.kind {
        PassKind::LightCulling {
            tile,
            variant,
            capacity,
            ..
        } if p.writes.iter().any(|w| w == lists) => Some((
            ListLayout::new(tile, variant, capacity, size.width, size.height),
            tile,
            variant_code(variant),
        )),
        _ => None,
    })
}

impl Renderer {
    /// Makes a compiled graph ready to run on `scene` at `size`: resources, pipelines
    /// (through the cache) and bind groups. `light_stats` adds the statistics pass.
    pub fn prepare(
        &mut self,
        graph: CompiledGraph,
        scene: &Scene,
        gpu: &SceneGpu,
        size: FrameSize,
        light_stats: bool,
    ) -> Result<PreparedFrame, RenderError> {
        self.prepare_reusing(graph, scene, gpu, size, light_stats, None)
    }

    /// Like [`prepare`](Self::prepare) for a frame that replaces `previous` (hot reload,
    /// switching graphs): physical textures and buffers whose descriptor and usage did
    /// not change are taken from it instead of created. `previous` stays usable (the
    /// handles are shared), so it can keep running if this frame is never used.
    pub fn prepare_reusing(
        &mut self,
        graph: CompiledGraph,
        scene: &Scene,
        gpu: &SceneGpu,
        size: FrameSize,
        light_stats: bool,
        previous: Option<&PreparedFrame>,
    ) -> Result<PreparedFrame, RenderError> {
        // wgpu reports validation errors (a list buffer over the binding limit, say) as
        // errors here instead of panicking.
        let scope = self
            .ctx
            .device
            .push_error_scope(wgpu::ErrorFilter::Validation);
        let generation = self.pipelines.next_generation();
        let before = self.pipelines.counters();
        self.pipelines.take_built();
        let pool = previous.map(|p| &p.resources);
        let result = self.prepare_unscoped(graph, scene, gpu, size, light_stats, pool);
        let built = self
            .pipelines
            .take_built()
            .iter()
            .map(|k| k.describe())
            .collect();
        let stats = PrepareStats::from_cache(self.pipelines.counters() - before, built, generation);
        match pollster::block_on(scope.pop()) {
            Some(e) => Err(RenderError::Wgpu(e.to_string())),
            None => result.map(|mut frame| {
                frame.prepare_stats = PrepareStats {
                    resources_created: frame.resources.created(),
                    resources_reused: frame.resources.reused(),
                    ..stats
                };
                frame
            }),
        }
    }

    fn prepare_unscoped(
        &mut self,
        graph: CompiledGraph,
        scene: &Scene,
        gpu: &SceneGpu,
        size: FrameSize,
        light_stats: bool,
        pool: Option<&FrameResources>,
    ) -> Result<PreparedFrame, RenderError> {
        let device = self.ctx.device.clone();
        let out = graph.output().to_string();
        match graph
            .checked
            .desc
            .resources
            .iter()
            .find(|r| r.name() == out)
        {
            Some(ResourceDesc::Texture {
                format: TextureFormat::Rgba32Float,
                samples: 1,
                ..
            }) => {}
            _ => return Err(RenderError::OutputFormat(out)),
        }
        let resources = FrameResources::create_reusing(&device, &graph.plan, pool);
        let gpu_frame = GpuFrame::new(
            &scene.camera,
            scene.ambient,
            size.width,
            size.height,
            gpu.light_count,
        );
        let frame_uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("frame"),
            contents: bytemuck::bytes_of(&gpu_frame),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let fragment = wgpu::ShaderStages::FRAGMENT;
        let forward_layout = |lists: bool| {
            let mut entries = vec![
                uniform_entry(0, vf),
                storage_entry(1, fragment, true),
                storage_entry(2, fragment, true),
            ];
            if lists {
                entries.push(storage_entry(3, fragment, true));
                entries.push(uniform_entry(4, fragment));
            }
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(if lists { "forward+lists" } else { "forward" }),
                entries: &entries,
            })
        };
        let mut passes = Vec::new();
        let first_writer = |name: &str, pass: &str| {
            graph
                .passes
                .iter()
                .find(|p| {
                    graph.checked.desc.passes[p.index]
                        .writes
                        .iter()
                        .any(|w| w == name)
                })
                .is_some_and(|p| p.name == pass)
        };
        for sp in &graph.passes {
            let pass_err = |message: String| RenderError::Pass {
                pass: sp.name.clone(),
                message,
            };
            let exec = match &sp.kind {
                PassKind::DepthPrepass => {
                    let depth = sp.roles.slot(Slot::Depth).unwrap().to_string();
                    let samples = self.samples_of(&graph, &depth);
                    let layout = forward_layout(false);
                    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some(&sp.name),
                        layout: &layout,
                        entries: &[
                            entry(0, &frame_uniform),
                            entry(1, &gpu.light_geometry),
                            entry(2, &gpu.light_properties),
                        ],
                    });
                    let draws = self.material_draws(
                        gpu,
                        &layout,
                        None,
                        samples,
                        DrawMode::DepthOnly,
                        &sp.name,
                    )?;
                    PassExec::Prepass {
                        clear: first_writer(&depth, &sp.name),
                        depth,
                        draws,
                        bind,
                    }
                }
                PassKind::LightCulling {
                    tile,
                    variant,
                    capacity,
                    coarse,
                } => {
                    let lists = sp.roles.slot(Slot::LightLists).unwrap().to_string();
                    let depth = sp.roles.slot(Slot::Depth).unwrap();
                    let layout =
                        ListLayout::new(*tile, *variant, *capacity, size.width, size.height);
                    let params =
                        GpuListParams::new(&layout, *tile, variant_code(*variant)).buffer(&device);
                    let compute = wgpu::ShaderStages::COMPUTE;
                    let bgl = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                        label: Some("culling"),
                        entries: &[
                            uniform_entry(0, compute),
                            storage_entry(1, compute, true),
                            depth_entry(2),
                            storage_entry(3, compute, false),
                            uniform_entry(4, compute),
                            storage_entry(5, compute, false),
                        ],
                    });
                    let coarse = (*coarse).max(1);
                    let coarse_groups = [
                        layout.tiles_x.div_ceil(coarse),
                        layout.tiles_y.div_ceil(coarse),
                        1,
                    ];
                    // Each coarse tile: a count and up to COARSE_CAPACITY indices (a
                    // single unused word without a coarse stage).
                    let coarse_words = if coarse > 1 {
                        coarse_groups[0] as u64 * coarse_groups[1] as u64 * (COARSE_CAPACITY + 1)
                    } else {
                        1
                    };
                    let coarse_lists = device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("coarse light lists"),
                        size: coarse_words * 4,
                        usage: wgpu::BufferUsages::STORAGE,
                        mapped_at_creation: false,
                    });
                    let key = PipelineKey {
                        shader: "cull/tiled.wgsl".into(),
                        defines: defines(&[
                            ("TILE", format!("{tile}u")),
                            ("CAPACITY", format!("{capacity}u")),
                            ("VARIANT", format!("{}u", variant_code(*variant))),
                            ("COARSE", format!("{coarse}u")),
                            ("COARSE_CAPACITY", format!("{COARSE_CAPACITY}u")),
                        ]),
                        virtual_code: BTreeMap::new(),
                        state: String::new(),
                    };
                    let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                        label: Some("culling"),
                        bind_group_layouts: &[Some(&bgl)],
                        immediate_size: 0,
                    });
                    let mut build = |entry: &str, state: &str| {
                        let key = PipelineKey {
                            state: state.to_string(),
                            ..key.clone()
                        };
                        let pipeline = self
                            .pipelines
                            .get_or_build(
                                &self.shaders,
                                key,
                                |_, module| {
                                    Pipeline::compute(&device, entry, Some(&pl), &module, entry)
                                },
                                &device,
                            )
                            .map_err(|source| RenderError::Shader {
                                pass: sp.name.clone(),
                                source,
                            })?;
                        let Pipeline::Compute(pipeline) = pipeline else {
                            unreachable!("built as a compute pipeline")
                        };
                        Ok::<_, RenderError>(pipeline)
                    };
                    let pipeline = build("main", "")?;
                    let coarse_stage = if coarse > 1 {
                        Some((build("coarse", "coarse")?, coarse_groups))
                    } else {
                        None
                    };
                    let depth_view = resources
                        .view(&graph.plan, depth)
                        .ok_or_else(|| pass_err("depth not planned".into()))?;
                    let list_buf = resources
                        .buffer(&graph.plan, &lists)
                        .ok_or_else(|| pass_err("lists not planned".into()))?;
                    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some(&sp.name),
                        layout: &bgl,
                        entries: &[
                            entry(0, &frame_uniform),
                            entry(1, &gpu.light_geometry),
                            wgpu::BindGroupEntry {
                                binding: 2,
                                resource: wgpu::BindingResource::TextureView(depth_view),
                            },
                            entry(3, list_buf),
                            entry(4, &params),
                            entry(5, &coarse_lists),
                        ],
                    });
                    PassExec::Culling {
                        coarse: coarse_stage,
                        pipeline,
                        bind,
                        groups: [layout.tiles_x, layout.tiles_y, layout.lists_per_tile],
                        lists,
                    }
                }
                PassKind::GBuffer => {
                    let depth = sp.roles.slot(Slot::Depth).unwrap().to_string();
                    // After a depth prepass the G-buffer only tests depth: each pixel is
                    // written once instead of once per overlapping surface.
                    let writes_depth = graph.checked.desc.passes[sp.index].writes.contains(&depth);
                    // One texture: view depth, octahedral normal and material, packed.
                    let packed = sp.roles.slot(Slot::GNormal).is_none();
                    let layout = forward_layout(false);
                    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some(&sp.name),
                        layout: &layout,
                        entries: &[
                            entry(0, &frame_uniform),
                            entry(1, &gpu.light_geometry),
                            entry(2, &gpu.light_properties),
                        ],
                    });
                    let draws = self.material_draws(
                        gpu,
                        &layout,
                        None,
                        1,
                        DrawMode::GBuffer {
                            writes_depth,
                            packed,
                        },
                        &sp.name,
                    )?;
                    PassExec::GBuffer {
                        depth,
                        clear_depth: writes_depth,
                        positions: sp.roles.slot(Slot::GPosition).unwrap().to_string(),
                        normals: sp.roles.slot(Slot::GNormal).map(str::to_string),
                        draws,
                        bind,
                    }
                }
                PassKind::DeferredShading { lights } => {
                    let culled = *lights == LightSource::Culled;
                    let compute = wgpu::ShaderStages::COMPUTE;
                    let texture = |binding| wgpu::BindGroupLayoutEntry {
                        binding,
                        visibility: compute,
                        ty: wgpu::BindingType::Texture {
                            sample_type: wgpu::TextureSampleType::Float { filterable: false },
                            view_dimension: wgpu::TextureViewDimension::D2,
                            multisampled: false,
                        },
                        count: None,
                    };
                    let mut layout_entries = vec![
                        uniform_entry(0, compute),
                        storage_entry(1, compute, true),
                        storage_entry(2, compute, true),
                        texture(5),
                        wgpu::BindGroupLayoutEntry {
                            binding: 7,
                            visibility: compute,
                            ty: wgpu::BindingType::StorageTexture {
                                access: wgpu::StorageTextureAccess::WriteOnly,
                                format: wgpu::TextureFormat::Rgba32Float,
                                view_dimension: wgpu::TextureViewDimension::D2,
                            },
                            count: None,
                        },
                    ];
                    let view_of = |slot: Slot| {
                        let name = sp.roles.slot(slot).unwrap();
                        resources
                            .view(&graph.plan, name)
                            .ok_or_else(|| pass_err(format!("'{name}' not planned")))
                    };
                    let mut entries = vec![
                        entry(0, &frame_uniform),
                        entry(1, &gpu.light_geometry),
                        entry(2, &gpu.light_properties),
                        wgpu::BindGroupEntry {
                            binding: 5,
                            resource: wgpu::BindingResource::TextureView(view_of(Slot::GPosition)?),
                        },
                        wgpu::BindGroupEntry {
                            binding: 7,
                            resource: wgpu::BindingResource::TextureView(view_of(Slot::Color)?),
                        },
                    ];
                    // Without a normals texture the G-buffer is the packed one.
                    let packed = sp.roles.slot(Slot::GNormal).is_none();
                    if !packed {
                        layout_entries.push(texture(6));
                        entries.push(wgpu::BindGroupEntry {
                            binding: 6,
                            resource: wgpu::BindingResource::TextureView(view_of(Slot::GNormal)?),
                        });
                    }
                    let lists = if culled {
                        let lists = sp.roles.slot(Slot::LightLists).unwrap();
                        Some(
                            list_buffers(&graph, &resources, lists, size, &device)
                                .map_err(pass_err)?,
                        )
                    } else {
                        None
                    };
                    if let Some((buf, params)) = &lists {
                        layout_entries.push(storage_entry(3, compute, true));
                        layout_entries.push(uniform_entry(4, compute));
                        entries.push(entry(3, buf));
                        entries.push(entry(4, params));
                    }
                    let bgl = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                        label: Some("deferred shading"),
                        entries: &layout_entries,
                    });
                    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some(&sp.name),
                        layout: &bgl,
                        entries: &entries,
                    });
                    let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                        label: Some("deferred shading"),
                        bind_group_layouts: &[Some(&bgl)],
                        immediate_size: 0,
                    });
                    let mut pipelines = Vec::new();
                    for (index, m) in gpu.materials.iter().enumerate() {
                        if m.bind_group.is_some() {
                            return Err(pass_err(format!(
                                "material '{}' has textures; deferred shading supports untextured materials only (the G-buffer holds no UVs or tangents yet)",
                                m.name
                            )));
                        }
                        let mut d = vec![("MATERIAL_INDEX", index.to_string())];
                        if packed {
                            d.push(("G_PACKED", "1".into()));
                        }
                        if culled {
                            d.push(("LIGHT_LISTS", "1".into()));
                        }
                        let key = PipelineKey {
                            shader: "deferred/shade.wgsl".into(),
                            defines: defines(&d),
                            virtual_code: BTreeMap::from([(
                                "material".to_string(),
                                m.wgsl.clone(),
                            )]),
                            state: String::new(),
                        };
                        let pipeline = self
                            .pipelines
                            .get_or_build(
                                &self.shaders,
                                key,
                                |_, module| {
                                    Pipeline::compute(
                                        &device,
                                        "deferred shading",
                                        Some(&pl),
                                        &module,
                                        "main",
                                    )
                                },
                                &device,
                            )
                            .map_err(|source| RenderError::Shader {
                                pass: format!("{} (material '{}')", sp.name, m.name),
                                source,
                            })?;
                        let Pipeline::Compute(p) = pipeline else {
                            unreachable!()
                        };
                        pipelines.push(p);
                    }
                    PassExec::Deferred {
                        pipelines,
                        bind,
                        groups: [size.width.div_ceil(8), size.height.div_ceil(8), 1],
                    }
                }
                PassKind::ForwardShading { lights } => {
                    let color = sp.roles.slot(Slot::Color).unwrap().to_string();
                    let depth = sp.roles.slot(Slot::Depth).unwrap().to_string();
                    let samples = self.samples_of(&graph, &color);
                    let culled = *lights == LightSource::Culled;
                    let layout = forward_layout(culled);
                    let mut entries = vec![
                        entry(0, &frame_uniform),
                        entry(1, &gpu.light_geometry),
                        entry(2, &gpu.light_properties),
                    ];
                    let lists = if culled {
                        let lists = sp.roles.slot(Slot::LightLists).unwrap();
                        Some(
                            list_buffers(&graph, &resources, lists, size, &device)
                                .map_err(pass_err)?,
                        )
                    } else {
                        None
                    };
                    if let Some((buf, params)) = &lists {
                        entries.push(entry(3, buf));
                        entries.push(entry(4, params));
                    }
                    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some(&sp.name),
                        layout: &layout,
                        entries: &entries,
                    });
                    let draws = self.material_draws(
                        gpu,
                        &layout,
                        Some(culled),
                        samples,
                        DrawMode::Shade,
                        &sp.name,
                    )?;
                    PassExec::Shading {
                        clear: first_writer(&color, &sp.name),
                        color,
                        depth,
                        draws,
                        bind,
                    }
                }
                PassKind::Compute { dispatch, .. } => {
                    let (pipeline, bind) =
                        self.generic_compute(&graph, sp, &resources, &frame_uniform, gpu)?;
                    let groups = match *dispatch {
                        Dispatch::PerPixel { workgroup: (x, y) } => [
                            size.width.div_ceil(x.max(1)),
                            size.height.div_ceil(y.max(1)),
                            1,
                        ],
                        Dispatch::PerTile { tile } => [
                            size.width.div_ceil(tile.max(1)),
                            size.height.div_ceil(tile.max(1)),
                            1,
                        ],
                        Dispatch::PerLight { workgroup } => {
                            [gpu.light_count.div_ceil(workgroup.max(1)).max(1), 1, 1]
                        }
                        Dispatch::Fixed(x, y, z) => [x, y, z],
                    };
                    PassExec::Compute {
                        pipeline,
                        bind,
                        groups,
                    }
                }
                PassKind::Fullscreen { .. } => {
                    let target = sp.roles.target.clone().unwrap();
                    let (pipeline, bind) = self.generic_fullscreen(
                        &graph,
                        sp,
                        &resources,
                        &frame_uniform,
                        gpu,
                        &target,
                    )?;
                    PassExec::Fullscreen {
                        clear: first_writer(&target, &sp.name),
                        pipeline,
                        bind,
                        target,
                    }
                }
            };
            passes.push((sp.name.clone(), exec));
        }
        let absent = graph
            .plan
            .resources
            .iter()
            .filter(|r| r.absent)
            .map(|r| r.name.clone())
            .collect();
        let queries = self.ctx.has_timestamps.then(|| {
            let count = 2 * (passes.len() as u32 + 1);
            (
                device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("pass timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count,
                }),
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamps"),
                    size: 8 * count as u64,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }),
            )
        });
        let stats = if light_stats {
            Some(self.stats_pass(&graph, &resources, &frame_uniform, gpu, &gpu_frame, size)?)
        } else {
            None
        };
        Ok(PreparedFrame {
            graph,
            size,
            resources,
            frame_uniform,
            passes,
            absent,
            queries,
            stats,
            prepare_stats: PrepareStats::default(),
        })
    }

    fn samples_of(&self, graph: &CompiledGraph, name: &str) -> u32 {
        graph
            .checked
            .desc
            .resources
            .iter()
            .find_map(|r| match r {
                ResourceDesc::Texture {
                    name: n, samples, ..
                } if n == name => Some(*samples),
                _ => None,
            })
            .unwrap_or(1)
    }

    /// One pipeline per material (draws sorted by material). `lists`: None for the
    /// depth prepass and the G-buffer, Some(culled) for shading.
    fn material_draws(
        &mut self,
        gpu: &SceneGpu,
        layout: &wgpu::BindGroupLayout,
        lists: Option<bool>,
        samples: u32,
        mode: DrawMode,
        pass: &str,
    ) -> Result<Vec<Draw>, RenderError> {
        let depth_only = mode == DrawMode::DepthOnly;
        let gbuffer = matches!(mode, DrawMode::GBuffer { .. });
        let writes_depth = match mode {
            DrawMode::DepthOnly => true,
            DrawMode::GBuffer { writes_depth, .. } => writes_depth,
            DrawMode::Shade => false,
        };
        let device = self.ctx.device.clone();
        let mut draws = Vec::new();
        for mesh in gpu.opaque_draws() {
            let material_index = gpu.meshes[mesh].material;
            let m = &gpu.materials[material_index];
            let material_layout = m.bind_group.as_ref().map(|(l, _)| l.as_ref());
            let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(pass),
                bind_group_layouts: &[Some(layout), None, material_layout],
                immediate_size: 0,
            });
            let masked = matches!(m.alpha_mode, AlphaMode::Mask(_));
            let mut d = vec![];
            if depth_only {
                d.push(("DEPTH_ONLY", "1".to_string()));
            }
            if let DrawMode::GBuffer { packed: true, .. } = mode {
                d.push(("GBUFFER_PACKED", "1".to_string()));
            }
            if gbuffer {
                d.push(("GBUFFER", "1".to_string()));
                d.push(("MATERIAL_INDEX", material_index.to_string()));
            }
            if let AlphaMode::Mask(cutoff) = m.alpha_mode {
                d.push(("ALPHA_MASK", "1".into()));
                d.push(("ALPHA_CUTOFF", format!("{cutoff:?}")));
            }
            if lists == Some(true) {
                d.push(("LIGHT_LISTS", "1".into()));
            }
            // A prepass or G-buffer draw of an opaque, untextured material never calls the
            // material code: key it with a neutral material, so editing the material
            // rebuilds only the pipelines that shade with it.
            let material_unused = !masked && mode != DrawMode::Shade && m.bind_group.is_none();
            let code = match neutral_material_wgsl() {
                Some(neutral) if material_unused => neutral.to_string(),
                _ => m.wgsl.clone(),
            };
            let key = PipelineKey {
                shader: "forward/forward.wgsl".into(),
                defines: defines(&d),
                virtual_code: BTreeMap::from([("material".to_string(), code)]),
                state: format!(
                    "samples={samples} double_sided={} mode={mode:?}",
                    m.double_sided
                ),
            };
            let cull_mode = (!m.double_sided).then_some(wgpu::Face::Back);
            let pipeline = self
                .pipelines
                .get_or_build(
                    &self.shaders,
                    key,
                    |_, module| {
                        let fragment_entry = match mode {
                            DrawMode::DepthOnly => "fs_depth",
                            DrawMode::GBuffer { .. } => "fs_gbuffer",
                            DrawMode::Shade => "fs_main",
                        };
                        let target = Some(wgpu::ColorTargetState {
                            format: wgpu::TextureFormat::Rgba32Float,
                            blend: None,
                            write_mask: wgpu::ColorWrites::ALL,
                        });
                        let targets = [target.clone(), target];
                        let fragment = (!depth_only || masked).then(|| wgpu::FragmentState {
                            module: &module,
                            entry_point: Some(fragment_entry),
                            compilation_options: Default::default(),
                            targets: match mode {
                                DrawMode::DepthOnly => &[],
                                DrawMode::GBuffer { packed: false, .. } => &targets,
                                DrawMode::GBuffer { packed: true, .. } => &targets[..1],
                                DrawMode::Shade => &targets[..1],
                            },
                        });
                        Pipeline::Render(Arc::new(device.create_render_pipeline(
                            &wgpu::RenderPipelineDescriptor {
                                label: Some(pass),
                                layout: Some(&pl),
                                vertex: wgpu::VertexState {
                                    module: &module,
                                    entry_point: Some("vs_main"),
                                    compilation_options: Default::default(),
                                    buffers: &[Some(GpuVertex::layout())],
                                },
                                primitive: wgpu::PrimitiveState {
                                    cull_mode,
                                    ..Default::default()
                                },
                                depth_stencil: Some(wgpu::DepthStencilState {
                                    format: wgpu::TextureFormat::Depth32Float,
                                    depth_write_enabled: Some(writes_depth),
                                    depth_compare: Some(if writes_depth {
                                        wgpu::CompareFunction::Less
                                    } else {
                                        wgpu::CompareFunction::LessEqual
                                    }),
                                    stencil: Default::default(),
                                    bias: Default::default(),
                                }),
                                multisample: wgpu::MultisampleState {
                                    count: samples,
                                    ..Default::default()
                                },
                                fragment,
                                multiview_mask: None,
                                cache: None,
                            },
                        )))
                    },
                    &device,
                )
                .map_err(|source| RenderError::Shader {
                    pass: format!("{pass} (material '{}')", m.name),
                    source,
                })?;
            let Pipeline::Render(pipeline) = pipeline else {
                unreachable!()
            };
            let gm = &gpu.meshes[mesh];
            draws.push(Draw {
                material: m.bind_group.as_ref().map(|(_, g)| g.clone()),
                pipeline,
                vertices: gm.vertices.clone(),
                indices: gm.indices.clone(),
                index_count: gm.index_count,
            });
        }
        Ok(draws)
    }
}

/// Material code for pipelines that include the material but never call it (`None`
/// only if generating it failed, then each material keys with its own code).
fn neutral_material_wgsl() -> Option<&'static str> {
    static CODE: std::sync::OnceLock<Option<String>> = std::sync::OnceLock::new();
    CODE.get_or_init(|| {
        let neutral = crate::scene::SurfaceMaterial {
            name: "neutral".into(),
            ..Default::default()
        };
        crate::material::Material::from_surface(&neutral)
            .wgsl()
            .ok()
    })
    .as_deref()
}

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

impl PreparedFrame {
    /// What preparing this frame built, reused and created.
    pub fn stats(&self) -> &PrepareStats {
        &self.prepare_stats
    }

    /// Records and submits one frame; returns GPU milliseconds per pass when the
    /// adapter has timestamps.
    pub fn execute(&self, r: &Renderer) -> Result<Option<Vec<(String, f64)>>, RenderError> {
        let scope = r.ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let result = self.execute_unscoped(r);
        match pollster::block_on(scope.pop()) {
            Some(e) => Err(RenderError::Wgpu(e.to_string())),
            None => result,
        }
    }

    fn execute_unscoped(&self, r: &Renderer) -> Result<Option<Vec<(String, f64)>>, RenderError> {
        let device = &r.ctx.device;
        let plan = &self.graph.plan;
        let mut encoder = device.create_command_encoder(&Default::default());
        for name in &self.absent {
            if let Some(b) = self.resources.buffer(plan, name) {
                encoder.clear_buffer(b, 0, None);
            } else if let Some(t) = self.resources.texture(plan, name) {
                encoder.clear_texture(t, &Default::default());
            }
        }
        let ts = |i: usize| {
            self.queries
                .as_ref()
                .map(|(q, _)| (q, 2 * i as u32, 2 * i as u32 + 1))
        };
        for (i, (name, exec)) in self.passes.iter().enumerate() {
            let compute_ts = ts(i).map(|(q, a, b)| wgpu::ComputePassTimestampWrites {
                query_set: q,
                beginning_of_pass_write_index: Some(a),
                end_of_pass_write_index: Some(b),
            });
            let render_ts = ts(i).map(|(q, a, b)| wgpu::RenderPassTimestampWrites {
                query_set: q,
                beginning_of_pass_write_index: Some(a),
                end_of_pass_write_index: Some(b),
            });
            match exec {
                PassExec::Prepass {
                    depth,
                    clear,
                    draws,
                    bind,
                } => {
                    let view = self.resources.view(plan, depth).unwrap();
                    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some(name),
                        color_attachments: &[],
                        depth_stencil_attachment: Some(depth_attachment(view, *clear)),
                        timestamp_writes: render_ts,
                        occlusion_query_set: None,
                        multiview_mask: None,
                    });
                    draw_meshes(&mut pass, bind, draws);
                }
                PassExec::Shading {
                    color,
                    depth,
                    clear,
                    draws,
                    bind,
                } => {
                    let cview = self.resources.view(plan, color).unwrap();
                    let dview = self.resources.view(plan, depth).unwrap();
                    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some(name),
                        color_attachments: &[Some(color_attachment(cview, *clear))],
                        depth_stencil_attachment: Some(depth_attachment(dview, false)),
                        timestamp_writes: render_ts,
                        occlusion_query_set: None,
                        multiview_mask: None,
                    });
                    draw_meshes(&mut pass, bind, draws);
                }
                PassExec::Culling {
                    coarse,
                    pipeline,
                    bind,
                    groups,
                    lists,
                } => {
                    // Header words (pool cursor and overflow counters) start at zero.
                    encoder.clear_buffer(self.resources.buffer(plan, lists).unwrap(), 0, Some(16));
                    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some(name),
                        timestamp_writes: compute_ts,
                    });
                    pass.set_bind_group(0, bind, &[]);
                    if let Some((coarse_pipeline, coarse_groups)) = coarse {
                        pass.set_pipeline(coarse_pipeline);
                        let [x, y, z] = *coarse_groups;
                        pass.dispatch_workgroups(x, y, z);
                    }
                    pass.set_pipeline(pipeline);
                    pass.dispatch_workgroups(groups[0], groups[1], groups[2]);
                }
                PassExec::Compute {
                    pipeline,
                    bind,
                    groups,
                } => dispatch(&mut encoder, name, compute_ts, pipeline, bind, *groups),
                PassExec::GBuffer {
                    depth,
                    clear_depth,
                    positions,
                    normals,
                    draws,
                    bind,
                } => {
                    let dview = self.resources.view(plan, depth).unwrap();
                    let clear = |view| wgpu::RenderPassColorAttachment {
                        view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            // w = -1 marks pixels where nothing was drawn.
                            load: wgpu::LoadOp::Clear(wgpu::Color {
                                r: 0.0,
                                g: 0.0,
                                b: 0.0,
                                a: -1.0,
                            }),
                            store: wgpu::StoreOp::Store,
                        },
                    };
                    let mut targets =
                        vec![Some(clear(self.resources.view(plan, positions).unwrap()))];
                    if let Some(normals) = normals {
                        targets.push(Some(clear(self.resources.view(plan, normals).unwrap())));
                    }
                    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some(name),
                        color_attachments: &targets,
                        depth_stencil_attachment: Some(depth_attachment(dview, *clear_depth)),
                        timestamp_writes: render_ts,
                        occlusion_query_set: None,
                        multiview_mask: None,
                    });
                    draw_meshes(&mut pass, bind, draws);
                }
                PassExec::Deferred {
                    pipelines,
                    bind,
                    groups,
                } => {
                    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some(name),
                        timestamp_writes: compute_ts,
                    });
                    pass.set_bind_group(0, bind, &[]);
                    for p in pipelines {
                        pass.set_pipeline(p);
                        pass.dispatch_workgroups(groups[0], groups[1], groups[2]);
                    }
                }
                PassExec::Fullscreen {
                    pipeline,
                    bind,
                    target,
                    clear,
                } => {
                    let view = self.resources.view(plan, target).unwrap();
                    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some(name),
                        color_attachments: &[Some(color_attachment(view, *clear))],
                        depth_stencil_attachment: None,
                        timestamp_writes: render_ts,
                        occlusion_query_set: None,
                        multiview_mask: None,
                    });
                    pass.set_pipeline(pipeline);
                    pass.set_bind_group(0, bind, &[]);
                    pass.draw(0..3, 0..1);
                }
            }
        }
        if let Some((pipeline, bind, _)) = &self.stats {
            let groups = [self.size.width.div_ceil(8), self.size.height.div_ceil(8), 1];
            dispatch(
                &mut encoder,
                "light statistics",
                None,
                pipeline,
                bind,
                groups,
            );
        }
        if let Some((q, buf)) = &self.queries {
            encoder.resolve_query_set(q, 0..2 * self.passes.len() as u32, buf, 0);
        }
        r.ctx.queue.submit([encoder.finish()]);
        let Some((_, buf)) = &self.queries else {
            device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| RenderError::Wgpu(e.to_string()))?;
            return Ok(None);
        };
        let bytes = read_buffer(device, &r.ctx.queue, buf)?;
        let ticks: &[u64] = bytemuck::cast_slice(&bytes);
        let period = r.ctx.queue.get_timestamp_period() as f64;
        Ok(Some(
            self.passes
                .iter()
                .enumerate()
                .map(|(i, (n, _))| {
                    let dt = ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f64 * period;
                    (n.clone(), dt / 1e6)
                })
                .collect(),
        ))
    }

    /// Runs one frame and reads back the output, culling reports and statistics.
    pub fn render(&self, r: &Renderer) -> Result<FrameResult, RenderError> {
        let pass_ms = self.execute(r)?;
        let image = read_rgba32f(&r.ctx.device, &r.ctx.queue, self.output_texture())?;
        let (culling, light_stats) = self.read_reports(r)?;
        Ok(FrameResult {
            width: self.size.width,
            height: self.size.height,
            image,
            pass_ms,
            culling,
            light_stats,
        })
    }

    /// The graph's output texture (Rgba32Float; sampled by the viewer).
    pub fn output_texture(&self) -> &wgpu::Texture {
        self.resources
            .texture(&self.graph.plan, self.graph.output())
            .expect("validation makes the output a planned texture")
    }

    /// Reads back what the last executed frame's culling passes and statistics pass
    /// counted (not the image).
    pub fn read_reports(
        &self,
        r: &Renderer,
    ) -> Result<(Vec<CullingReport>, Option<LightStats>), RenderError> {
        let device = &r.ctx.device;
        let plan = &self.graph.plan;
        let mut culling = Vec::new();
        for (name, exec) in &self.passes {
            if let PassExec::Culling { lists, .. } = exec {
                let layout = list_layout_for(&self.graph, lists, self.size).unwrap().0;
                let words = read_buffer(
                    device,
                    &r.ctx.queue,
                    self.resources.buffer(plan, lists).unwrap(),
                )?;
                let words: &[u32] = bytemuck::cast_slice(&words);
                let counts = (0..layout.lists() as usize)
                    .map(|l| {
                        words[(ListLayout::HEADER_WORDS + ListLayout::ENTRY_WORDS * l as u32 + 1)
                            as usize]
                    })
                    .collect();
                culling.push(CullingReport {
                    pass: name.clone(),
                    layout,
                    overflowed_lists: words[1],
                    longest_list: words[2],
                    counts,
                });
            }
        }
        let light_stats = match &self.stats {
            Some((_, _, buf)) => {
                let bytes = read_buffer(device, &r.ctx.queue, buf)?;
                let counts: &[[u32; 2]] = bytemuck::cast_slice(&bytes);
                let mut s = LightStats::default();
                for &[listed, exact] in counts {
                    if listed == 0 && exact == 0 {
                        continue;
                    }
                    s.pixels += 1;
                    s.listed_total += listed as u64;
                    s.exact_total += exact as u64;
                    s.max_listed = s.max_listed.max(listed);
                    s.max_exact = s.max_exact.max(exact);
                }
                Some(s)
            }
            None => None,
        };
        Ok((culling, light_stats))
    }

    /// Moves the camera without re-preparing (benchmarks, the viewer).
    pub fn set_camera(&self, r: &Renderer, scene: &Scene, light_count: u32) {
        self.set_view(r, &scene.camera, scene.ambient, light_count);
    }

    /// Writes the frame uniform for `camera`: the next `execute` renders from there.
    pub fn set_view(&self, r: &Renderer, camera: &Camera, ambient: Vec3, light_count: u32) {
        let f = GpuFrame::new(
            camera,
            ambient,
            self.size.width,
            self.size.height,
            light_count,
        );
        r.ctx
            .queue
            .write_buffer(&self.frame_uniform, 0, bytemuck::bytes_of(&f));
    }
}

/// The light-list buffer a culling pass writes, and a uniform with its layout, for a
/// pass that reads `lists`.
pub(super) fn list_buffers(
    graph: &CompiledGraph,
    resources: &FrameResources,
    lists: &str,
    size: FrameSize,
    device: &wgpu::Device,
) -> Result<(wgpu::Buffer, wgpu::Buffer), String> {
    let (layout, tile, variant) = list_layout_for(graph, lists, size)
        .ok_or_else(|| format!("no LightCulling pass writes '{lists}'"))?;
    let buffer = resources
        .buffer(&graph.plan, lists)
        .ok_or_else(|| format!("'{lists}' is not planned"))?;
    Ok((
        buffer.clone(),
        GpuListParams::new(&layout, tile, variant).buffer(device),
    ))
}

/// One compute pass with one dispatch.
fn dispatch(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    timestamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
    pipeline: &wgpu::ComputePipeline,
    bind: &wgpu::BindGroup,
    groups: [u32; 3],
) {
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: timestamps,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind, &[]);
    pass.dispatch_workgroups(groups[0], groups[1], groups[2]);
}

fn depth_attachment(
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

fn color_attachment(view: &wgpu::TextureView, clear: bool) -> wgpu::RenderPassColorAttachment<'_> {
    wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: if clear {
                wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)
            } else {
                wgpu::LoadOp::Load
            },
            store: wgpu::StoreOp::Store,
        },
    }
}

fn draw_meshes(pass: &mut wgpu::RenderPass<'_>, bind: &wgpu::BindGroup, draws: &[Draw]) {
    pass.set_bind_group(0, bind, &[]);
    let mut current: Option<*const wgpu::RenderPipeline> = None;
    for d in draws {
        // Draws are sorted by material: switch pipelines only when it changes.
        let ptr = Arc::as_ptr(&d.pipeline);
        if current != Some(ptr) {
            pass.set_pipeline(&d.pipeline);
            current = Some(ptr);
            if let Some(group) = &d.material {
                pass.set_bind_group(2, group, &[]);
            }
        }
        pass.set_vertex_buffer(0, d.vertices.slice(..));
        pass.set_index_buffer(d.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..d.index_count, 0, 0..1);
    }
}

/// What a material draw writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum DrawMode {
    DepthOnly,
    GBuffer { writes_depth: bool, packed: bool },
    Shade,
}

/// One mesh drawn with its material's pipeline.
pub(super) struct Draw {
    pipeline: Arc<wgpu::RenderPipeline>,
    /// The material's textures (group 2), if it has any.
    material: Option<wgpu::BindGroup>,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
}
