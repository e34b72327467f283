//! Running a sweep: each point's scene, graphs and reference prepared, the graphs timed
//! together (`bench::timing`), each image compared with the reference, one row a graph.

use super::seeds::{set_seed_columns, SeedRun};
use super::{Sweep, SweepError};
use crate::bench::cases::SceneCase;
use crate::bench::metrics::non_finite_pixels;
use crate::bench::report::{summarize, BenchRow, TimingSummary};
use crate::bench::{compare, CompareOptions};
use crate::bench::{sweep_columns, timing};
use crate::graph::{self, FrameSize};
use crate::render::{PreparedFrame, Renderer, SceneGpu};
use crate::scene::{self, lights::RandomLights, Scene};
use std::path::Path;

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
        if scene.all_lights_cast_shadows {
            for light in &mut s.lights {
                light.flags |= crate::scene::light_flags::CASTS_SHADOW;
            }
        }
        s.light_motion.clear();
    }
    s
}

/// How far a sweep is, for [`run`]'s callback.
pub enum SweepEvent<'a> {
    /// Point `index` (from 0) of `total` is starting; `point` names it.
    Start {
        /// 0-based index of the point.
        index: usize,
        /// Number of points in the sweep.
        total: usize,
        /// The point's label: scene, graph, light count and size.
        point: &'a str,
    },
    /// `done` points of `total` have finished, the last one gave `row`.
    Done {
        /// Points finished so far.
        done: usize,
        /// Number of points in the sweep.
        total: usize,
        /// The finished point's measurement.
        row: &'a BenchRow,
    },
}

/// How many NaN / Inf pixels a row lists by position (all are counted).
pub(crate) const NON_FINITE_EXAMPLES: usize = 16;

/// Runs the sweep; `progress` hears when each point starts and ends.
pub fn run(
    sweep: &Sweep,
    sweep_dir: &Path,
    renderer: &mut Renderer,
    mut progress: impl FnMut(SweepEvent),
) -> Result<Vec<BenchRow>, SweepError> {
    let counts: Vec<Option<u32>> = if sweep.lights.is_empty() {
        vec![None]
    } else {
        sweep.lights.iter().map(|&c| Some(c)).collect()
    };
    let cases: Vec<Option<&SceneCase>> = if sweep.cases.is_empty() {
        vec![None]
    } else {
        sweep.cases.iter().map(Some).collect()
    };
    let total = sweep.point_count();
    let mut rows = Vec::new();
    for spec in &sweep.scenes {
        let base_scene = load_scene(spec, sweep_dir)?;
        for case in &cases {
            for count in &counts {
                let scene = match count {
                    Some(c) => with_light_count(&base_scene, *c),
                    None => base_scene.clone(),
                };
                let scene = match case {
                    Some(case) => case
                        .apply(&scene)
                        .map_err(|m| SweepError::Scene(format!("{spec} case {}", case.name), m))?,
                    None => scene,
                };
                let gpu = SceneGpu::upload(&renderer.ctx.device, &renderer.ctx.queue, &scene)
                    .map_err(|e| SweepError::Scene(spec.clone(), e.to_string()))?;
                for &(width, height) in &sweep.resolutions {
                    let size = FrameSize {
                        width,
                        height,
                        lights: scene.lights.len() as u32,
                    };
                    // Each reference graph the point's graphs name, rendered once.
                    let mut references: Vec<(&str, Vec<[f32; 4]>)> = Vec::new();
                    if size.lights <= sweep.brute_force_limit {
                        for g in &sweep.graphs {
                            let name = sweep.reference_for(g);
                            if references.iter().all(|r| r.0 != name) {
                                let image = render_once(renderer, name, &scene, &gpu, size)?;
                                references.push((name, image));
                            }
                        }
                    }
                    let point = Point {
                        scene: &scene,
                        gpu: &gpu,
                        size,
                    };
                    let label = |g: &str| {
                        format!(
                            "{} {} {} lights {width}x{height}",
                            scene.name,
                            g.trim_end_matches(".ron"),
                            size.lights
                        )
                    };
                    progress(SweepEvent::Start {
                        index: rows.len(),
                        total,
                        point: &label(&sweep.graphs.join(", ")),
                    });
                    let prepared = sweep
                        .graphs
                        .iter()
                        .map(|g| prepare(g, &point, renderer))
                        .collect::<Result<Vec<_>, _>>()?;
                    let frames: Vec<&PreparedFrame> = prepared.iter().collect();
                    let (times, update_cpu_ms) = match sweep.animate {
                        None => (
                            timing::time_point(&frames, renderer, &sweep.method())?,
                            None,
                        ),
                        Some(step) => {
                            let moving = crate::bench::animate::time_moving(
                                &frames,
                                point.scene,
                                &gpu,
                                renderer,
                                &sweep.method(),
                                step,
                            )?;
                            (moving.times, Some(moving.update_cpu_ms))
                        }
                    };
                    for (i, ((g, frame), graph_times)) in sweep
                        .graphs
                        .iter()
                        .zip(&prepared)
                        .zip(&times.graphs)
                        .enumerate()
                    {
                        let mut row = BenchRow {
                            scene: scene.name.clone(),
                            technique: g.trim_end_matches(".ron").to_string(),
                            // Moving-light timings are told apart from still ones.
                            params: sweep
                                .animate
                                .map(|s| format!("animate={s}s"))
                                .unwrap_or_default(),
                            light_count: size.lights,
                            width,
                            height,
                            adapter: renderer.ctx.adapter_name(),
                            ..Default::default()
                        };
                        set_timing_columns(&mut row, sweep, graph_times, &times, renderer);
                        row.light_update_cpu_ms = update_cpu_ms
                            .as_ref()
                            .and_then(|ms| summarize(&ms[i]))
                            .map(|t| t.median);
                        let reference_name = sweep.reference_for(g);
                        let reference = references.iter().find(|r| r.0 == reference_name);
                        row.reference = reference.map(|r| r.0.trim_end_matches(".ron").to_string());
                        let reference = reference.map(|r| r.1.as_slice());
                        fill_row(sweep, g, frame, &point, reference, renderer, &mut row)?;
                        if let (s @ 1.., Some(reference)) = (sweep.seeds, reference) {
                            let run = SeedRun {
                                prepared: frame,
                                scene: &scene,
                                gpu: &gpu,
                                size,
                                graph_name: g,
                            };
                            set_seed_columns(&mut row, &run, reference, s, renderer)?;
                        }
                        rows.push(row);
                        progress(SweepEvent::Done {
                            done: rows.len(),
                            total,
                            row: rows.last().expect("just pushed"),
                        });
                    }
                }
            }
        }
    }
    Ok(rows)
}

/// What one point renders: a scene at a size.
struct Point<'a> {
    scene: &'a Scene,
    gpu: &'a SceneGpu,
    size: FrameSize,
}

fn prepare(
    graph_name: &str,
    point: &Point,
    renderer: &mut Renderer,
) -> Result<PreparedFrame, SweepError> {
    let checked = check_graph(graph_name, renderer)?;
    let compiled = graph::compile(checked, &point.scene.features(), point.size);
    Ok(renderer.prepare(compiled, point.scene, point.gpu, point.size, false)?)
}

/// The time columns of one graph's row: frame and pass medians with p10–p90 over every
/// timed frame, the range of its round medians, the warm-up and the SM clock.
fn set_timing_columns(
    row: &mut BenchRow,
    sweep: &Sweep,
    times: &timing::GraphTimes,
    point: &timing::PointTimes,
    renderer: &Renderer,
) {
    row.frame_ms = summarize(&times.frames);
    if row.frame_ms.is_none() {
        row.untimed = Some(if sweep.frames == 0 {
            "the sweep sets frames: 0".into()
        } else if !renderer.ctx.has_timestamps {
            format!("{} has no timestamp queries", renderer.ctx.adapter_name())
        } else {
            "no timestamps came back".into()
        });
    }
    row.pass_ms = times
        .per_pass
        .iter()
        .filter_map(|(n, v)| summarize(v).map(|t: TimingSummary| (n.clone(), t)))
        .collect();
    let rounds = &times.round_medians;
    if !rounds.is_empty() {
        row.rounds = Some(rounds.len() as u32);
        row.round_ms_min = rounds.iter().copied().reduce(f64::min);
        row.round_ms_max = rounds.iter().copied().reduce(f64::max);
    }
    row.warmup_s = Some(point.warmup.as_secs_f64());
    row.sm_mhz_start = point.clock_start.map(|c| c.mhz);
    row.sm_mhz_end = point.clock_end.map(|c| c.mhz);
    row.sm_mhz_max = point.clock_end.or(point.clock_start).map(|c| c.max_mhz);
}

/// Renders a timed graph's frame once more for its image and reports, compares it with the
/// reference and fills the rest of the row.
fn fill_row(
    sweep: &Sweep,
    graph_name: &str,
    prepared: &PreparedFrame,
    point: &Point,
    reference: Option<&[[f32; 4]]>,
    renderer: &mut Renderer,
    row: &mut BenchRow,
) -> Result<(), SweepError> {
    let Point { scene, gpu, size } = *point;
    let result = prepared.render(renderer)?;
    // Light statistics cost a frame of their own (an exact count is a brute-force pass), and
    // only forward shading gathers them.
    let light_stats = if sweep.light_stats && prepared.graph.has_forward_shading() {
        renderer
            .prepare(prepared.graph.clone(), scene, gpu, size, true)?
            .render(renderer)?
            .light_stats
    } else {
        None
    };
    if let Some(reference) = reference {
        let m = compare(
            reference,
            &result.image,
            size.width,
            size.height,
            &CompareOptions::default(),
        )
        .map_err(|e| SweepError::Graph(graph_name.into(), e.to_string()))?;
        row.set_metrics(&m);
    }
    let (non_finite, examples) = non_finite_pixels(&result.image, size.width, NON_FINITE_EXAMPLES);
    row.nan_pixels = Some(non_finite.nan_pixels as u64);
    row.inf_pixels = Some(non_finite.inf_pixels as u64);
    row.non_finite_examples = examples;
    row.lit_pixels = Some(
        result
            .image
            .iter()
            .filter(|p| p[..3].iter().any(|&c| c != 0.0))
            .count() as u64,
    );
    if let Some(c) = result.culling.first() {
        row.max_lights_per_tile = c.per_tile().into_iter().max();
        sweep_columns::set_list_columns(row, c);
    }
    if let Some(s) = &light_stats {
        row.listed_exact_ratio = Some(s.false_positive_ratio());
    }
    sweep_columns::set_shadow_columns(row, &prepared.graph, gpu, &result.shadows);
    sweep_columns::set_atlas_columns(row, &result);
    sweep_columns::set_link_columns(row, &result);
    Ok(())
}

fn render_once(
    renderer: &mut Renderer,
    graph_name: &str,
    scene: &Scene,
    gpu: &SceneGpu,
    size: FrameSize,
) -> Result<Vec<[f32; 4]>, SweepError> {
    let checked = check_graph(graph_name, renderer)?;
    let compiled = graph::compile(checked, &scene.features(), size);
    let prepared = renderer.prepare(compiled, scene, gpu, size, false)?;
    Ok(prepared.render(renderer)?.image)
}

/// Graph `name` of the project's graphs/ (the root's own file, else the built-in one),
/// parsed and validated.
fn check_graph(name: &str, renderer: &Renderer) -> Result<graph::CheckedGraph, SweepError> {
    let err = |e: String| SweepError::Graph(name.into(), e);
    let (path, text) = crate::shader::assets::project()
        .read(&format!("graphs/{name}"))
        .map_err(|e| err(e.to_string()))?;
    graph::check_text(&path, &text, &renderer.shaders).map_err(|e| err(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::with_light_count;
    use crate::scene::{builtin, light_flags};

    #[test]
    fn generated_lights_cast_where_the_scene_says_every_light_casts() {
        let mut harada = builtin::by_name("harada").expect("built-in harada");
        let casting = |s: &crate::scene::Scene| {
            s.lights
                .iter()
                .filter(|l| l.flags & light_flags::CASTS_SHADOW != 0)
                .count()
        };
        assert_eq!(casting(&with_light_count(&harada, 300)), 0);
        harada.all_lights_cast_shadows = true;
        let all = with_light_count(&harada, 300);
        assert_eq!((all.lights.len(), casting(&all)), (300, 300));
    }
}
