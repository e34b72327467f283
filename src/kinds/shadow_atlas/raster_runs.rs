//! The compute atlas's raster runs (`raster.rs`): the solid casters' run, then one per
//! alpha-masked caster material (`ALPHA_TEST`, its material code and textures), each a
//! depth pass and, for the reflective shadow maps, an id pass, with their own counters
//! and indirect arguments.

use super::{pass_error, PrepareCtx};
use crate::render::bind::BindingSet;
use crate::render::pipelines::{Pipeline, PipelineKey};
use crate::render::RenderError;
use std::collections::BTreeMap;
use std::sync::Arc;

const SHADER: &str = "shadow/atlas_raster.wgsl";
/// Counter words (the shader's RECORDS..SERIAL_CELLS).
const COUNTERS: u64 = 4;

/// One pass of a raster run over the depth buffer (the depth, or with IDS the nearest
/// triangle): its pipelines, and its own counters and arguments (the passes run in one
/// compute pass, so none can clear another's).
pub(super) struct RunPass {
    pub(super) setup: Arc<wgpu::ComputePipeline>,
    pub(super) raster: Arc<wgpu::ComputePipeline>,
    pub(super) ids: bool,
    pub(super) counters: wgpu::Buffer,
    pub(super) args: wgpu::Buffer,
}

/// A raster run: the solid casters (run 0), or one alpha-masked material's casters,
/// alpha-tested against its material.
pub(super) struct Run {
    /// The depth pass, then (for the reflective shadow maps' buffers) the IDS pass.
    pub(super) passes: Vec<RunPass>,
    /// This run's work and list capacities, with its first job.
    pub(super) params: wgpu::Buffer,
    /// The material's textures (group 2), for a textured masked material.
    pub(super) textures: Option<wgpu::BindGroup>,
    /// Whether it alpha-tests (binds the merged geometry and the views in raster).
    pub(super) masked: bool,
}

/// A storage buffer of at least 16 bytes, writable by the queue.
pub(super) fn storage(
    device: &wgpu::Device,
    label: &str,
    bytes: u64,
    extra: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(16),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | extra,
        mapped_at_creation: false,
    })
}

/// A 32-byte uniform buffer the queue writes (a run's or the store's parameters).
pub(super) fn uniform(device: &wgpu::Device, label: &str) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: 32,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A raster run's counters (read back for the report) and its indirect arguments.
fn counters_and_args(device: &wgpu::Device, what: &str) -> [wgpu::Buffer; 2] {
    [
        storage(
            device,
            &format!("{what} counters"),
            4 * COUNTERS,
            wgpu::BufferUsages::COPY_SRC,
        ),
        storage(
            device,
            &format!("{what} arguments"),
            16,
            wgpu::BufferUsages::INDIRECT,
        ),
    ]
}

/// The raster runs over `offered` (every buffer under its shader name but `params`,
/// `counters` and `args`, which each run and pass adds): the solid casters', then one per
/// material of `masked`; with `with_ids` each also an id pass. `base_defines` gives a
/// stage's defines.
pub(super) fn prepare_runs(
    cx: &mut PrepareCtx,
    pass: &str,
    masked: &[usize],
    with_ids: bool,
    base_defines: &dyn Fn(&str) -> Vec<(String, String)>,
    offered: &BindingSet,
) -> Result<Vec<Run>, RenderError> {
    let device = cx.device();
    let mut runs = Vec::new();
    for run in std::iter::once(None).chain(masked.iter().copied().map(Some)) {
        let params = uniform(&device, "atlas raster parameters");
        let mut offered = offered.clone();
        offered.buffer("params", &params);
        let mut passes = Vec::new();
        let mut textures = None;
        for ids_pass in [false, true] {
            if ids_pass && !with_ids {
                continue;
            }
            let what = if ids_pass {
                "rsm raster id"
            } else {
                "atlas raster"
            };
            let [counters, args] = counters_and_args(&device, what);
            offered.buffer("counters", &counters);
            offered.buffer("args", &args);
            let stage = |stage: &str| {
                let mut d = base_defines(stage);
                if ids_pass {
                    d.push(("IDS".into(), "1".into()));
                }
                if stage == "SETUP" && (ids_pass || run.is_some()) {
                    d.push(("TRI_IDS".into(), "1".into()));
                }
                d
            };
            let (setup, raster) = match run {
                None => (
                    plain_pipeline(cx, pass, stage("SETUP"), "setup")?,
                    plain_pipeline(cx, pass, stage("RASTER"), "raster")?,
                ),
                Some(material) => {
                    let (setup, _) =
                        masked_pipeline(cx, pass, stage("SETUP"), "setup", material, &offered)?;
                    // Both stages bind the material's textures alike: one bind group.
                    let (raster, t) =
                        masked_pipeline(cx, pass, stage("RASTER"), "raster", material, &offered)?;
                    textures = t;
                    (setup, raster)
                }
            };
            passes.push(RunPass {
                setup,
                raster,
                ids: ids_pass,
                counters,
                args,
            });
        }
        runs.push(Run {
            passes,
            params,
            textures,
            masked: run.is_some(),
        });
    }
    Ok(runs)
}

/// A pipeline of the shader without a material (group 0 only).
pub(super) fn plain_pipeline(
    cx: &mut PrepareCtx,
    pass: &str,
    defines: Vec<(String, String)>,
    entry: &str,
) -> Result<Arc<wgpu::ComputePipeline>, RenderError> {
    let key = PipelineKey {
        shader: SHADER.into(),
        defines: defines.into_iter().collect(),
        virtual_code: BTreeMap::new(),
        state: String::new(),
    };
    let device = cx.device();
    let layouts = cx.renderer.layouts.clone();
    let (p, _) = cx
        .renderer
        .pipelines
        .get_or_build_reflected(
            &cx.renderer.shaders,
            key,
            |_, module, bindings| {
                let bgl = layouts.get(
                    &device,
                    crate::render::bind::layout_entries(bindings, 0, wgpu::ShaderStages::COMPUTE),
                );
                let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some(entry),
                    bind_group_layouts: &[Some(&*bgl)],
                    immediate_size: 0,
                });
                Pipeline::compute(&device, entry, Some(&pl), &module, entry)
            },
            &device,
        )
        .map_err(|source| RenderError::Shader {
            pass: pass.to_string(),
            source,
        })?;
    match p {
        Pipeline::Compute(p) => Ok(p),
        _ => Err(pass_error(pass, "expected a compute pipeline".into())),
    }
}

/// A pipeline of the shader alpha-testing `material` (its code, and its textures bound
/// in group 2, returned with it).
fn masked_pipeline(
    cx: &mut PrepareCtx,
    pass: &str,
    mut defines: Vec<(String, String)>,
    entry: &str,
    material: usize,
    offered: &BindingSet,
) -> Result<(Arc<wgpu::ComputePipeline>, Option<wgpu::BindGroup>), RenderError> {
    let m = &cx.gpu.materials[material];
    defines.push(("ALPHA_TEST".into(), "1".into()));
    defines.push(("MATERIAL_INDEX".into(), format!("{material}u")));
    if m.textures.is_some() {
        defines.push(("MATERIAL_TEXTURED".into(), "1".into()));
    }
    let key = PipelineKey {
        shader: SHADER.into(),
        defines: defines.into_iter().collect(),
        virtual_code: BTreeMap::from([("material".to_string(), m.wgsl_for_compute().to_string())]),
        state: entry.into(),
    };
    let textures = m.textures.clone();
    let label = format!("{pass} (alpha test of material '{}')", m.name);
    let (pipeline, _, textures) =
        cx.compute_pipeline_with_material(&label, key, entry, offered, textures.as_ref())?;
    Ok((pipeline, textures))
}
