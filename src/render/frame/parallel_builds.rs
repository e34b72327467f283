//! Building the pipelines of a graph's passes on several threads before the sequential
//! prepare finds them in the cache.

use crate::render::passes::{self, PrepareCtx};
use crate::render::{pipelines, Renderer};
use std::time::Instant;

/// Builds the pipelines the passes lack on scoped threads, one per pass, before the
/// sequential prepare: each thread prepares its pass with a fork of the pipeline cache
/// (and its own validation error scope) and drops the prepared pass; the forks' new
/// pipelines are adopted in pass order, and the sequential prepare then finds them,
/// counting and naming them as if it had built them (`PipelineCache::adopt`). A pass
/// that fails on its thread contributes nothing: the sequential prepare meets the same
/// error and reports it as before. Drivers compile pipelines concurrently (wgpu's Device
/// is Send + Sync), so a reload rebuilding pipelines of several passes waits for the
/// slowest instead of the sum.
pub(super) fn prebuild_in_parallel(cx: &mut PrepareCtx<'_>) {
    use crate::render::pipelines::ForkMode;
    let r = &mut *cx.renderer;
    // One fork per pass; a pass that asked for several pipelines last time gets one fork
    // per pipeline, each building one of them (ForkMode::Only).
    let forks: Vec<(&crate::graph::ScheduledPass, ForkMode)> = cx
        .graph
        .passes
        .iter()
        .flat_map(|sp| {
            let n = r.pipelines.pipelines_of_pass_last_time(&sp.name);
            let modes: Vec<ForkMode> = match n {
                0 | 1 => vec![ForkMode::All],
                n => (0..n).map(ForkMode::Only).collect(),
            };
            modes.into_iter().map(move |m| (sp, m))
        })
        .collect();
    if !r.pipelines.parallel_builds || forks.len() < 2 {
        return;
    }
    // Whether earlier frames were still on the GPU, noted before any thread builds.
    r.pipelines.note_gpu_state_now(&r.ctx.device);
    let (graph, gpu, resources, frame_uniform, size, scene) = (
        cx.graph,
        cx.gpu,
        cx.resources,
        cx.frame_uniform,
        cx.size,
        cx.scene,
    );
    let start = Instant::now();
    let forks: Vec<Option<pipelines::ForkBuilds>> = std::thread::scope(|s| {
        let threads: Vec<_> = forks
            .iter()
            .map(|&(sp, mode)| {
                let mut fork = Renderer {
                    ctx: r.ctx.clone(),
                    shaders: r.shaders.clone(),
                    pipelines: r.pipelines.fork(mode),
                    layouts: r.layouts.clone(),
                };
                s.spawn(move || {
                    fork.pipelines.set_pass(&sp.name);
                    // Error scopes are per thread: this one sees this pass's errors.
                    let scope = fork
                        .ctx
                        .device
                        .push_error_scope(wgpu::ErrorFilter::Validation);
                    let prepared = passes::prepare(
                        &mut PrepareCtx {
                            renderer: &mut fork,
                            graph,
                            gpu,
                            resources,
                            frame_uniform,
                            size,
                            scene,
                            light_count: &Default::default(),
                        },
                        sp,
                    )
                    .is_ok();
                    let clean = pollster::block_on(scope.pop()).is_none();
                    // A fork of one build ends its pass early on purpose (and may meet
                    // errors its stand-ins made): its build's own scope decides.
                    let keep = match mode {
                        ForkMode::All => prepared && clean,
                        ForkMode::Only(_) => fork.pipelines.fork_build_clean(),
                    };
                    keep.then(|| fork.pipelines.into_builds())
                })
            })
            .collect();
        threads
            .into_iter()
            .map(|t| t.join().ok().flatten())
            .collect()
    });
    let mut built = 0;
    let mut threads = 0;
    for f in forks.into_iter().flatten().filter(|f| !f.is_empty()) {
        built += f.len();
        threads += 1;
        r.pipelines.adopt(f);
    }
    if built > 0 {
        r.pipelines.add_build_wall(start.elapsed());
        r.pipelines.build_threads = threads;
    }
}
