//! The render side of the pass kinds, built-in and generic: each kind folder's
//! `prepare.rs` (`src/kinds/<kind>/`), which build.rs mounts here as
//! `render::passes::<kind>`, prepares its pipelines and bind groups from a scheduled pass
//! and records itself.
//! This file holds the prepare dispatch, generated from the registry of kinds
//! (`graph::kinds::built_in_kinds!`), and what preparing any pass needs.

// Each kind folder's `prepare.rs` as `render::passes::<kind>`, its other files as
// `<kind>_<file>` (build.rs).
include!(concat!(env!("OUT_DIR"), "/kind_prepare.rs"));

use super::bind::{BindingSet, Bound};
use super::pipelines::{Pipeline, PipelineKey};
use super::report::PassReport;
use super::resources::FrameResources;
use super::scene_gpu::SceneGpu;
use super::{RenderError, Renderer};
use crate::gpu::structs::{GpuLinkParams, GpuListParams};
use crate::graph::kinds::built_in_kinds;
use crate::graph::{
    CompiledGraph, FrameSize, PassKind, ResourceDesc, SceneResource, ScheduledPass,
};
pub use shadow_atlas_raster::AtlasRasterReport;
use std::collections::BTreeMap;
use std::sync::Arc;
pub(crate) use vpl_visibility::VplLookup;

/// A pass ready to record, as often as frames run.
pub(super) trait PreparedPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>);
    /// What the pass counted on the GPU, for passes that count (read after a frame).
    fn report(&self, _r: &Renderer) -> Result<Option<PassReport>, RenderError> {
        Ok(None)
    }
    /// The camera moved without re-preparing: passes that depend on the view (the
    /// shadow atlas's allocation) update for the next frame.
    fn set_view(&self, _r: &Renderer, _camera: &crate::scene::Camera) {}
    /// Why this pass cannot follow an update to `lights`, if it cannot (room prepared
    /// for the lights at prepare that they outgrow).
    fn can_follow_lights(&self, _lights: &[crate::scene::Light]) -> Result<(), String> {
        Ok(())
    }
    /// The scene's lights changed without re-preparing (`PreparedFrame::update_lights`):
    /// passes that keep per-light state on the CPU (atlas allocation, per-light
    /// dispatches) update it for the next frame.
    fn follow_lights(&self, _r: &Renderer, _lights: &[crate::scene::Light]) {}
}

/// What a kind's `prepare` returns, boxed: its pass, or a pass it boxed itself because
/// it picks one of several (ComputeRaster's hardware fallback).
trait IntoPrepared {
    fn into_prepared(self) -> Box<dyn PreparedPass>;
}

impl<P: PreparedPass + 'static> IntoPrepared for P {
    fn into_prepared(self) -> Box<dyn PreparedPass> {
        Box::new(self)
    }
}

impl IntoPrepared for Box<dyn PreparedPass> {
    fn into_prepared(self) -> Box<dyn PreparedPass> {
        self
    }
}

/// The render side of the registry (`graph::kinds::built_in_kinds`): the prepare
/// dispatch, calling each kind module's `prepare(cx, sp)` (with `&params` for a kind that
/// has them), and the two generic kinds after the built-in ones.
macro_rules! render_side {
    ($( $(#[$doc:meta])* $kind:ident $( ($params:ident : $ty:ident) )? => $module:ident, )*) => {
        /// Prepares one scheduled pass.
        pub(super) fn prepare(
            cx: &mut PrepareCtx<'_>,
            sp: &ScheduledPass,
        ) -> Result<Box<dyn PreparedPass>, RenderError> {
            Ok(match &sp.kind {
                $( PassKind::$kind $( ($params) )? => {
                    $module::prepare(cx, sp $(, $params)?)?.into_prepared()
                } )*
                PassKind::Compute {
                    shader,
                    entry,
                    dispatch,
                } => compute::prepare(cx, sp, shader, entry, *dispatch)?.into_prepared(),
                PassKind::Fullscreen { shader, entry } => {
                    fullscreen::prepare(cx, sp, shader, entry)?.into_prepared()
                }
            })
        }
    };
}

built_in_kinds!(render_side);

/// Which lights a shading pass visits at a pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ShadeLists {
    AllLights,
    /// A LightCulling pass's tile lists.
    Tiles,
    /// A LightLinkedList pass's per-pixel links.
    Links,
}

impl ShadeLists {
    /// The shader define that selects the walk in `common/light_lists.wgsl`.
    pub fn define(self) -> Option<(&'static str, String)> {
        match self {
            ShadeLists::AllLights => None,
            ShadeLists::Tiles => Some(("LIGHT_LISTS", "1".into())),
            ShadeLists::Links => Some(("LINKED_LISTS", "1".into())),
        }
    }
}

/// The timestamp query pair around one pass, when the adapter has timestamps.
#[derive(Clone, Copy)]
pub(super) struct Timestamps<'a>(pub Option<(&'a wgpu::QuerySet, u32)>);

impl<'a> Timestamps<'a> {
    pub fn compute(self) -> Option<wgpu::ComputePassTimestampWrites<'a>> {
        self.0.map(|(q, i)| wgpu::ComputePassTimestampWrites {
            query_set: q,
            beginning_of_pass_write_index: Some(2 * i),
            end_of_pass_write_index: Some(2 * i + 1),
        })
    }
    pub fn render(self) -> Option<wgpu::RenderPassTimestampWrites<'a>> {
        self.0.map(|(q, i)| wgpu::RenderPassTimestampWrites {
            query_set: q,
            beginning_of_pass_write_index: Some(2 * i),
            end_of_pass_write_index: Some(2 * i + 1),
        })
    }
}

/// What preparing a pass needs: the renderer (pipeline cache), the compiled graph, the
/// scene's buffers and the frame's physical resources.
pub(super) struct PrepareCtx<'a> {
    pub renderer: &'a mut Renderer,
    pub graph: &'a CompiledGraph,
    pub gpu: &'a SceneGpu,
    pub resources: &'a FrameResources,
    pub frame_uniform: &'a wgpu::Buffer,
    pub size: FrameSize,
    pub scene: &'a crate::scene::Scene,
    /// The frame's light count (starts at the scene's).
    pub light_count: &'a crate::render::LightCount,
}

impl PrepareCtx<'_> {
    pub fn device(&self) -> wgpu::Device {
        self.renderer.ctx.device.clone()
    }

    pub fn view(&self, pass: &str, name: &str) -> Result<wgpu::TextureView, RenderError> {
        self.resources
            .view(&self.graph.plan, name)
            .cloned()
            .ok_or_else(|| pass_error(pass, format!("texture '{name}' is not planned")))
    }

    /// The graph's declaration of resource `name`.
    fn resource(&self, name: &str) -> Option<&ResourceDesc> {
        self.graph
            .checked
            .desc
            .resources
            .iter()
            .find(|r| r.name() == name)
    }

    /// Whether the declared texture holds depths as R32Float (a compute resolve's)
    /// rather than in a depth format: its readers bind it as `texture_2d<f32>`
    /// (`FLOAT_DEPTH`).
    pub fn float_depth(&self, name: &str) -> bool {
        crate::graph::kinds::is_float_depth(self.resource(name))
    }

    pub fn buffer(&self, pass: &str, name: &str) -> Result<wgpu::Buffer, RenderError> {
        self.resources
            .buffer(&self.graph.plan, name)
            .cloned()
            .ok_or_else(|| pass_error(pass, format!("buffer '{name}' is not planned")))
    }

    /// The scene's shadow BVH, built on the first pass that binds it.
    fn bvh(&self, pass: &str) -> Result<&super::scene_gpu::GpuBvh, RenderError> {
        self.gpu
            .bvh(&self.renderer.ctx.device, self.scene)
            .map_err(|m| pass_error(pass, m))
    }

    /// The opaque meshes merged for vertex fetching, built on the first pass that binds them.
    fn merged(
        &self,
        pass: &str,
    ) -> Result<&super::visibility_geometry::VisibilityGeometry, RenderError> {
        self.gpu
            .visibility_geometry(&self.renderer.ctx.device, self.scene)
            .map_err(|m| pass_error(pass, m))
    }

    /// A declared resource as something to bind: scene imports, planned buffers and
    /// textures. `None` for scene geometry (drawn, never bound).
    fn bound(&self, pass: &str, name: &str) -> Result<Option<Bound>, RenderError> {
        let desc = self.resource(name);
        Ok(Some(match desc {
            Some(ResourceDesc::Import { from, .. }) => match from {
                SceneResource::LightGeometry => Bound::Buffer(self.gpu.light_geometry.clone()),
                SceneResource::LightProperties => Bound::Buffer(self.gpu.light_properties.clone()),
                SceneResource::Geometry => return Ok(None),
                SceneResource::BvhNodes => Bound::Buffer(self.bvh(pass)?.nodes.clone()),
                SceneResource::BvhTriangles => Bound::Buffer(self.bvh(pass)?.triangles.clone()),
                SceneResource::Vertices => Bound::Buffer(self.merged(pass)?.vertices.clone()),
                SceneResource::Triangles => Bound::Buffer(self.merged(pass)?.triangles.clone()),
                SceneResource::MaterialTriangles => {
                    Bound::Buffer(self.merged(pass)?.material_triangles.clone())
                }
            },
            Some(ResourceDesc::Buffer { .. }) => Bound::Buffer(self.buffer(pass, name)?),
            Some(ResourceDesc::Texture { .. }) => Bound::View(self.view(pass, name)?),
            None => return Err(pass_error(pass, format!("'{name}' is not declared"))),
        }))
    }

    /// A light slot filled by a buffer no scheduled pass writes (its `VplSpawn` pass was
    /// culled: `when: IndirectLights` on a scene without them) reads the scene's own
    /// light array, so the frame is exactly the graph without VPLs.
    fn scene_lights_instead(&self, slot: &str, name: &str) -> Option<Bound> {
        use crate::graph::slot::{LIGHT_GEOMETRY, LIGHT_PROPERTIES};
        let is_buffer = matches!(self.resource(name), Some(ResourceDesc::Buffer { .. }));
        let written = self.graph.passes.iter().any(|p| {
            self.graph.checked.desc.passes[p.index]
                .writes
                .iter()
                .any(|w| w == name)
        });
        if !is_buffer || written {
            return None;
        }
        match slot {
            LIGHT_GEOMETRY => Some(Bound::Buffer(self.gpu.light_geometry.clone())),
            LIGHT_PROPERTIES => Some(Bound::Buffer(self.gpu.light_properties.clone())),
            _ => None,
        }
    }

    /// What a pass may bind: the frame uniform and, under their slot names (built-in
    /// kinds) or their own names (generic kinds), exactly the resources it declared.
    pub fn declared(&self, sp: &ScheduledPass) -> Result<BindingSet, RenderError> {
        let mut set = BindingSet::default();
        set.buffer("frame", self.frame_uniform);
        for (slot, name) in &sp.roles.slots {
            if let Some(b) = self.scene_lights_instead(slot, name) {
                set.offer(slot, b);
            } else if let Some(b) = self.bound(&sp.name, name)? {
                set.offer(slot, b);
            }
            self.offer_bvh_alpha(&sp.name, name, &mut set)?;
        }
        for (_, name) in &sp.roles.bindings {
            if crate::graph::BUILTIN_BINDINGS.contains(&name.as_str()) {
                continue;
            }
            if let Some(b) = self.bound(&sp.name, name)? {
                set.offer(name, b);
            }
            self.offer_bvh_alpha(&sp.name, name, &mut set)?;
        }
        Ok(set)
    }

    /// Where a pass binds the BVH's triangles and some of them are alpha-masked, their
    /// alpha data comes with them as `bvh_alpha`; the pipelines then alpha-test rays
    /// (`BVH_ALPHA_TEST`, see [`with_bvh_alpha`]).
    fn offer_bvh_alpha(
        &self,
        pass: &str,
        name: &str,
        set: &mut BindingSet,
    ) -> Result<(), RenderError> {
        if let Some(ResourceDesc::Import {
            from: SceneResource::BvhTriangles,
            ..
        }) = self.resource(name)
        {
            if let Some(alpha) = &self.bvh(pass)?.alpha {
                set.offer(BVH_ALPHA, Bound::Buffer(alpha.clone()));
            }
        }
        Ok(())
    }

    /// What a shading pass binds to sample a shadow atlas: the comparison sampler
    /// (nearest within a tap: each tap compares a 2×2 footprint; taps are clamped to
    /// their tile), and its shadow source.
    pub fn shading_shadows(
        &self,
        sp: &ScheduledPass,
        offered: &mut BindingSet,
    ) -> crate::graph::kinds::forward_shading::Shadows {
        use crate::graph::kinds::forward_shading::{shadows, Shadows};
        // A scene without casting lights shades as the graph without shadows: the passes
        // that fill the mask were culled (`when: ShadowCasters`), there is nothing to
        // trace, and a light update cannot add a caster to a frame prepared without.
        // The shadowed light loop would cost its extra work for nothing (about 3% of
        // harada's shading in default.ron).
        if !self.scene.features().has_shadow_casters {
            return Shadows::None;
        }
        let s = shadows(&sp.roles, &self.graph.plan);
        if let Shadows::Atlas(..) | Shadows::Hybrid(..) | Shadows::HybridTrace(..) = s {
            offered.offer("shadow_sampler", comparison_sampler(&self.device()));
            offered.offer("shadow_gather", gather_sampler(&self.device()));
        }
        s
    }

    /// The uniform describing the light lists in `lists` (their layout is published on
    /// the planned buffer by the culling pass declared to write it).
    pub fn list_params(&self, pass: &str, lists: &str) -> Result<wgpu::Buffer, RenderError> {
        let layout = self.graph.plan.list_layout(lists).ok_or_else(|| {
            let problem = if self.graph.plan.link_layout(lists).is_some() {
                format!("'{lists}' holds light linked lists; this pass reads the tile lists of a LightCulling pass")
            } else {
                format!("no LightCulling pass is declared to write '{lists}'")
            };
            pass_error(pass, problem)
        })?;
        Ok(GpuListParams::new(&layout).buffer(&self.renderer.ctx.device))
    }

    /// The lists a shading pass walks for `lights`, with the uniform that describes them
    /// offered (`list_params` for tile lists, `link_params` for linked lists).
    pub fn shading_lists(
        &self,
        sp: &ScheduledPass,
        lights: crate::graph::LightSource,
        offered: &mut BindingSet,
    ) -> Result<ShadeLists, RenderError> {
        // Every light the pass may see: the scene's, or all the bound light buffer holds
        // (passes before it, VplSpawn, may add lights).
        let lights_bound = offered
            .buffer_size("light_geometry")
            .map_or(self.gpu.light_capacity as u64, |b| {
                b / crate::gpu::structs::LIGHT_BYTES
            });
        let ctx = &self.renderer.ctx;
        let adapter = ctx.adapter.get_info().name;
        let loop_check = |most: u64, what: &str| {
            let limits = &ctx.driver_limits;
            crate::render::device_limits::check_light_loop(limits, &adapter, &sp.name, most, what)
        };
        if lights == crate::graph::LightSource::AllLights {
            loop_check(lights_bound, "lights: AllLights")?;
            return Ok(ShadeLists::AllLights);
        }
        let lists = sp.required(crate::graph::slot::LIGHT_LISTS);
        if let Some(links) = self.graph.plan.link_layout(lists) {
            loop_check(lights_bound, "a pixel's linked list may hold every light")?;
            let params = GpuLinkParams::new(&links).ok_or_else(|| {
                pass_error(
                    &sp.name,
                    format!("'{lists}': the link pool is past what u32 link indices address"),
                )
            })?;
            offered.buffer("link_params", &params.buffer(&self.renderer.ctx.device));
            return Ok(ShadeLists::Links);
        }
        if let Some(layout) = self.graph.plan.list_layout(lists) {
            let per_list = match layout.storage {
                crate::graph::ListStorage::Fixed { capacity } => capacity as u64,
                crate::graph::ListStorage::Compact { max_indices, .. } => max_indices as u64,
            };
            loop_check(
                per_list.min(lights_bound),
                &format!("'{lists}': a tile's list may hold up to that many"),
            )?;
        }
        offered.buffer("list_params", &self.list_params(&sp.name, lists)?);
        Ok(ShadeLists::Tiles)
    }

    /// A render pipeline from the pipeline cache (`build` runs on a miss with the
    /// composed shader, its module and its reflected bindings), errors named by `pass`.
    pub fn render_pipeline(
        &mut self,
        pass: &str,
        key: PipelineKey,
        build: impl FnOnce(
            &crate::shader::Composed,
            wgpu::ShaderModule,
            &[crate::shader::ReflectedBinding],
        ) -> Pipeline,
    ) -> Result<
        (
            Arc<wgpu::RenderPipeline>,
            Arc<[crate::shader::ReflectedBinding]>,
        ),
        RenderError,
    > {
        let device = self.device();
        let (pipeline, bindings) = self
            .renderer
            .pipelines
            .get_or_build_reflected(&self.renderer.shaders, key, build, &device)
            .map_err(|source| RenderError::Shader {
                pass: pass.to_string(),
                source,
            })?;
        let Pipeline::Render(pipeline) = pipeline else {
            return Err(pass_error(pass, "expected a render pipeline".into()));
        };
        Ok((pipeline, bindings))
    }

    /// A compute pipeline whose group-0 layout is made from its own reflected bindings,
    /// with the bind group from `offered`.
    pub fn compute_pipeline(
        &mut self,
        pass: &str,
        key: PipelineKey,
        entry: &str,
        offered: &BindingSet,
    ) -> Result<(Arc<wgpu::ComputePipeline>, wgpu::BindGroup), RenderError> {
        self.compute_pipeline_with_material(pass, key, entry, offered, None)
            .map(|(pipeline, bind, _)| (pipeline, bind))
    }

    /// [`Self::compute_pipeline`] whose shader includes material code: the material's
    /// textures (`material`) bound in group 2 as mesh draws bind them, if it declares any.
    pub fn compute_pipeline_with_material(
        &mut self,
        pass: &str,
        key: PipelineKey,
        entry: &str,
        offered: &BindingSet,
        material: Option<&BindingSet>,
    ) -> Result<
        (
            Arc<wgpu::ComputePipeline>,
            wgpu::BindGroup,
            Option<wgpu::BindGroup>,
        ),
        RenderError,
    > {
        use super::draws::{material_layout, MATERIAL_GROUP};
        let key = with_bvh_alpha(key, offered);
        let device = self.device();
        let layouts = self.renderer.layouts.clone();
        let compute = wgpu::ShaderStages::COMPUTE;
        let (pipeline, bindings) = self
            .renderer
            .pipelines
            .get_or_build_reflected(
                &self.renderer.shaders,
                key,
                |_, module, bindings| {
                    let bgl =
                        layouts.get(&device, super::bind::layout_entries(bindings, 0, compute));
                    let textures = material_layout(&layouts, &device, bindings, compute);
                    let groups = match &textures {
                        Some(t) => vec![Some(&*bgl), None, Some(&**t)],
                        None => vec![Some(&*bgl)],
                    };
                    let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                        label: Some(pass),
                        bind_group_layouts: &groups,
                        immediate_size: 0,
                    });
                    Pipeline::compute(&device, pass, Some(&pl), &module, entry)
                },
                &device,
            )
            .map_err(|source| RenderError::Shader {
                pass: pass.to_string(),
                source,
            })?;
        let Pipeline::Compute(pipeline) = pipeline else {
            return Err(pass_error(pass, "expected a compute pipeline".into()));
        };
        let bgl = layouts.get(&device, super::bind::layout_entries(&bindings, 0, compute));
        let bind = offered
            .bind(&device, pass, &bgl, &bindings, 0)
            .map_err(|m| pass_error(pass, m))?;
        let textures = match (
            material,
            material_layout(&layouts, &device, &bindings, compute),
        ) {
            (Some(set), Some(layout)) => Some(
                set.bind(&device, pass, &layout, &bindings, MATERIAL_GROUP)
                    .map_err(|m| pass_error(pass, m))?,
            ),
            (None, Some(_)) => {
                return Err(pass_error(
                    pass,
                    "the shader declares bindings in group 2 (material textures) but the pass binds no material there".into(),
                ))
            }
            _ => None,
        };
        Ok((pipeline, bind, textures))
    }
}

/// The shadow atlas's sampler: bilinear comparison (each tap compares a 2×2 footprint),
/// lit where the reference depth is at most the stored one.
pub(super) fn comparison_sampler(device: &wgpu::Device) -> Bound {
    Bound::Sampler(device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("shadow_sampler"),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        compare: Some(wgpu::CompareFunction::LessEqual),
        ..Default::default()
    }))
}

/// An R32Float shadow atlas's sampler (a compute raster's): its filter compares by hand,
/// four texels a `textureGather`.
pub(super) fn gather_sampler(device: &wgpu::Device) -> Bound {
    Bound::Sampler(device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("shadow_gather"),
        ..Default::default()
    }))
}

/// A 1D grid of `items` threads in groups of `per_group`, folded into y past the
/// device's per-dimension limit (the shaders flatten it back).
pub(super) fn grid(items: u32, per_group: u32, max: u32) -> [u32; 3] {
    let groups = items.div_ceil(per_group).max(1);
    if groups <= max {
        [groups, 1, 1]
    } else {
        [max, groups.div_ceil(max), 1]
    }
}

pub(super) fn pass_error(pass: &str, message: String) -> RenderError {
    RenderError::Pass {
        pass: pass.to_string(),
        message,
    }
}

/// The binding alpha-tested rays read (`shaders/shadow/bvh.wgsl`).
pub(super) const BVH_ALPHA: &str = "bvh_alpha";

/// `key` with `BVH_ALPHA_TEST` where `offered` holds the BVH's alpha data: a shader
/// tracing rays then alpha-tests the masked casters' triangles it hits. One rule for
/// every pass that traces, so none can bind the data and skip the test.
pub(super) fn with_bvh_alpha(mut key: PipelineKey, offered: &BindingSet) -> PipelineKey {
    if offered.has(BVH_ALPHA) {
        key.defines.insert("BVH_ALPHA_TEST".into(), "1".into());
    }
    key
}

pub(super) fn defines(pairs: &[(&str, String)]) -> BTreeMap<String, String> {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.clone()))
        .collect()
}

/// One compute pass with one dispatch.
pub(super) fn dispatch(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    ts: Timestamps<'_>,
    pipeline: &wgpu::ComputePipeline,
    bind: &wgpu::BindGroup,
    groups: [u32; 3],
) {
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: ts.compute(),
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind, &[]);
    pass.dispatch_workgroups(groups[0], groups[1], groups[2]);
}
