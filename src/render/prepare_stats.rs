//! What one `Renderer::prepare` did: pipelines found in or added to the cache, physical
//! resources reused from the frame it replaces or created, and where the time went.

use super::pipelines::{CacheCounters, GpuStateAtBuild, PipelineBuild};
use std::time::Duration;

/// What one prepare did: pipelines found in or added to the cache, physical resources
/// reused or created, and the time each step took.
#[derive(Clone, Debug, Default)]
pub struct PrepareStats {
    /// Pipelines the cache already held.
    pub pipeline_hits: usize,
    /// Pipelines the cache did not hold (built, or failed to compose or validate).
    pub pipeline_misses: usize,
    /// The pipelines built, described by [`PipelineKey::describe`](super::PipelineKey::describe).
    pub pipelines_built: Vec<String>,
    /// Physical textures and buffers created for this frame.
    pub resources_created: usize,
    /// Physical textures and buffers taken over from the frame this one replaces.
    pub resources_reused: usize,
    /// Composing shader sources and validating them with naga (misses only).
    pub shader_compose: Duration,
    /// Creating shader modules and pipelines (misses only).
    pub pipeline_build: Duration,
    /// Of `pipeline_build`: `create_shader_module`.
    pub shader_modules: Duration,
    /// Of `pipeline_build`: the passes' build functions (`create_render/compute_pipeline`).
    pub pipeline_create: Duration,
    /// Each pipeline built, in the order asked for.
    pub builds: Vec<PipelineBuild>,
    /// Of the pipelines built, those built on the passes' threads ahead of the
    /// sequential prepare.
    pub pipelines_built_in_parallel: usize,
    /// Whether the GPU still had earlier frames' work when the first build began.
    pub gpu_at_build: GpuStateAtBuild,
    /// Wall time of composing and building: with parallel builds less than
    /// `shader_compose + pipeline_build`, which add up each thread's time.
    pub build_wall: Duration,
    /// Threads that built pipelines ahead of the sequential prepare.
    pub build_threads: usize,
    /// The pipeline-cache generation this prepare used (see
    /// [`PipelineCache::evict_unused_since`](super::PipelineCache::evict_unused_since)).
    pub cache_generation: u64,
}

impl PrepareStats {
    pub(super) fn from_cache(
        delta: CacheCounters,
        built: Vec<String>,
        builds: Vec<PipelineBuild>,
        gpu_at_build: GpuStateAtBuild,
        generation: u64,
    ) -> Self {
        Self {
            shader_modules: delta.module,
            pipelines_built_in_parallel: delta.prebuilt,
            pipeline_create: delta.create,
            builds,
            gpu_at_build,
            pipeline_hits: delta.hits,
            pipeline_misses: delta.misses,
            pipelines_built: built,
            shader_compose: delta.compose,
            pipeline_build: delta.build,
            cache_generation: generation,
            ..Default::default()
        }
    }
}
