//! Pipeline cache: keyed by shader file, defines, material and target state, so an
//! unchanged pass reuses its pipelines across graph recompiles and frames. It counts
//! hits, misses and builds and times composing and building, so hot reload can show
//! (and tests can check) exactly what an edit rebuilt.

use crate::gpu::pipeline_cache::DiskPipelineCache;
use crate::shader::{reflect_bindings, Composed, ReflectedBinding, ShaderError, ShaderLibrary};
use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

mod key;
mod stats;
pub use key::PipelineKey;
pub use stats::{CacheCounters, PipelineBuild};

thread_local! {
    /// The driver cache of the pipeline a build function on this thread is building.
    static DRIVER_CACHE: RefCell<Option<wgpu::PipelineCache>> = const { RefCell::new(None) };
}

/// The driver's pipeline cache (kept on disk) for the pipeline being built: every
/// pipeline descriptor made in a [`PipelineCache`] build function sets
/// `cache: driver_cache().as_ref()`. `None` outside build functions and where the adapter
/// has no pipeline cache.
pub fn driver_cache() -> Option<wgpu::PipelineCache> {
    DRIVER_CACHE.with(|c| c.borrow().clone())
}

/// Runs `f` with [`driver_cache`] answering `cache`, then restores what it answered.
fn with_driver_cache<R>(cache: Option<wgpu::PipelineCache>, f: impl FnOnce() -> R) -> R {
    let previous = DRIVER_CACHE.with(|c| c.replace(cache));
    let result = f();
    DRIVER_CACHE.with(|c| c.replace(previous));
    result
}

/// A built render or compute pipeline, shared between the passes that use it.
#[derive(Clone)]
pub enum Pipeline {
    /// A render pipeline (raster passes).
    Render(Arc<wgpu::RenderPipeline>),
    /// A compute pipeline.
    Compute(Arc<wgpu::ComputePipeline>),
}

impl Pipeline {
    /// A compute pipeline; `layout: None` derives the layout from the shader.
    pub fn compute(
        device: &wgpu::Device,
        label: &str,
        layout: Option<&wgpu::PipelineLayout>,
        module: &wgpu::ShaderModule,
        entry: &str,
    ) -> Self {
        Pipeline::Compute(Arc::new(device.create_compute_pipeline(
            &wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout,
                module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: driver_cache().as_ref(),
            },
        )))
    }
}

#[derive(Clone)]
struct Entry {
    pipeline: Pipeline,
    /// The composed shader's bindings, as naga reflects them.
    bindings: Arc<[ReflectedBinding]>,
    /// Every shader file that went into it (includes too).
    files: Vec<PathBuf>,
    /// The generation that last asked for it (see [`PipelineCache::next_generation`]).
    last_used: u64,
    /// Built on another thread ahead of the sequential prepare ([`PipelineCache::fork`]):
    /// the first request counts it as the miss and build it replaced, with these times,
    /// so counts, order and names are what a sequential prepare reports.
    prebuilt: Option<PipelineBuild>,
}

/// What a fork of the cache builds on its thread.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ForkMode {
    /// Every pipeline its pass lacks, one after another (the main cache: always).
    #[default]
    All,
    /// Only the pass's `n`-th missing pipeline (from 0), then stop the pass: the misses
    /// before it are answered with a stand-in (the pipeline of the same shader and state
    /// the edit replaced) so the pass gets that far. Several such forks build one pass's
    /// pipelines at once.
    Only(usize),
}

/// What a [`PipelineCache::fork`] built, for [`PipelineCache::adopt`].
pub struct ForkBuilds {
    entries: Vec<(PipelineKey, Entry)>,
}

impl ForkBuilds {
    pub fn len(&self) -> usize {
        self.entries.len()
    }
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

/// Render and compute pipelines by [`PipelineKey`], with counters and build times; shared
/// across frames and hot reloads so only what changed is rebuilt.
#[derive(Default)]
pub struct PipelineCache {
    pipelines: HashMap<PipelineKey, Entry>,
    /// Pipelines built since the cache was made.
    pub builds: usize,
    hits: usize,
    misses: usize,
    compose_time: Duration,
    /// Builds done ahead on other threads and taken over.
    prebuilt: usize,
    module_time: Duration,
    create_time: Duration,
    /// Keys built since the last [`take_built`](Self::take_built).
    built: Vec<PipelineKey>,
    /// What each build since the last [`take_builds`](Self::take_builds) cost.
    records: Vec<PipelineBuild>,
    /// The pass being prepared, named in [`PipelineBuild::pass`].
    pass: String,
    generation: u64,
    /// Whether the GPU was still busy when this generation's first build started
    /// (`None`: nothing built yet in this generation).
    gpu_busy: Option<bool>,
    /// Wait for the GPU to go idle before a generation's first build, and how long that took.
    pub wait_for_idle_before_build: bool,
    gpu_wait: Duration,
    /// The driver's pipeline cache on disk, handed to every build (see [`driver_cache`]).
    driver: Option<Arc<DiskPipelineCache>>,
    /// Prepare builds the pipelines a frame lacks on one thread per pass before the
    /// sequential prepare (see `Renderer::prepare_reusing`); on by default.
    pub parallel_builds: bool,
    /// Wall time of composing and building since the last
    /// [`take_build_wall`](Self::take_build_wall): the parallel phases, plus the builds
    /// done in sequence.
    build_wall: Duration,
    /// Threads that built pipelines in the last parallel phase (read by prepare).
    pub build_threads: usize,
    /// What this fork builds ([`ForkMode::All`] outside forks).
    fork_mode: ForkMode,
    /// Misses this fork has met.
    fork_misses: usize,
    /// Whether this fork's one build ([`ForkMode::Only`]) raised no validation error.
    fork_build_clean: bool,
    /// Entries dropped by [`invalidate_files`](Self::invalidate_files) until the next
    /// eviction: stand-ins for forks (never answered as hits).
    stale: HashMap<PipelineKey, Entry>,
    /// Per pass, the keys it asked for since the generation began (hashes).
    requested: HashMap<String, std::collections::HashSet<u64>>,
    /// Per pass, how many distinct pipelines it asked for in the last generation.
    keys_last_generation: HashMap<String, usize>,
}

/// Returned by a fork's request to end its pass early (never seen outside forks).
fn stop_fork() -> ShaderError {
    ShaderError::Io {
        file: PathBuf::from("<parallel build>"),
        message: "the fork built its pipeline".into(),
    }
}

/// Whether the GPU was busy with earlier submissions when a prepare's first pipeline
/// build began, and how long waiting for it took (zero unless asked for).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GpuStateAtBuild {
    /// `None`: nothing was built.
    pub busy: Option<bool>,
    /// How long waiting for the GPU took.
    pub wait: Duration,
}

impl PipelineCache {
    /// An empty cache whose builds use (and fill) the driver's pipeline cache `driver`.
    pub(crate) fn with_driver_cache(driver: Option<Arc<DiskPipelineCache>>) -> Self {
        Self {
            driver,
            parallel_builds: true,
            ..Default::default()
        }
    }

    /// A cache for another thread: the same pipelines (shared handles), generation,
    /// driver cache and pass, fresh counters. What it builds comes back with
    /// [`into_builds`](Self::into_builds) and [`adopt`](Self::adopt).
    pub fn fork(&self, mode: ForkMode) -> Self {
        Self {
            pipelines: self.pipelines.clone(),
            stale: self.stale.clone(),
            fork_mode: mode,
            fork_build_clean: true,
            generation: self.generation,
            // The GPU's state was noted (or not needed) before forking.
            gpu_busy: Some(self.gpu_busy.unwrap_or(false)),
            driver: self.driver.clone(),
            pass: self.pass.clone(),
            ..Default::default()
        }
    }

    /// How many distinct pipelines `pass` asked for in the last generation (0: unknown).
    pub(crate) fn pipelines_of_pass_last_time(&self, pass: &str) -> usize {
        self.keys_last_generation.get(pass).copied().unwrap_or(0)
    }

    /// Whether this `ForkMode::Only` fork's build raised no validation error.
    pub(crate) fn fork_build_clean(&self) -> bool {
        self.fork_build_clean
    }

    /// The pipelines this fork built (not those it was forked with).
    pub fn into_builds(mut self) -> ForkBuilds {
        let mut records = self.records.into_iter();
        let entries = self
            .built
            .into_iter()
            .filter_map(|key| {
                let mut entry = self.pipelines.remove(&key)?;
                entry.prebuilt = records.next();
                Some((key, entry))
            })
            .collect();
        ForkBuilds { entries }
    }

    /// Takes over what forks built, in the order given (the first of two builds of one
    /// key wins; forks are adopted in pass order, so the result does not depend on which
    /// thread finished first).
    pub fn adopt(&mut self, builds: ForkBuilds) {
        for (key, entry) in builds.entries {
            self.pipelines.entry(key).or_insert(entry);
        }
    }

    /// Adds the wall time of a parallel build phase.
    pub(crate) fn add_build_wall(&mut self, wall: Duration) {
        self.build_wall += wall;
    }

    /// Wall time of composing and building since the last call.
    pub fn take_build_wall(&mut self) -> Duration {
        std::mem::take(&mut self.build_wall)
    }

    /// Notes now whether the GPU is busy, before builds on other threads begin.
    pub(crate) fn note_gpu_state_now(&mut self, device: &wgpu::Device) {
        self.note_gpu_state(device);
    }

    /// For a fork: a pipeline to stand in for `key` until the fork reaches the one it
    /// builds: `key`'s own entry the edit made stale, else one of the same shader and
    /// state (another material, other defines).
    fn stand_in(&self, key: &PipelineKey) -> Option<Pipeline> {
        if let Some(e) = self.stale.get(key) {
            return Some(e.pipeline.clone());
        }
        self.pipelines
            .iter()
            .chain(self.stale.iter())
            .find(|(k, _)| k.shader == key.shader && k.state == key.state)
            .map(|(_, e)| e.pipeline.clone())
    }

    /// Marks what forks built and nothing asked for as plain entries: a later request is
    /// a hit, as it would have been after a sequential build.
    pub(crate) fn settle_prebuilt(&mut self) {
        for e in self.pipelines.values_mut() {
            e.prebuilt = None;
        }
    }

    /// Saves the driver's pipeline cache if it holds anything new (after a reload's
    /// builds; it is saved on exit too). A failure is logged: the cache only saves time.
    pub(crate) fn save_driver_cache(&self) {
        if let Some(d) = &self.driver {
            d.save_or_warn();
        }
    }

    /// Returns the cached pipeline or composes, validates (naga, with file:line errors)
    /// and builds it with `build`.
    pub fn get_or_build(
        &mut self,
        shaders: &ShaderLibrary,
        key: PipelineKey,
        build: impl FnOnce(&Composed, wgpu::ShaderModule) -> Pipeline,
        device: &wgpu::Device,
    ) -> Result<Pipeline, ShaderError> {
        self.get_or_build_reflected(shaders, key, |c, m, _| build(c, m), device)
            .map(|(p, _)| p)
    }

    /// Like [`get_or_build`](Self::get_or_build), handing `build` the shader's reflected
    /// bindings (to make its layout from) and returning them with the pipeline.
    pub(crate) fn get_or_build_reflected(
        &mut self,
        shaders: &ShaderLibrary,
        key: PipelineKey,
        build: impl FnOnce(&Composed, wgpu::ShaderModule, &[ReflectedBinding]) -> Pipeline,
        device: &wgpu::Device,
    ) -> Result<(Pipeline, Arc<[ReflectedBinding]>), ShaderError> {
        if self.fork_mode == ForkMode::All {
            use std::hash::{Hash, Hasher};
            let mut h = std::collections::hash_map::DefaultHasher::new();
            key.hash(&mut h);
            self.requested
                .entry(self.pass.clone())
                .or_default()
                .insert(h.finish());
        }
        if let Some(e) = self.pipelines.get_mut(&key) {
            e.last_used = self.generation;
            match e.prebuilt.take() {
                // Built ahead on another thread: counted here, in request order.
                Some(mut record) => {
                    self.misses += 1;
                    self.builds += 1;
                    self.prebuilt += 1;
                    self.compose_time += record.compose;
                    self.module_time += record.module;
                    self.create_time += record.create;
                    self.pass.clone_into(&mut record.pass);
                    self.records.push(record);
                    self.built.push(key.clone());
                }
                None => self.hits += 1,
            }
            return Ok((e.pipeline.clone(), e.bindings.clone()));
        }
        self.misses += 1;
        let nth_miss = self.fork_misses;
        self.fork_misses += 1;
        let only = match self.fork_mode {
            ForkMode::All => None,
            ForkMode::Only(n) if nth_miss > n => return Err(stop_fork()),
            ForkMode::Only(n) => Some(n),
        };
        let start = Instant::now();
        let composed = shaders.compose(&key.shader, &key.defines, &key.virtual_code);
        let composed = composed.and_then(|c| c.validate().map(|m| (c, m)));
        let compose = start.elapsed();
        self.compose_time += compose;
        self.build_wall += compose;
        let (composed, naga_module) = composed?;
        let bindings: Arc<[ReflectedBinding]> = reflect_bindings(&naga_module).into();
        super::device_limits::check_storage_buffers(&key, &bindings, device)?;
        if only.is_some_and(|n| nth_miss < n) {
            // A miss before the one this fork builds: a stand-in lets the pass go on.
            return match self.stand_in(&key) {
                Some(p) => Ok((p, bindings)),
                None => Err(stop_fork()),
            };
        }
        // A fork's one build gets a scope of its own: the stand-ins may make errors
        // later in the pass that say nothing about this pipeline.
        let scope = only.map(|_| device.push_error_scope(wgpu::ErrorFilter::Validation));
        self.note_gpu_state(device);
        let start = Instant::now();
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(&key.shader),
            source: wgpu::ShaderSource::Wgsl(composed.text.clone().into()),
        });
        let module_time = start.elapsed();
        let start = Instant::now();
        let driver = self.driver.as_ref().map(|d| d.cache().clone());
        let pipeline = with_driver_cache(driver, || build(&composed, module, &bindings));
        let create = start.elapsed();
        if let Some(scope) = scope {
            self.fork_build_clean = pollster::block_on(scope.pop()).is_none();
        }
        self.build_wall += module_time + create;
        self.module_time += module_time;
        self.create_time += create;
        self.builds += 1;
        self.records.push(PipelineBuild {
            pass: self.pass.clone(),
            pipeline: key.short(),
            compose,
            module: module_time,
            create,
        });
        self.built.push(key.clone());
        self.pipelines.insert(
            key,
            Entry {
                pipeline: pipeline.clone(),
                bindings: bindings.clone(),
                files: composed.files.clone(),
                last_used: self.generation,
                prebuilt: None,
            },
        );
        if only.is_some() {
            // This fork's pipeline is built: the rest of the pass is other forks' work.
            return Err(stop_fork());
        }
        Ok((pipeline, bindings))
    }

    /// Pipelines the cache holds.
    pub fn len(&self) -> usize {
        self.pipelines.len()
    }
    /// Whether the cache holds no pipeline.
    pub fn is_empty(&self) -> bool {
        self.pipelines.is_empty()
    }

    /// A snapshot of the running totals.
    pub fn counters(&self) -> CacheCounters {
        CacheCounters {
            hits: self.hits,
            misses: self.misses,
            builds: self.builds,
            compose: self.compose_time,
            build: self.module_time + self.create_time,
            module: self.module_time,
            create: self.create_time,
            prebuilt: self.prebuilt,
        }
    }

    /// Names the pass whose pipelines are asked for next (in [`PipelineBuild::pass`]).
    pub fn set_pass(&mut self, pass: &str) {
        pass.clone_into(&mut self.pass);
    }

    /// What each build since the last call cost, oldest first.
    pub fn take_builds(&mut self) -> Vec<PipelineBuild> {
        std::mem::take(&mut self.records)
    }

    /// Whether the GPU was busy when this generation's first build began.
    pub(crate) fn gpu_state_at_build(&self) -> GpuStateAtBuild {
        GpuStateAtBuild {
            busy: self.gpu_busy,
            wait: self.gpu_wait,
        }
    }

    /// Before a generation's first build: records whether the queue still had work
    /// (a non-blocking poll) and, if asked, waits for it, timed. Drivers may serialise
    /// pipeline creation behind in-flight work; this tells the two apart.
    fn note_gpu_state(&mut self, device: &wgpu::Device) {
        if self.gpu_busy.is_some() {
            return;
        }
        let busy = match device.poll(wgpu::PollType::Poll) {
            Ok(status) => !status.is_queue_empty(),
            Err(e) => {
                log::warn!("pipeline cache: polling the device: {e}");
                false
            }
        };
        self.gpu_busy = Some(busy);
        if busy && self.wait_for_idle_before_build {
            let start = Instant::now();
            if let Err(e) = device.poll(wgpu::PollType::wait_indefinitely()) {
                log::warn!("pipeline cache: waiting for the GPU: {e}");
            }
            self.gpu_wait = start.elapsed();
        }
    }

    /// The keys built since the last call, oldest first.
    pub fn take_built(&mut self) -> Vec<PipelineKey> {
        std::mem::take(&mut self.built)
    }

    /// Starts a new generation: pipelines asked for from now on are marked with it, so
    /// [`evict_unused_since`](Self::evict_unused_since) can drop the ones a replaced frame
    /// alone used (old material versions, say) and the cache stays bounded under edits.
    pub fn next_generation(&mut self) -> u64 {
        self.keys_last_generation = std::mem::take(&mut self.requested)
            .into_iter()
            .map(|(pass, keys)| (pass, keys.len()))
            .collect();
        self.gpu_busy = None;
        self.gpu_wait = Duration::ZERO;
        self.generation += 1;
        self.generation
    }

    /// Drops every pipeline not asked for since `generation` began; returns how many.
    /// Frames already prepared keep theirs alive: this only affects later requests.
    pub fn evict_unused_since(&mut self, generation: u64) -> usize {
        self.stale.clear();
        let before = self.pipelines.len();
        self.pipelines.retain(|_, e| e.last_used >= generation);
        before - self.pipelines.len()
    }

    /// Drops every pipeline built from any of `files`, directly or through an include
    /// (hot reload); returns how many were dropped.
    pub fn invalidate_files(&mut self, files: &[PathBuf]) -> usize {
        let canonical = |p: &Path| p.canonicalize().ok();
        let same =
            |a: &Path, b: &Path| a == b || (canonical(a).is_some() && canonical(a) == canonical(b));
        let (dropped, kept): (HashMap<_, _>, HashMap<_, _>) = std::mem::take(&mut self.pipelines)
            .into_iter()
            .partition(|(_, e)| e.files.iter().any(|u| files.iter().any(|f| same(u, f))));
        self.pipelines = kept;
        let n = dropped.len();
        self.stale.extend(dropped);
        n
    }
}
