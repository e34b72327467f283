//! Pipeline cache: keyed by shader file, defines, material and target state, so an
//! unchanged pass reuses its pipelines across graph recompiles and frames. It counts
//! hits, misses and builds and times composing and building, so hot reload can show
//! (and tests can check) exactly what an edit rebuilt.

use crate::shader::{reflect_bindings, Composed, ReflectedBinding, ShaderError, ShaderLibrary};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PipelineKey {
    pub shader: String,
    pub defines: BTreeMap<String, String>,
    /// Generated code's text (materials), part of the key so an edit rebuilds.
    pub virtual_code: BTreeMap<String, String>,
    /// Target formats, sample count, entry points...
    pub state: String,
}

impl PipelineKey {
    /// A short human description: shader, defines, and the material the generated code
    /// comes from (its first line names it), e.g.
    /// ``forward/forward.wgsl [LIGHT_LISTS=1] material `box` ``.
    pub fn describe(&self) -> String {
        let mut out = self.shader.clone();
        if !self.defines.is_empty() {
            let d: Vec<String> = self
                .defines
                .iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect();
            out.push_str(&format!(" [{}]", d.join(" ")));
        }
        for (name, code) in &self.virtual_code {
            let first = code.lines().next().unwrap_or("");
            match first.split('`').nth(1) {
                Some(material) => out.push_str(&format!(" {name} `{material}`")),
                None => out.push_str(&format!(" <{name}>")),
            }
        }
        if !self.state.is_empty() {
            out.push_str(&format!(" ({})", self.state));
        }
        out
    }
}

#[derive(Clone)]
pub enum Pipeline {
    Render(Arc<wgpu::RenderPipeline>),
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
                cache: None,
            },
        )))
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
    /// Time spent creating shader modules and pipelines.
    pub build: Duration,
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
        }
    }
}

struct Entry {
    pipeline: Pipeline,
    /// The composed shader's bindings, as naga reflects them.
    bindings: Arc<[ReflectedBinding]>,
    /// Every shader file that went into it (includes too).
    files: Vec<PathBuf>,
    /// The generation that last asked for it (see [`PipelineCache::next_generation`]).
    last_used: u64,
}

#[derive(Default)]
pub struct PipelineCache {
    pipelines: HashMap<PipelineKey, Entry>,
    pub builds: usize,
    hits: usize,
    misses: usize,
    compose_time: Duration,
    build_time: Duration,
    /// Keys built since the last [`take_built`](Self::take_built).
    built: Vec<PipelineKey>,
    generation: u64,
}

impl PipelineCache {
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
    pub fn get_or_build_reflected(
        &mut self,
        shaders: &ShaderLibrary,
        key: PipelineKey,
        build: impl FnOnce(&Composed, wgpu::ShaderModule, &[ReflectedBinding]) -> Pipeline,
        device: &wgpu::Device,
    ) -> Result<(Pipeline, Arc<[ReflectedBinding]>), ShaderError> {
        if let Some(e) = self.pipelines.get_mut(&key) {
            e.last_used = self.generation;
            self.hits += 1;
            return Ok((e.pipeline.clone(), e.bindings.clone()));
        }
        self.misses += 1;
        let start = Instant::now();
        let composed = shaders.compose(&key.shader, &key.defines, &key.virtual_code);
        let composed = composed.and_then(|c| c.validate().map(|m| (c, m)));
        self.compose_time += start.elapsed();
        let (composed, naga_module) = composed?;
        let bindings: Arc<[ReflectedBinding]> = reflect_bindings(&naga_module).into();
        let start = Instant::now();
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(&key.shader),
            source: wgpu::ShaderSource::Wgsl(composed.text.clone().into()),
        });
        let pipeline = build(&composed, module, &bindings);
        self.build_time += start.elapsed();
        self.builds += 1;
        self.built.push(key.clone());
        self.pipelines.insert(
            key,
            Entry {
                pipeline: pipeline.clone(),
                bindings: bindings.clone(),
                files: composed.files.clone(),
                last_used: self.generation,
            },
        );
        Ok((pipeline, bindings))
    }

    pub fn len(&self) -> usize {
        self.pipelines.len()
    }
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
            build: self.build_time,
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
        self.generation += 1;
        self.generation
    }

    /// Drops every pipeline not asked for since `generation` began; returns how many.
    /// Frames already prepared keep theirs alive: this only affects later requests.
    pub fn evict_unused_since(&mut self, generation: u64) -> usize {
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
        let before = self.pipelines.len();
        self.pipelines
            .retain(|_, e| !e.files.iter().any(|u| files.iter().any(|f| same(u, f))));
        before - self.pipelines.len()
    }
}
