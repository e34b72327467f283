//! Drawing the scene's meshes, one pipeline per material, for every pass that draws
//! them: depth only, G-buffer, shading (optionally blended), at any sample count. The
//! group-0 layout comes from the shader's reflected bindings and the bind group from
//! what the pass offers, by name.

use super::bind::{layout_entries, BindingSet};
use super::passes::pass_error;
use super::pipelines::{Pipeline, PipelineKey};
use super::scene_gpu::SceneGpu;
use super::{RenderError, Renderer};
use crate::gpu::structs::GpuVertex;
use crate::graph::kinds::forward_shading::Shadows;
use crate::scene::AlphaMode;
use std::collections::BTreeMap;
use std::sync::Arc;

mod record;
pub(super) use record::{color_attachment, depth_attachment, ViewDraw};

/// What a mesh draw writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum DrawMode {
    DepthOnly,
    GBuffer {
        writes_depth: bool,
        /// One target: view depth, octahedral normal, material.
        packed: bool,
        /// Unpacked: a target of shading normals after the positions.
        normals: bool,
        /// Unpacked: a target of geometric normals next (ray-cast shadows).
        geometric: bool,
        /// Two targets next: the surface the material samples and the uv derivatives.
        surface: bool,
        /// Two targets last: the second uv set and its derivatives.
        uv1: bool,
    },
    Shade {
        lists: super::passes::ShadeLists,
        blend: bool,
        shadows: Shadows,
        /// The depth tested against is an R32Float texture (`FLOAT_DEPTH`), not an
        /// attachment: the fragment shader loads it and discards what the attachment's
        /// LessEqual test would have failed; the pipeline has no depth state.
        float_depth: bool,
        /// VPLs hidden from a pixel add nothing (`VPL_VISIBILITY`): the bits' layout.
        vpl_visibility: Option<super::passes::VplLookup>,
        /// The scene has indirect lights, so the lights may hold VPLs; without them
        /// `NO_VPLS` leaves their code out ([`vpl_defines`]).
        vpls: bool,
    },
    /// A shadow atlas's views: depth only, the view from the instance index, both faces,
    /// biased.
    AtlasDepth {
        format: wgpu::TextureFormat,
        depth_bias: i32,
        /// `f32::to_bits` of the slope-scaled bias (the mode is a pipeline key).
        slope_bias_bits: u32,
    },
    /// Reflective shadow maps' views: normal, flux and position targets over depth, the
    /// view from the instance index, both faces.
    Rsm,
    /// A visibility buffer: each fragment's triangle id into one R32Uint target. The
    /// mesh's first id is the instance index (`first_triangle..first_triangle + 1`).
    Visibility {
        writes_depth: bool,
    },
}

impl DrawMode {
    fn writes_depth(self) -> bool {
        match self {
            DrawMode::DepthOnly | DrawMode::AtlasDepth { .. } | DrawMode::Rsm => true,
            DrawMode::GBuffer { writes_depth, .. } | DrawMode::Visibility { writes_depth } => {
                writes_depth
            }
            DrawMode::Shade { .. } => false,
        }
    }
    fn depth_only(self) -> bool {
        matches!(self, DrawMode::DepthOnly | DrawMode::AtlasDepth { .. })
    }
}

/// One mesh drawn with its material's pipeline.
struct Draw {
    /// Index into the scene's GPU meshes.
    mesh: usize,
    pipeline: Arc<wgpu::RenderPipeline>,
    /// The material's textures (group 2), if it has any.
    material: Option<wgpu::BindGroup>,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    /// The instance drawn: the mesh's first triangle id for visibility draws, else 0.
    instance: u32,
}

/// Which of the scene's meshes a pass draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum MeshSet {
    /// Opaque and alpha-masked meshes, sorted by material.
    Opaque,
    /// Blended meshes, in scene order (sorted by view depth when recorded), drawn
    /// two-sided.
    Transparent,
    /// What casts into shadow maps: the opaque set and the blended meshes that opt in.
    ShadowCasters,
}

/// The meshes of a pass (opaque ones sorted by material) and the pass's group-0 bind group.
pub(super) struct MeshDraws {
    bind: Option<wgpu::BindGroup>,
    draws: Vec<Draw>,
}

const SHADER: &str = "forward/forward.wgsl";

/// `NO_VPLS` where the scene has no indirect light, so no VPL: the light loops then leave
/// out the glossy widening only VPLs take (shaders/common/light_loop.wgsl).
pub(crate) fn vpl_defines(has_indirect_lights: bool) -> Option<(&'static str, String)> {
    (!has_indirect_lights).then(|| ("NO_VPLS", "1".into()))
}

/// The light loop's shadow defines (see `shaders/common/shadows.wgsl`).
pub(super) fn shadow_defines(shadows: Shadows) -> Vec<(&'static str, String)> {
    let offset = format!(
        "{:?}",
        crate::graph::kinds::shadow_ray_cast::DEFAULT_NORMAL_OFFSET
    );
    match shadows {
        Shadows::None => vec![],
        Shadows::Mask => vec![
            ("SHADOWS", "1".into()),
            ("SHADOW_MASK", "1".into()),
            ("SHADOW_NORMAL_OFFSET", offset),
        ],
        Shadows::Trace => vec![
            ("SHADOWS", "1".into()),
            ("SHADOW_TRACE", "1".into()),
            ("SHADOW_NORMAL_OFFSET", offset),
        ],
        Shadows::Atlas(filter, raster)
        | Shadows::Hybrid(filter, raster)
        | Shadows::HybridTrace(filter, raster) => {
            let mut d = vec![("SHADOWS", "1".into()), ("SHADOW_NORMAL_OFFSET", offset)];
            d.extend(atlas_defines(filter, raster));
            match shadows {
                Shadows::Hybrid(..) => d.push(("SHADOW_MASK", "1".into())),
                Shadows::HybridTrace(..) => d.push(("SHADOW_TRACE", "1".into())),
                _ => return d,
            }
            d.push(("SHADOW_HYBRID", "1".into()));
            d
        }
    }
}

/// How the light loop samples a shadow atlas (`SHADOW_ATLAS`): its filter, and whether
/// it compares by hand in an R32Float atlas (`SHADOW_ATLAS_FLOAT`, a compute raster's).
pub(super) fn atlas_defines(
    filter: crate::graph::kinds::shadow_atlas::ShadowFilter,
    raster: crate::graph::kinds::shadow_atlas::AtlasRaster,
) -> Vec<(&'static str, String)> {
    use crate::graph::kinds::shadow_atlas::{AtlasRaster, ShadowFilter};
    // The atlas's light entries (SHADOW_ATLAS_LIGHTS) come with every atlas read.
    let mut d = vec![
        ("SHADOW_ATLAS", "1".into()),
        ("SHADOW_ATLAS_LIGHTS", "1".into()),
    ];
    if filter == ShadowFilter::Pcf5x5 {
        d.push(("SHADOW_PCF5", "1".into()));
    }
    if raster == AtlasRaster::Compute {
        d.push(("SHADOW_ATLAS_FLOAT", "1".into()));
    }
    d
}

/// The bind group the generated material code declares its textures in.
pub(super) const MATERIAL_GROUP: u32 = 2;

/// The material's texture layout, from the composed shader's reflection (None when the
/// material declares no textures).
pub(super) fn material_layout(
    layouts: &super::bind::LayoutCache,
    device: &wgpu::Device,
    bindings: &[crate::shader::ReflectedBinding],
    stages: wgpu::ShaderStages,
) -> Option<Arc<wgpu::BindGroupLayout>> {
    let entries = super::bind::layout_entries_filtering(bindings, MATERIAL_GROUP, stages, true);
    (!entries.is_empty()).then(|| layouts.get(device, entries))
}

impl Renderer {
    /// One pipeline per material (draws sorted by material) for `mode` at `samples`.
    pub(super) fn mesh_draws(
        &mut self,
        gpu: &SceneGpu,
        mode: DrawMode,
        set: MeshSet,
        samples: u32,
        pass: &str,
        offered: &BindingSet,
    ) -> Result<MeshDraws, RenderError> {
        let device = self.ctx.device.clone();
        let layouts = self.layouts.clone();
        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let mut draws = Vec::new();
        // One texture group per material, shared by its meshes.
        let mut material_groups: std::collections::HashMap<usize, wgpu::BindGroup> =
            Default::default();
        let mut group0: Option<(
            Vec<wgpu::BindGroupLayoutEntry>,
            Arc<[crate::shader::ReflectedBinding]>,
        )> = None;
        let meshes = match set {
            MeshSet::Opaque => gpu.opaque_draws(),
            MeshSet::Transparent => gpu.transparent_draws(),
            MeshSet::ShadowCasters => gpu.shadow_caster_draws(),
        };
        for mesh in meshes {
            let material_index = gpu.meshes[mesh].material;
            let m = &gpu.materials[material_index];
            let masked = m.alpha_mode.is_masked();
            let mut d: Vec<(&str, String)> = vec![];
            match mode {
                DrawMode::DepthOnly => d.push(("DEPTH_ONLY", "1".into())),
                DrawMode::AtlasDepth { .. } => {
                    d.push(("DEPTH_ONLY", "1".into()));
                    d.push(("ATLAS_DEPTH", "1".into()));
                }
                DrawMode::Rsm => d.push(("RSM", "1".into())),
                DrawMode::Visibility { .. } => d.push(("VISIBILITY", "1".into())),
                DrawMode::GBuffer {
                    packed,
                    normals,
                    geometric,
                    surface,
                    uv1,
                    ..
                } => {
                    d.push(("GBUFFER", "1".into()));
                    d.push(("MATERIAL_INDEX", material_index.to_string()));
                    if packed {
                        d.push(("GBUFFER_PACKED", "1".into()));
                    }
                    if normals {
                        d.push(("GBUFFER_NORMALS", "1".into()));
                    }
                    if geometric {
                        d.push(("GBUFFER_GEOMETRIC", "1".into()));
                    }
                    if surface {
                        d.push(("GBUFFER_SURFACE", "1".into()));
                    }
                    if uv1 {
                        d.push(("GBUFFER_UV1", "1".into()));
                    }
                }
                DrawMode::Shade {
                    lists,
                    shadows,
                    float_depth,
                    vpl_visibility,
                    vpls,
                    ..
                } => {
                    d.push(("SHADE", "1".into()));
                    d.extend(super::passes::VplLookup::defines(vpl_visibility));
                    d.extend(vpl_defines(vpls));
                    d.extend(lists.define());
                    d.extend(shadow_defines(shadows));
                    if float_depth {
                        d.push(("FLOAT_DEPTH", "1".into()));
                    }
                }
            }
            if let AlphaMode::Mask(cutoff) = m.alpha_mode {
                d.push(("ALPHA_MASK", "1".into()));
                d.push(("ALPHA_CUTOFF", format!("{cutoff:?}")));
            }
            // MSAA draws interpolate at the centroid: inside the triangle, so the shaded
            // point lies within the depths culling saw (see forward.wgsl).
            if samples > 1 {
                d.push(("MSAA", "1".into()));
            }
            // A prepass or G-buffer draw of an opaque, untextured material never calls the
            // material code: key it with a neutral material, so editing the material
            // rebuilds only the pipelines that shade with it.
            let shading = matches!(mode, DrawMode::Shade { .. } | DrawMode::Rsm);
            let material_unused = !masked && !shading && m.textures.is_none();
            let code = match neutral_material_wgsl() {
                Some(neutral) if material_unused => neutral.to_string(),
                _ => m.wgsl.clone(),
            };
            let key = super::passes::with_bvh_alpha(
                PipelineKey {
                    shader: SHADER.into(),
                    defines: super::passes::defines(&d),
                    virtual_code: BTreeMap::from([("material".to_string(), code)]),
                    state: format!(
                        "samples={samples} double_sided={} mode={mode:?} set={set:?}",
                        m.double_sided
                    ),
                },
                offered,
            );
            // Shadow views draw both faces (any surface occludes, as for a ray) and their
            // triangles in spatial chunks. Transparent surfaces show both faces (AMD's TiledLighting11 sample:
            // shaded two-sided; the normal flips on back faces in `shading_point`).
            let shadow_view = matches!(mode, DrawMode::AtlasDepth { .. });
            let two_sided = m.double_sided
                || shadow_view
                || set == MeshSet::Transparent
                || mode == DrawMode::Rsm;
            let cull_mode = (!two_sided).then_some(wgpu::Face::Back);
            let (pipeline, bindings) = self
                .pipelines
                .get_or_build_reflected(
                    &self.shaders,
                    key,
                    |_, module, bindings| {
                        let bgl = layouts.get(&device, layout_entries(bindings, 0, vf));
                        let material = material_layout(
                            &layouts,
                            &device,
                            bindings,
                            wgpu::ShaderStages::FRAGMENT,
                        );
                        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                            label: Some(pass),
                            bind_group_layouts: &[Some(&bgl), None, material.as_deref()],
                            immediate_size: 0,
                        });
                        build_pipeline(
                            &device, pass, &pl, &module, mode, masked, samples, cull_mode,
                        )
                    },
                    &device,
                )
                .map_err(|source| RenderError::Shader {
                    pass: format!("{pass} (material '{}')", m.name),
                    source,
                })?;
            let Pipeline::Render(pipeline) = pipeline else {
                return Err(pass_error(pass, "expected a render pipeline".into()));
            };
            let entries = layout_entries(&bindings, 0, vf);
            match &group0 {
                None => group0 = Some((entries, bindings.clone())),
                Some((first, _)) if *first != entries => {
                    return Err(pass_error(
                        pass,
                        format!(
                            "material '{}' changes the shader's group-0 bindings",
                            m.name
                        ),
                    ))
                }
                Some(_) => {}
            }
            let material = match (
                &m.textures,
                material_layout(&layouts, &device, &bindings, wgpu::ShaderStages::FRAGMENT),
            ) {
                (Some(textures), Some(layout)) => {
                    if let std::collections::hash_map::Entry::Vacant(e) =
                        material_groups.entry(material_index)
                    {
                        e.insert(
                            textures
                                .bind(&device, &m.name, &layout, &bindings, MATERIAL_GROUP)
                                .map_err(|e| {
                                    pass_error(pass, format!("material '{}': {e}", m.name))
                                })?,
                        );
                    }
                    material_groups.get(&material_index).cloned()
                }
                _ => None,
            };
            let gm = &gpu.meshes[mesh];
            draws.push(Draw {
                mesh,
                material,
                pipeline,
                vertices: gm.vertices.clone(),
                indices: if shadow_view {
                    gm.shadow_indices.clone()
                } else {
                    gm.indices.clone()
                },
                index_count: gm.index_count,
                instance: match mode {
                    DrawMode::Visibility { .. } => gm.first_triangle,
                    _ => 0,
                },
            });
        }
        let bind = match group0 {
            Some((entries, bindings)) => {
                let bgl = layouts.get(&device, entries);
                Some(
                    offered
                        .bind(&device, pass, &bgl, &bindings, 0)
                        .map_err(|m| pass_error(pass, m))?,
                )
            }
            None => None,
        };
        Ok(MeshDraws { bind, draws })
    }
}

#[allow(clippy::too_many_arguments)]
fn build_pipeline(
    device: &wgpu::Device,
    pass: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    mode: DrawMode,
    masked: bool,
    samples: u32,
    cull_mode: Option<wgpu::Face>,
) -> Pipeline {
    let writes_depth = mode.writes_depth();
    let (entry, colour_targets) = match mode {
        DrawMode::DepthOnly => ("fs_depth", 0),
        DrawMode::GBuffer {
            normals,
            geometric,
            surface,
            uv1,
            ..
        } => (
            "fs_gbuffer",
            1 + usize::from(normals)
                + usize::from(geometric)
                + 2 * usize::from(surface)
                + 2 * usize::from(uv1),
        ),
        DrawMode::Shade { .. } => ("fs_main", 1),
        DrawMode::AtlasDepth { .. } => ("fs_depth", 0),
        DrawMode::Rsm => ("fs_rsm", 3),
        DrawMode::Visibility { .. } => ("fs_visibility", 1),
    };
    let blend = match mode {
        DrawMode::Shade { blend: true, .. } => Some(wgpu::BlendState::ALPHA_BLENDING),
        _ => None,
    };
    let target = Some(wgpu::ColorTargetState {
        format: match mode {
            DrawMode::Visibility { .. } => wgpu::TextureFormat::R32Uint,
            _ => wgpu::TextureFormat::Rgba32Float,
        },
        blend,
        write_mask: wgpu::ColorWrites::ALL,
    });
    let targets = vec![target; colour_targets];
    // A depth-only draw needs a fragment stage only to discard masked fragments.
    let fragment = (!mode.depth_only() || masked).then(|| wgpu::FragmentState {
        module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        targets: &targets,
    });
    Pipeline::Render(Arc::new(
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(pass),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(GpuVertex::layout())],
            },
            primitive: wgpu::PrimitiveState {
                cull_mode,
                ..Default::default()
            },
            depth_stencil: (!matches!(
                mode,
                DrawMode::Shade {
                    float_depth: true,
                    ..
                }
            ))
            .then(|| wgpu::DepthStencilState {
                format: match mode {
                    DrawMode::AtlasDepth { format, .. } => format,
                    _ => wgpu::TextureFormat::Depth32Float,
                },
                depth_write_enabled: Some(writes_depth),
                // LessEqual also where the draw writes depth: of two fragments at the same
                // depth the later one wins, as in forward shading after a prepass (which
                // tests LessEqual against it), so a G-buffer without a prepass keeps the
                // same one of two coincident surfaces (tests/depth_ties.rs).
                depth_compare: Some(wgpu::CompareFunction::LessEqual),
                stencil: Default::default(),
                bias: match mode {
                    DrawMode::AtlasDepth {
                        depth_bias,
                        slope_bias_bits,
                        ..
                    } => wgpu::DepthBiasState {
                        constant: depth_bias,
                        slope_scale: f32::from_bits(slope_bias_bits),
                        clamp: 0.0,
                    },
                    _ => Default::default(),
                },
            }),
            multisample: wgpu::MultisampleState {
                count: samples,
                ..Default::default()
            },
            fragment,
            multiview_mask: None,
            cache: crate::render::pipelines::driver_cache().as_ref(),
        }),
    ))
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
            .renderer_wgsl(&Default::default())
            .ok()
    })
    .as_deref()
}
