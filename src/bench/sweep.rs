//! Benchmark sweeps: scenes × light counts × resolutions × graphs. The graphs of a point
//! are timed together on the GPU (warmed up by time, then interleaved rounds: see
//! `bench::timing`) and each is compared with the reference image of the same scene
//! (brute force unless the sweep names another graph).

use super::cases::SceneCase;
use super::metrics::non_finite_pixels;
use super::report::{summarize, BenchRow, TimingSummary};
use super::{compare, CompareOptions};
use super::{sweep_columns, timing};
use crate::graph::{self, FrameSize};
use crate::render::{PreparedFrame, RenderError, Renderer, SceneGpu};
use crate::scene::{self, lights::RandomLights, Scene};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// A sweep file (RON, scene-file extensions: `Some(..)` may be left out, `Random(count: ..)`).
/// Every point is a scene × case × light count × resolution × graph.
#[derive(Clone, Debug, Deserialize)]
#[serde(rename = "Sweep", deny_unknown_fields)]
pub struct Sweep {
    /// `builtin:NAME` or a scene file path (relative to the sweep file).
    pub(crate) scenes: Vec<String>,
    /// Graph files, relative to the project's graphs/ folder.
    pub graphs: Vec<String>,
    /// Light counts; empty keeps each scene's own lights. Lights are placed uniformly
    /// in the scene bounds (AMD sample: radius 0.075 × |half-extent|, half spots).
    #[serde(default)]
    pub lights: Vec<u32>,
    /// Variations of every scene (lights, ranges, intensities, near/far, camera at a light's
    /// centre), applied after the light count: see [`SceneCase`]. Empty runs the scenes as
    /// they are.
    #[serde(default)]
    pub(crate) cases: Vec<SceneCase>,
    /// Output sizes (width, height), each side 1..=16384.
    pub resolutions: Vec<(u32, u32)>,
    /// Warm-up frames every graph of a point runs at least.
    #[serde(default = "default_warmup")]
    pub warmup: u32,
    /// Wall-clock seconds the graphs of a point run, in turn, before timing starts: GPUs
    /// reach their clocks after about a second of work.
    #[serde(default = "default_warmup_seconds")]
    pub warmup_seconds: f64,
    /// Timed frames per graph, split over `rounds` rounds (rounded up).
    #[serde(default = "default_frames")]
    pub frames: u32,
    /// Rounds of timed frames; each runs every graph of the point in turn.
    #[serde(default = "default_rounds")]
    pub rounds: u32,
    /// Above this many lights the reference is not run (no error columns).
    #[serde(default = "default_brute_force_limit")]
    pub(crate) brute_force_limit: u32,
    /// The graph whose image the error columns compare against, like `graphs` (default
    /// `brute_force.ron`). Brute force does not trace shadows: name a shadow-tracing graph to
    /// compare ray-cast shadows with something shadowed.
    #[serde(default = "default_reference")]
    pub(crate) reference: String,
    /// Per-graph exceptions to `reference`: graph → its reference graph, e.g.
    /// `{"raycast_shadows.ron": "raycast_shadows_naive.ron"}`. Keys must be in `graphs`.
    #[serde(default)]
    pub(crate) references: BTreeMap<String, String>,
    /// Render an extra frame per point for the light statistics (the listed/exact column);
    /// it costs as much as a brute-force frame.
    #[serde(default = "yes")]
    pub(crate) light_stats: bool,
    /// Seconds of light motion between frames: every warm-up and timed frame first moves
    /// the lights there (`PreparedFrame::update_lights`). See [`crate::bench::animate`].
    #[serde(default)]
    pub(crate) animate: Option<f64>,
}

fn yes() -> bool {
    true
}
fn default_warmup() -> u32 {
    5
}
fn default_warmup_seconds() -> f64 {
    1.0
}
fn default_frames() -> u32 {
    30
}
fn default_rounds() -> u32 {
    5
}
fn default_brute_force_limit() -> u32 {
    16384
}
fn default_reference() -> String {
    "brute_force.ron".into()
}

/// Most timed frames per graph and point: 100,000 frames of a 1 ms graph already take
/// 100 s a point; the times are kept in memory (8 bytes a frame).
pub const MAX_FRAMES: u32 = 100_000;
/// Most warm-up frames per graph and point (warming up by time is what reaches the clocks).
pub const MAX_WARMUP_FRAMES: u32 = 100_000;
/// Most points one sweep runs (scenes × cases × light counts × resolutions × graphs):
/// every point renders and times each of its graphs, so 100,000 already take days; the
/// product of five long lists would also overflow the count.
pub const MAX_POINTS: u64 = 100_000;
/// Most rounds per point: each round keeps a median; more rounds than timed frames do not
/// run anyway (one frame a round at least).
pub const MAX_ROUNDS: u32 = 10_000;

/// `LINE: ` of the first `field:` outside comments (a whole identifier), or nothing.
fn field_line(text: &str, field: &str) -> String {
    text.lines()
        .position(|l| {
            let code = l.split("//").next().unwrap_or("");
            code.match_indices(field).any(|(i, _)| {
                let before = code[..i].chars().next_back();
                let after = code[i + field.len()..].trim_start();
                !before.is_some_and(|c| c.is_alphanumeric() || c == '_') && after.starts_with(':')
            })
        })
        .map_or(String::new(), |i| format!("{}: ", i + 1))
}

/// Why a sweep stopped.
#[derive(Debug, Error)]
pub enum SweepError {
    /// The sweep file could not be read or parsed.
    #[error("{file}: {message}")]
    File {
        /// The sweep file.
        file: PathBuf,
        /// What is wrong, with the line where known.
        message: String,
    },
    /// A scene could not be loaded or a case not applied: (scene, reason).
    #[error("scene {0}: {1}")]
    Scene(String, String),
    /// A graph could not be checked or compiled: (graph, reason).
    #[error("graph {0}: {1}")]
    Graph(String, String),
    /// Rendering a point failed on the GPU.
    #[error(transparent)]
    Render(#[from] RenderError),
}

impl Sweep {
    /// Reads and checks a sweep file; errors name the file and line.
    pub fn load(path: &Path) -> Result<Self, SweepError> {
        let text = std::fs::read_to_string(path).map_err(|e| SweepError::File {
            file: path.to_path_buf(),
            message: e.to_string(),
        })?;
        Self::parse(&text, path)
    }

    /// Parses and checks sweep text (`path` names it in messages).
    pub fn parse(text: &str, path: &Path) -> Result<Self, SweepError> {
        let error = |message: String| SweepError::File {
            file: path.to_path_buf(),
            message,
        };
        let sweep: Sweep = crate::scene::scene_file::ron_options()
            .from_str(text)
            .map_err(|e: ron::error::SpannedError| {
                error(format!(
                    "{}:{}: {}",
                    e.span.start.line, e.span.start.col, e.code
                ))
            })?;
        // Line of the first occurrence of `needle`, for errors found after parsing.
        let line_of = |needle: &str| {
            text.lines()
                .position(|l| l.contains(needle))
                .map_or(String::new(), |i| format!("{}: ", i + 1))
        };
        for (i, c) in sweep.cases.iter().enumerate() {
            c.check().map_err(|m| {
                let line = line_of(&format!("\"{}\"", c.name));
                error(format!("{line}cases[{i}] (\"{}\"): {m}", c.name))
            })?;
        }
        // Counts that size allocations and loops, checked against their limits at the
        // line of their field.
        let counts = [
            ("warmup", sweep.warmup, MAX_WARMUP_FRAMES),
            ("frames", sweep.frames, MAX_FRAMES),
            ("rounds", sweep.rounds, MAX_ROUNDS),
        ];
        for (field, value, limit) in counts {
            if value > limit {
                let line = field_line(text, field);
                return Err(error(format!(
                    "{line}{field} {value} is over the limit of {limit}"
                )));
            }
        }
        if let Some(&n) = sweep
            .lights
            .iter()
            .find(|&&n| n as u64 > crate::scene::scene_file::MAX_SCENE_LIGHTS)
        {
            let line = field_line(text, "lights");
            return Err(error(format!(
                "{line}lights {n} is over the limit of {} (a scene file's limit)",
                crate::scene::scene_file::MAX_SCENE_LIGHTS
            )));
        }
        if let Some(step) = sweep.animate.filter(|s| !(s.is_finite() && *s > 0.0)) {
            let line = line_of("animate");
            return Err(error(format!(
                "{line}animate {step} must be a finite number of seconds > 0"
            )));
        }
        if !(0.0..=3600.0).contains(&sweep.warmup_seconds) {
            let line = line_of("warmup_seconds");
            return Err(error(format!(
                "{line}warmup_seconds {} must lie in 0..=3600",
                sweep.warmup_seconds
            )));
        }
        for &(w, h) in &sweep.resolutions {
            if w == 0 || h == 0 || w > 16384 || h > 16384 {
                let line = line_of("resolutions");
                return Err(error(format!(
                    "{line}resolution ({w}, {h}) must lie in 1..=16384"
                )));
            }
        }
        match sweep.points() {
            Some(n) if n <= MAX_POINTS => {}
            n => {
                let line = line_of("Sweep");
                let n = n.map_or("over 2^64".to_string(), |n| n.to_string());
                return Err(error(format!(
                    "{line}the sweep has {n} points (scenes × cases × light counts × resolutions × graphs), over the limit of {MAX_POINTS}"
                )));
            }
        }
        if let Some(g) = sweep.references.keys().find(|g| !sweep.graphs.contains(g)) {
            let line = line_of("references");
            return Err(error(format!(
                "{line}references names graph \"{g}\", which is not in graphs"
            )));
        }
        Ok(sweep)
    }

    /// The reference graph the error columns of `graph` compare against.
    pub fn reference_for(&self, graph: &str) -> &str {
        self.references.get(graph).unwrap_or(&self.reference)
    }

    /// The timing settings.
    pub(crate) fn method(&self) -> timing::Method {
        timing::Method {
            warmup_frames: self.warmup,
            warmup_seconds: self.warmup_seconds,
            rounds: self.rounds,
            frames: self.frames,
        }
    }

    /// Number of points the sweep runs (at most [`MAX_POINTS`] once parsed).
    pub fn point_count(&self) -> usize {
        self.points()
            .map_or(usize::MAX, |n| n.min(usize::MAX as u64) as usize)
    }

    /// scenes × cases × light counts × resolutions × graphs; `None` past u64.
    fn points(&self) -> Option<u64> {
        [
            self.scenes.len(),
            self.cases.len().max(1),
            self.lights.len().max(1),
            self.resolutions.len(),
            self.graphs.len(),
        ]
        .iter()
        .try_fold(1u64, |product, &n| product.checked_mul(n as u64))
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
                            let moving = super::animate::time_moving(
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
    use super::*;

    /// 8,000 entries in each of the five lists: 3.3e19 points, past u64 (the count
    /// wrapped in release builds and panicked with overflow checks; the sweep fuzz
    /// target's binary found it), refused at the `Sweep(` line.
    #[test]
    fn too_many_points_are_refused_even_past_u64() {
        let list = |item: &str| vec![item; 8000].join(", ");
        let text = format!(
            "Sweep(\n scenes: [{}],\n graphs: [{}],\n lights: [{}],\n resolutions: [{}],\n cases: [{}],\n)",
            list("\"builtin:harada\""),
            list("\"a.ron\""),
            list("1"),
            list("(1, 1)"),
            list("(name: \"c\")"),
        );
        let e = Sweep::parse(&text, "big.ron".as_ref())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("big.ron: 1: the sweep has over 2^64 points")
                && e.contains("limit of 100000"),
            "{e}"
        );
        let fewer = text.replace(&list("1"), "1");
        let e = Sweep::parse(&fewer, "big.ron".as_ref())
            .unwrap_err()
            .to_string();
        assert!(e.contains("has 4096000000000000 points"), "{e}");
    }

    const SWEEP: &str = r#"Sweep(
        scenes: ["builtin:chairs"],
        graphs: ["forward_plus.ron", "raycast_shadows.ron"],
        resolutions: [(16, 9)],
        references: {"raycast_shadows.ron": "raycast_shadows_naive.ron"},
    )"#;

    #[test]
    fn references_name_a_graph_per_graph() {
        let s = Sweep::parse(SWEEP, "s.ron".as_ref()).unwrap();
        assert_eq!(s.reference_for("forward_plus.ron"), "brute_force.ron");
        assert_eq!(
            s.reference_for("raycast_shadows.ron"),
            "raycast_shadows_naive.ron"
        );
        let typo = SWEEP.replace("\"raycast_shadows.ron\":", "\"raycast_shadow.ron\":");
        let e = Sweep::parse(&typo, "s.ron".as_ref())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("5: references names graph \"raycast_shadow.ron\""),
            "{e}"
        );
    }

    #[test]
    fn the_shadow_sweep_parses() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/sweeps/raycast_shadows.ron");
        let s = Sweep::load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.point_count(), 10);
        assert_eq!(s.reference_for("forward_plus.ron"), "brute_force.ron");
    }
}
