//! What one `Renderer::prepare` did: pipelines found in or added to the cache, physical
//! resources reused from the frame it replaces or created, and where the time went.

use super::pipelines::CacheCounters;
use std::time::Duration;

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
    /// The pipeline-cache generation this prepare used (see
    /// [`PipelineCache::evict_unused_since`](super::PipelineCache::evict_unused_since)).
    pub cache_generation: u64,
}

impl PrepareStats {
    pub(super) fn from_cache(delta: CacheCounters, built: Vec<String>, generation: u64) -> Self {
        Self {
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
