//! Pipeline cache: keyed by shader file, defines, material and target state, so an
//! unchanged pass reuses its pipelines across graph recompiles and frames.

use crate::shader::{Composed, ShaderError, ShaderLibrary};
use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct PipelineKey {
    pub shader: String,
    pub defines: BTreeMap<String, String>,
    /// Generated code's text (materials), part of the key so an edit rebuilds.
    pub virtual_code: BTreeMap<String, String>,
    /// Target formats, sample count, entry points...
    pub state: String,
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

#[derive(Default)]
pub struct PipelineCache {
    /// Each pipeline with every shader file that went into it (includes too).
    pipelines: HashMap<PipelineKey, (Pipeline, Vec<std::path::PathBuf>)>,
    pub builds: usize,
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
        if let Some((p, _)) = self.pipelines.get(&key) {
            return Ok(p.clone());
        }
        let composed = shaders.compose(&key.shader, &key.defines, &key.virtual_code)?;
        composed.validate()?;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(&key.shader),
            source: wgpu::ShaderSource::Wgsl(composed.text.clone().into()),
        });
        let pipeline = build(&composed, module);
        self.builds += 1;
        self.pipelines
            .insert(key, (pipeline.clone(), composed.files.clone()));
        Ok(pipeline)
    }

    pub fn len(&self) -> usize {
        self.pipelines.len()
    }
    pub fn is_empty(&self) -> bool {
        self.pipelines.is_empty()
    }
    /// Drops every pipeline built from any of `files`, directly or through an include
    /// (hot reload); returns how many were dropped.
    pub fn invalidate_files(&mut self, files: &[std::path::PathBuf]) -> usize {
        let same = |a: &std::path::Path, b: &std::path::Path| {
            a == b
                || (a.canonicalize().ok().is_some()
                    && a.canonicalize().ok() == b.canonicalize().ok())
        };
        let before = self.pipelines.len();
        self.pipelines
            .retain(|_, (_, used)| !used.iter().any(|u| files.iter().any(|f| same(u, f))));
        before - self.pipelines.len()
    }
}
