//! Running a compiled graph on wgpu: physical resources from the plan, pipelines from
//! the cache, one wgpu pass per graph pass with GPU timestamps around it, readback.

mod bind;
mod device_limits;
mod draws;
mod frame;
mod light_motion;
mod light_stats;
pub mod materials;
mod passes;
mod pipelines;
mod prepare_stats;
mod present;
mod report;
mod resources;
mod scene_gpu;
mod texture_fit;
pub mod texture_mips;
pub mod visibility_geometry;

pub(crate) use bind::LayoutCache;
pub use device_limits::supported_sample_counts;
pub(crate) use frame::LightCount;
pub use frame::{LightUpdateError, MeshEditError, PreparedFrame, RenderTimings};
pub use materials::MaterialProgram;
pub use passes::AtlasRasterReport;
pub use pipelines::{
    CacheCounters, GpuStateAtBuild, Pipeline, PipelineBuild, PipelineCache, PipelineKey,
};
pub use prepare_stats::PrepareStats;
pub use present::Presenter;
pub use report::FallbackReport;
pub use report::{
    AtlasReport, CullingReport, FrameResult, LightStats, LinkReport, PassReport, RasterReport,
    ShadowCompareReport, ShadowReport, VplReport,
};
pub use resources::FrameResources;
pub use scene_gpu::{GpuBvh, GpuMesh, SceneGpu};

use crate::gpu::{GpuContext, GpuError};
use crate::shader::{ShaderError, ShaderLibrary};
use thiserror::Error;

/// An error preparing or rendering a frame; each names the pass (or graph line) involved
/// where there is one.
#[derive(Debug, Error)]
pub enum RenderError {
    /// The device failed (adapter, device request, readback).
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// A pass's shader failed to compose or compile.
    #[error("pass '{pass}': {source}")]
    Shader {
        /// The pass's name.
        pass: String,
        /// What the shader library reported.
        source: ShaderError,
    },
    /// A pass could not be prepared or recorded (pipeline, binding, missing scene data).
    #[error("pass '{pass}': {message}")]
    Pass {
        /// The pass's name.
        pass: String,
        /// What went wrong.
        message: String,
    },
    /// Past a device limit: names the graph file:line where the pass uses what is too big.
    #[error("{at}: pass '{pass}': {problem}")]
    AtPass {
        /// The graph line where the pass uses it.
        at: crate::graph::Location,
        /// The pass's name.
        pass: String,
        /// Which limit, and by how much.
        problem: String,
    },
    /// The graph's output is not an Rgba32Float texture, so it cannot be read back as an
    /// image.
    #[error("output '{0}' must be an Rgba32Float texture to be read back")]
    OutputFormat(String),
    /// wgpu reported a validation or out-of-memory error (its message, captured by an error
    /// scope).
    #[error("wgpu reported: {0}")]
    Wgpu(String),
    /// A material failed to load or compile.
    #[error(transparent)]
    Material(#[from] crate::material::MaterialError),
    /// The scene upload has room for more lights than the graph's plan was sized for.
    #[error("the graph was compiled for {compiled} lights but the scene upload has room for {capacity}: compile it with FrameSize::lights = {capacity}")]
    LightCapacity {
        /// `FrameSize::lights` the graph was compiled for.
        compiled: u32,
        /// Lights the scene upload has room for.
        capacity: u32,
    },
    /// [`crate::render::PreparedFrame::update_lights`] was refused.
    #[error(transparent)]
    LightUpdate(#[from] LightUpdateError),
}

/// A device, the shader library and the pipeline cache.
pub struct Renderer {
    /// The adapter, device and queue.
    pub ctx: GpuContext,
    /// The WGSL sources passes compose their shaders from.
    pub shaders: ShaderLibrary,
    /// Render and compute pipelines by what they were made from, reused across frames and
    /// reloads.
    pub pipelines: PipelineCache,
    /// Bind-group layouts by their reflected entries, shared by the pipelines made from them.
    pub(crate) layouts: std::sync::Arc<LayoutCache>,
}

impl Renderer {
    /// A renderer on `ctx` with the shaders of `shaders`.
    pub fn new(ctx: GpuContext, shaders: ShaderLibrary) -> Self {
        Self {
            pipelines: PipelineCache::with_driver_cache(ctx.pipeline_cache.clone()),
            ctx,
            shaders,
            layouts: Default::default(),
        }
    }

    /// A renderer on the caller's device and queue (an engine embedding lightgraph), with
    /// the built-in shaders. `adapter` is the one `device` was requested from. Features
    /// the device was opened without are fallbacks, not errors: a pass that has another
    /// way to run says so in every frame's report ([`FallbackReport`]), one that has none
    /// (blending glass needs `FLOAT32_BLENDABLE`) is refused at prepare with its name.
    /// Request [`GpuContext::wanted_features`] and [`GpuContext::wanted_limits`] to get
    /// the fast paths.
    pub fn from_device(adapter: wgpu::Adapter, device: wgpu::Device, queue: wgpu::Queue) -> Self {
        Self::new(
            GpuContext::from_device(adapter, device, queue),
            ShaderLibrary::builtin(),
        )
    }

    /// Opens the first adapter and uses the project's shaders/.
    pub fn headless() -> Result<Self, GpuError> {
        Self::headless_with(&crate::gpu::ContextOptions::default())
    }

    /// [`Self::headless`] with device options (features left off, as on an adapter
    /// without them).
    pub fn headless_with(options: &crate::gpu::ContextOptions) -> Result<Self, GpuError> {
        Ok(Self::new(
            GpuContext::headless_with(options)?,
            ShaderLibrary::builtin(),
        ))
    }
}
