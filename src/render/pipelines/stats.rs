//! What a [`PipelineCache`](super::PipelineCache) did: each build's times, and running
//! totals.

use std::time::Duration;

/// One pipeline built: which pass asked for it and where its time went.
#[derive(Clone, Debug, PartialEq)]
pub struct PipelineBuild {
    /// The pass being prepared when it was asked for (see [`PipelineCache::set_pass`]).
    pub pass: String,
    /// [`PipelineKey::short`]: shader and material.
    pub pipeline: String,
    /// Composing the shader source and validating it with naga.
    pub compose: Duration,
    /// `create_shader_module` (naga's WGSL front end and SPIR-V back end in wgpu).
    pub module: Duration,
    /// The pass's build function: layouts and `create_render/compute_pipeline` (the
    /// driver's compile, unless it defers it to first use).
    pub create: Duration,
}

impl PipelineBuild {
    /// `pass: shader `material``, the name the benchmark shows.
    pub fn name(&self) -> String {
        format!("{}: {}", self.pass, self.pipeline)
    }
}

/// Running totals of a [`PipelineCache`]; subtract two snapshots to see what happened
/// in between.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CacheCounters {
    /// Requests answered from the cache.
    pub hits: usize,
    /// Requests that were not in the cache (built, or failed to compose or validate).
    pub misses: usize,
    /// Pipelines built.
    pub builds: usize,
    /// Time spent composing shader sources and validating them with naga.
    pub compose: Duration,
    /// Time spent creating shader modules and pipelines (`module` + `create`).
    pub build: Duration,
    /// Of `build`: creating shader modules.
    pub module: Duration,
    /// Of `build`: the build functions (`create_render/compute_pipeline`).
    pub create: Duration,
    /// Of `builds`: those built ahead on other threads ([`PipelineCache::fork`]).
    pub prebuilt: usize,
}

impl std::ops::Sub for CacheCounters {
    type Output = CacheCounters;
    fn sub(self, earlier: CacheCounters) -> CacheCounters {
        CacheCounters {
            hits: self.hits - earlier.hits,
            misses: self.misses - earlier.misses,
            builds: self.builds - earlier.builds,
            compose: self.compose.saturating_sub(earlier.compose),
            build: self.build.saturating_sub(earlier.build),
            module: self.module.saturating_sub(earlier.module),
            create: self.create.saturating_sub(earlier.create),
            prebuilt: self.prebuilt - earlier.prebuilt,
        }
    }
}
