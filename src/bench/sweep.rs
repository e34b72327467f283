//! Benchmark sweeps: scenes × light counts × resolutions × graphs, each point timed on
//! the GPU (warm-up, then N frames, median and spread per pass) and compared with the
//! brute-force image of the same scene.

use super::report::{summarize, BenchRow};
use super::{compare, CompareOptions};
use crate::graph::{self, FrameSize};
use crate::render::{RenderError, Renderer, SceneGpu};
use crate::scene::{self, lights::RandomLights, Scene};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use thiserror::Error;

#[derive(Clone, Debug, Deserialize)]
#[serde(rename = "Sweep", deny_unknown_fields)]
pub struct Sweep {
    /// `builtin:NAME` or a scene file path (relative to the sweep file).
    pub scenes: Vec<String>,
    /// Graph files, relative to the project's graphs/ folder.
    pub graphs: Vec<String>,
    /// Light counts; empty keeps each scene's own lights. Lights are placed uniformly
    /// in the scene bounds (AMD sample: radius 0.075 × |half-extent|, half spots).
    #[serde(default)]
    pub lights: Vec<u32>,
    pub resolutions: Vec<(u32, u32)>,
    #[serde(default = "default_warmup")]
    pub warmup: u32,
    #[serde(default = "default_frames")]
    pub frames: u32,
    /// Above this many lights the brute-force reference is not run (no error columns).
    #[serde(default = "default_brute_force_limit")]
    pub brute_force_limit: u32,
}

fn default_warmup() -> u32 {
    5
}
fn default_frames() -> u32 {
    30
}
fn default_brute_force_limit() -> u32 {
    16384
}

#[derive(Debug, Error)]
pub enum SweepError {
    #[error("{file}: {message}")]
    File { file: PathBuf, message: String },
    #[error("scene {0}: {1}")]
    Scene(String, String),
    #[error("graph {0}: {1}")]
    Graph(String, String),
    #[error(transparent)]
    Render(#[from] RenderError),
}

impl Sweep {
    pub fn load(path: &Path) -> Result<Self, SweepError> {
        let text = std::fs::read_to_string(path).map_err(|e| SweepError::File {
            file: path.to_path_buf(),
            message: e.to_string(),
        })?;
        ron::from_str(&text).map_err(|e| SweepError::File {
            file: path.to_path_buf(),
            message: format!("{}:{}: {}", e.span.start.line, e.span.start.col, e.code),
        })
    }
}

fn load_scene(spec: &str, base: &Path) -> Result<Scene, SweepError> {
    if let Some(name) = spec.strip_prefix("builtin:") {
        return scene::builtin::by_name(name)
            .ok_or_else(|| SweepError::Scene(spec.into(), "no such built-in scene".into()));
    }
    scene::load(&base.join(spec))
        .map(|l| l.scene)
        .map_err(|e| SweepError::Scene(spec.into(), e.to_string()))
}

/// The scene with `count` lights spread uniformly through its bounds.
pub fn with_light_count(scene: &Scene, count: u32) -> Scene {
    let mut s = scene.clone();
    if let Some((lo, hi)) = scene.bounds() {
        let r = 0.075 * ((hi - lo) * 0.5).length();
        let mut set = RandomLights::in_box(count, lo, hi, 0x5eed);
        set.range = (r, r);
        set.intensity = (r * r * 0.5, r * r * 2.0);
        s.lights = set.generate(Some((lo, hi)));
    }
    s
}

/// Runs the sweep; `progress` is called after each point with (done, total).
pub fn run(
    sweep: &Sweep,
    sweep_dir: &Path,
    renderer: &mut Renderer,
    mut progress: impl FnMut(usize, usize, &BenchRow),
) -> Result<Vec<BenchRow>, SweepError> {
    let graphs_dir = crate::project_root().join("graphs");
    let counts: Vec<Option<u32>> = if sweep.lights.is_empty() {
        vec![None]
    } else {
        sweep.lights.iter().map(|&c| Some(c)).collect()
    };
    let total = sweep.scenes.len() * counts.len() * sweep.resolutions.len() * sweep.graphs.len();
    let adapter = renderer.ctx.adapter_name();
    let mut rows = Vec::new();
    for spec in &sweep.scenes {
        let base_scene = load_scene(spec, sweep_dir)?;
        for count in &counts {
            let scene = match count {
                Some(c) => with_light_count(&base_scene, *c),
                None => base_scene.clone(),
            };
            let gpu = SceneGpu::upload(&renderer.ctx.device, &renderer.ctx.queue, &scene)
                .map_err(|e| SweepError::Scene(spec.clone(), e.to_string()))?;
            for &(width, height) in &sweep.resolutions {
                let size = FrameSize {
                    width,
                    height,
                    lights: scene.lights.len() as u32,
                };
                let reference = if size.lights <= sweep.brute_force_limit {
                    Some(render_once(
                        renderer,
                        &graphs_dir.join("brute_force.ron"),
                        &scene,
                        &gpu,
                        size,
                    )?)
                } else {
                    None
                };
                for g in &sweep.graphs {
                    let path = graphs_dir.join(g);
                    let checked = graph::check_file(&path, &renderer.shaders)
                        .map_err(|e| SweepError::Graph(g.clone(), e.to_string()))?;
                    let compiled = graph::compile(checked, &scene.features(), size);
                    let prepared = renderer.prepare(compiled, &scene, &gpu, size, false)?;
                    for _ in 0..sweep.warmup {
                        prepared.execute(renderer)?;
                    }
                    let mut frames = Vec::new();
                    let mut per_pass: Vec<(String, Vec<f64>)> = Vec::new();
                    for _ in 0..sweep.frames {
                        if let Some(times) = prepared.execute(renderer)? {
                            frames.push(times.iter().map(|t| t.1).sum::<f64>());
                            for (name, ms) in times {
                                match per_pass.iter_mut().find(|p| p.0 == name) {
                                    Some(p) => p.1.push(ms),
                                    None => per_pass.push((name, vec![ms])),
                                }
                            }
                        }
                    }
                    let result = prepared.render(renderer)?;
                    let stats_frame = renderer
                        .prepare(
                            prepared.graph.clone(),
                            &scene,
                            &gpu,
                            size,
                            prepared.graph.has_forward_shading(),
                        )?
                        .render(renderer)?;
                    let mut row = BenchRow {
                        scene: scene.name.clone(),
                        technique: g.trim_end_matches(".ron").to_string(),
                        params: String::new(),
                        light_count: size.lights,
                        width,
                        height,
                        adapter: adapter.clone(),
                        ..Default::default()
                    };
                    if let Some(t) = summarize(&frames) {
                        row.frame_ms_median = t.median;
                        row.frame_ms_p10 = t.p10;
                        row.frame_ms_p90 = t.p90;
                    }
                    row.pass_ms_median = per_pass
                        .iter()
                        .filter_map(|(n, v)| summarize(v).map(|t| (n.clone(), t.median)))
                        .collect();
                    if let Some(reference) = &reference {
                        let m = compare(
                            reference,
                            &result.image,
                            width,
                            height,
                            &CompareOptions::default(),
                        )
                        .map_err(|e| SweepError::Graph(g.clone(), e.to_string()))?;
                        row.set_metrics(&m);
                    }
                    row.nan_pixels = Some(
                        result
                            .image
                            .iter()
                            .filter(|p| p.iter().any(|c| !c.is_finite()))
                            .count() as u64,
                    );
                    if let Some(c) = stats_frame.culling.first() {
                        row.max_lights_per_tile = c.per_tile().into_iter().max();
                        row.overflow_tiles = Some(c.overflowed_lists);
                    }
                    if let Some(s) = &stats_frame.light_stats {
                        row.listed_exact_ratio = Some(s.false_positive_ratio());
                    }
                    rows.push(row);
                    progress(rows.len(), total, rows.last().unwrap());
                }
            }
        }
    }
    Ok(rows)
}

fn render_once(
    renderer: &mut Renderer,
    graph_path: &Path,
    scene: &Scene,
    gpu: &SceneGpu,
    size: FrameSize,
) -> Result<Vec<[f32; 4]>, SweepError> {
    let checked = graph::check_file(graph_path, &renderer.shaders)
        .map_err(|e| SweepError::Graph(graph_path.display().to_string(), e.to_string()))?;
    let compiled = graph::compile(checked, &scene.features(), size);
    let prepared = renderer.prepare(compiled, scene, gpu, size, false)?;
    Ok(prepared.render(renderer)?.image)
}
