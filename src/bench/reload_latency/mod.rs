//! Edit-to-new-frame latency of hot reload, for a shader, a material and a graph edit.
//!
//! The project's shaders, `graphs/forward_plus.ron` and `materials/car_paint.ron` are
//! copied into a work folder with a scene file (the harada geometry, the boxes painted
//! with the car paint, N random lights). A [`ReloadSession`] renders it; then the
//! benchmark makes real edits in turn (shader: the range window's scale; material: the
//! pigment's red; graph: the culling pass's list capacity), each with a value the edit
//! before did not use (and the session drops pipelines only replaced frames used), so
//! every edit rebuilds what it really must. The clock starts when the file write has
//! returned, so the watcher's wait is included (`std::fs::write` closes the file: its
//! batch comes `WatchConfig::settle` after the last event, not the whole debounce), and
//! stops when the new frame has been read back.

mod summary;

pub use summary::{
    pipelines_csv, summarize_kinds, summarize_pipelines, to_csv, to_markdown, KindSummary,
    PipelineSummary,
};

use crate::reload::{Reload, ReloadSession, SceneSource};
use crate::render::{PipelineBuild, RenderTimings, Renderer};
use crate::shader::assets::{Project, RootSource};
use crate::shader::ShaderLibrary;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use thiserror::Error;

/// Why the hot-reload latency benchmark stopped.
#[derive(Debug, Error)]
pub enum ReloadBenchError {
    /// Copying or writing a file of the work folder failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The line an edit changes is not in the copied file (the project's file differs).
    #[error("{}: the text to edit is not there: {what}", file.display())]
    EditTarget {
        /// The file.
        file: PathBuf,
        /// The text that was looked for.
        what: String,
    },
    /// The reload session could not start (scene, graph or first frame failed).
    #[error("starting the reload session: {0}")]
    Session(String),
    /// An edit's reload failed: the edited file no longer compiled or rendered.
    #[error("{kind} edit {index}: {}: {message}", file.display())]
    Reload {
        /// Which kind of edit.
        kind: EditKind,
        /// 0-based index of the edit among those of its kind.
        index: usize,
        /// The edited file.
        file: PathBuf,
        /// The reload's error.
        message: String,
    },
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ReloadBenchError + '_ {
    move |source| ReloadBenchError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Which project file an edit changes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum EditKind {
    /// `common/lighting.wgsl`: the range window's scale (rebuilds every pipeline that
    /// includes it).
    Shader,
    /// `materials/car_paint.ron`: the pigment's red (rebuilds the pipelines of that material).
    Material,
    /// `graphs/forward_plus.ron`: the culling pass's list capacity (recompiles the graph).
    Graph,
}

impl EditKind {
    /// Every kind, in the order the benchmark edits them.
    pub const ALL: [EditKind; 3] = [EditKind::Shader, EditKind::Material, EditKind::Graph];
}

impl std::fmt::Display for EditKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            EditKind::Shader => "shader",
            EditKind::Material => "material",
            EditKind::Graph => "graph",
        })
    }
}

/// Settings of a hot-reload latency run ([`run`]).
#[derive(Clone, Debug)]
pub struct ReloadBenchConfig {
    /// Where shaders/, graphs/ and materials/ are looked for first (the built-in copies
    /// fill in what is not there).
    pub project: PathBuf,
    /// An empty folder to copy them into and edit there.
    pub work: PathBuf,
    /// Frame width in pixels.
    pub width: u32,
    /// Frame height in pixels.
    pub height: u32,
    /// Random lights in the scene.
    pub lights: u32,
    /// Edits of each kind.
    pub repeats: usize,
    /// Makes the shader edits' values (and so every pipeline built after the first
    /// shader edit) differ from another run's: a driver's own shader cache (NVIDIA keeps
    /// one on disk) then cannot answer from an earlier run. 0: the historical values;
    /// 1..=1023 give distinct values.
    pub salt: u32,
    /// Frames submitted without waiting right before each edit, as a viewer has in
    /// flight: pipeline builds then start while the GPU is busy.
    pub frames_in_flight: usize,
    /// Frames rendered right before each edit, each waited for, as a viewer renders
    /// continuously until a reload takes its loop: the GPU is as busy as under a viewer
    /// (an idle GPU lowers its clocks; then the new frame takes longer), and nothing is
    /// in flight when the edit lands.
    pub viewer_frames: usize,
    /// Wait for the GPU to go idle before building pipelines (timed in its own column).
    pub wait_for_idle_before_build: bool,
    /// Build one pass's pipelines after another (the renderer builds them on one thread
    /// per pass by default).
    pub sequential_builds: bool,
}

/// One timed edit, in milliseconds.
#[derive(Clone, Debug)]
pub struct ReloadSample {
    /// Which kind of edit.
    pub kind: EditKind,
    /// 0-based index of the edit among those of its kind.
    pub index: usize,
    /// File write returned → the new frame's GPU work done: what a viewer shows (it
    /// presents the output texture without reading it back). The headline.
    pub frame_ms: f64,
    /// File write returned → new frame read back (the HDR image copied to the CPU).
    pub total_ms: f64,
    /// File write returned → the watcher delivered the batch (event delivery, then the
    /// settle time for a saved file or the debounce otherwise).
    pub watch_ms: f64,
    /// Reading and uploading changed materials / scene.
    pub(crate) assets_ms: f64,
    /// Parsing, validating and compiling the graph.
    pub(crate) graph_ms: f64,
    /// Composing shader sources and validating them with naga.
    pub shader_compose_ms: f64,
    /// Creating shader modules and pipelines.
    pub pipeline_build_ms: f64,
    /// The rest of prepare: resources, bind groups, layouts.
    pub(crate) prepare_other_ms: f64,
    /// Executing the frame and reading it back.
    pub render_ms: f64,
    /// The same frame rendered again right after (not part of the latency): what of
    /// `render_ms` was the frame itself rather than first-use work in the driver.
    pub rerender_ms: f64,
    /// Composing and building, wall time (less than the sum of the two with parallel
    /// builds).
    pub(crate) build_wall_ms: f64,
    /// Of `pipeline_build_ms`: `create_shader_module`.
    pub shader_module_ms: f64,
    /// Of `pipeline_build_ms`: `create_render/compute_pipeline` (with layouts).
    pub pipeline_create_ms: f64,
    /// Whether the GPU still had earlier frames' work when the first build began.
    pub gpu_busy_at_build: Option<bool>,
    /// Waiting for the GPU before building (only with `wait_for_idle_before_build`).
    pub(crate) gpu_wait_before_build_ms: f64,
    /// Each pipeline built: pass, shader and material, and its times.
    pub(crate) builds: Vec<PipelineBuild>,
    /// Of `render_ms`: encoding and `queue.submit`.
    pub record_submit_ms: f64,
    /// Of `render_ms`: submit returned → GPU done (blocking poll).
    pub gpu_wait_ms: f64,
    /// The GPU's time for the frame, from pass timestamps (NaN without timestamps).
    pub(crate) gpu_frame_ms: f64,
    /// Of `render_ms`: copying, mapping and converting the Rgba32Float output.
    pub image_readback_ms: f64,
    /// Of `render_ms`: timestamps, culling reports and statistics read back.
    pub(crate) reports_readback_ms: f64,
    /// The same frame again: submit returned → GPU done.
    pub(crate) rerender_gpu_wait_ms: f64,
    /// Pipelines the reload built (the rest came from the session's cache).
    pub pipelines_built: usize,
    /// GPU resources the reload created.
    pub resources_created: usize,
    /// GPU resources the reload kept from the frame before.
    pub resources_reused: usize,
}

/// The harada lighting model's range window; the shader edit scales it.
const SHADER_FILE: &str = "common/lighting.wgsl";
const SHADER_LINE: &str = "return clamp(1.0 - r * r, 0.0, 1.0);";
const MATERIAL_MARKER: &str = "Lambert(weight: 0.65, color: (";
const GRAPH_MARKER: &str = "capacity: ";

/// The graph edit changes a fixed list capacity, a define of the culling pipelines, as
/// in every earlier measurement: the shipped graph's compact lists (whose bound is a
/// uniform, so editing it builds no pipeline) become fixed lists of 256 in the copy.
fn fixed_lists(text: &str) -> String {
    let Some(start) = find_in_code(text, "lists: Compact(max_indices: ") else {
        return text.to_string();
    };
    let end = start + text[start..].find(')').map_or(0, |e| e + 1);
    format!("{}capacity: 256{}", &text[..start], &text[end..])
}

/// Where `marker` first occurs outside `//` comments.
fn find_in_code(text: &str, marker: &str) -> Option<usize> {
    let mut offset = 0;
    for line in text.split_inclusive('\n') {
        let code = line.find("//").map_or(line, |c| &line[..c]);
        if let Some(i) = code.find(marker) {
            return Some(offset + i);
        }
        offset += line.len();
    }
    None
}

/// `text` with the number right after the first `marker` outside comments replaced by
/// `value`.
fn replace_number_after(text: &str, marker: &str, value: &str) -> Option<String> {
    let start = find_in_code(text, marker)? + marker.len();
    let len = text[start..]
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(text.len() - start);
    (len > 0).then(|| format!("{}{value}{}", &text[..start], &text[start + len..]))
}

/// An edit target: the pristine text and how the i-th edit changes it.
struct Target {
    kind: EditKind,
    file: PathBuf,
    original: String,
    salt: u32,
}

impl Target {
    fn load(kind: EditKind, file: PathBuf, salt: u32) -> Result<Self, ReloadBenchError> {
        let original = std::fs::read_to_string(&file).map_err(io(&file))?;
        let t = Target {
            kind,
            file,
            original,
            salt,
        };
        // Fail before timing anything if the text to edit is missing.
        t.edited(0)?;
        Ok(t)
    }

    /// The file's text for edit `i`: a value no earlier edit used.
    fn edited(&self, i: usize) -> Result<String, ReloadBenchError> {
        let step = i as f64 + 1.0;
        let (text, what) = match self.kind {
            EditKind::Shader => (
                self.original.contains(SHADER_LINE).then(|| {
                    let scale = match self.salt {
                        0 => format!("{:.4}", 1.0 + 1e-4 * step),
                        // Exact in f32 (steps of 2^-22 near 1), so every (edit, salt)
                        // pair compiles to its own constant.
                        salt => format!(
                            "{:.9}",
                            1.0 + (step * 1024.0 + f64::from(salt % 1024)) / 4_194_304.0
                        ),
                    };
                    self.original.replace(
                        SHADER_LINE,
                        &format!("return {scale} * clamp(1.0 - r * r, 0.0, 1.0);"),
                    )
                }),
                SHADER_LINE,
            ),
            EditKind::Material => (
                replace_number_after(
                    &self.original,
                    MATERIAL_MARKER,
                    &format!("{:.4}", 0.55 - 1e-4 * step),
                ),
                MATERIAL_MARKER,
            ),
            EditKind::Graph => (
                // 252, 248, ... 128, then round again: every value differs from the last.
                replace_number_after(
                    &self.original,
                    GRAPH_MARKER,
                    &(256 - 4 * (1 + i % 32)).to_string(),
                ),
                GRAPH_MARKER,
            ),
        };
        text.ok_or_else(|| ReloadBenchError::EditTarget {
            file: self.file.clone(),
            what: what.to_string(),
        })
    }
}

fn scene_text(lights: u32) -> String {
    format!(
        r#"// Reload benchmark: the harada geometry, its boxes in car paint, random lights.
Scene(
    name: "reload_bench",
    builtin: "harada",
    keep_model_lights: false,
    light_sets: [
        Random(count: {lights}, spot_fraction: 0.33, placement: Box(min: (-20, 0.1, -20), max: (20, 3, 20)),
               range: (1.0, 2.5), intensity: (0.3, 1.5), seed: 2012),
    ],
    material_overrides: {{ "harada_box": "car_paint.ron" }},
    ambient: (0, 0, 0),
)
"#
    )
}

/// Copies the inputs into `config.work`, starts a session on `gpu`, and times `repeats`
/// edits of each kind, interleaved. `progress` sees every sample.
pub fn run(
    config: &ReloadBenchConfig,
    gpu: crate::gpu::GpuContext,
    mut progress: impl FnMut(&ReloadSample),
) -> Result<BenchRun, ReloadBenchError> {
    let work = &config.work;
    let shaders = work.join("shaders");
    let project = Project::at(&config.project, RootSource::Flag);
    project.extract("shaders", &shaders).map_err(io(&shaders))?;
    let graph = work.join("forward_plus.ron");
    let material = work.join("car_paint.ron");
    let scene = work.join("scene.ron");
    for (rel, to) in [
        ("graphs/forward_plus.ron", &graph),
        ("materials/car_paint.ron", &material),
    ] {
        let (from, text) = project.read(rel).map_err(io(&project.locate(rel)))?;
        std::fs::write(to, fixed_lists(&text)).map_err(io(&from))?;
    }
    std::fs::write(&scene, scene_text(config.lights)).map_err(io(&scene))?;
    let targets = [
        Target::load(EditKind::Shader, shaders.join(SHADER_FILE), config.salt)?,
        Target::load(EditKind::Material, material, config.salt)?,
        Target::load(EditKind::Graph, graph.clone(), config.salt)?,
    ];

    let pipeline_cache = gpu.pipeline_cache_status();
    let renderer = Renderer::new(gpu, ShaderLibrary::new(&shaders));
    let started = Instant::now();
    let mut session = ReloadSession::new(
        renderer,
        &graph,
        SceneSource::File(scene),
        config.width,
        config.height,
        &[],
    )
    .map_err(ReloadBenchError::Session)?;
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let startup = match session.prepared() {
        Some(p) => Startup {
            total_ms: ms(started.elapsed()),
            pipelines_built: p.stats().pipelines_built.len(),
            shader_compose_ms: ms(p.stats().shader_compose),
            pipeline_build_ms: ms(p.stats().pipeline_build),
            pipeline_cache,
        },
        None => Startup {
            pipeline_cache,
            ..Default::default()
        },
    };
    session.renderer.pipelines.wait_for_idle_before_build = config.wait_for_idle_before_build;
    session.renderer.pipelines.parallel_builds = !config.sequential_builds;

    let mut samples = Vec::new();
    for index in 0..config.repeats {
        for t in &targets {
            let text = t.edited(index)?;
            let failed = |message: String| ReloadBenchError::Reload {
                kind: t.kind,
                index,
                file: t.file.clone(),
                message,
            };
            // Whatever a previous edit left behind is handled before the clock starts.
            while session.poll().is_some() {}
            // A viewer's frames, done or in flight when the edit lands.
            if let Some(p) = session.prepared() {
                for _ in 0..config.viewer_frames {
                    p.execute(&session.renderer)
                        .map_err(|e| failed(e.to_string()))?;
                }
                for _ in 0..config.frames_in_flight {
                    p.submit(&session.renderer)
                        .map_err(|e| failed(e.to_string()))?;
                }
            }
            std::fs::write(&t.file, &text).map_err(io(&t.file))?;
            let written = Instant::now();
            let reload = reload_of(&mut session, &t.file).map_err(failed)?;
            let (stats, rerender_ms, again) = match session.prepared() {
                Some(p) => {
                    let start = Instant::now();
                    let (_, again) = p
                        .render_timed(&session.renderer)
                        .map_err(|e| failed(e.to_string()))?;
                    (p.stats().clone(), ms(start.elapsed()), Some(again))
                }
                None => (Default::default(), f64::NAN, None),
            };
            let tm = reload.timings;
            let frame = tm.frame.unwrap_or_default();
            let sample = ReloadSample {
                kind: t.kind,
                index,
                frame_ms: reload
                    .frame_ready
                    .map_or(f64::NAN, |t| ms(t.saturating_duration_since(written))),
                total_ms: ms(reload.finished.saturating_duration_since(written)),
                watch_ms: ms(reload.received.saturating_duration_since(written)),
                assets_ms: ms(tm.assets),
                graph_ms: ms(tm.graph),
                shader_compose_ms: ms(tm.shader_compose),
                pipeline_build_ms: ms(tm.pipeline_build),
                prepare_other_ms: ms(tm.prepare.saturating_sub(tm.build_wall)),
                build_wall_ms: ms(tm.build_wall),
                render_ms: ms(tm.render),
                rerender_ms,
                shader_module_ms: ms(tm.shader_modules),
                pipeline_create_ms: ms(tm.pipeline_create),
                gpu_busy_at_build: tm.gpu_at_build.busy,
                gpu_wait_before_build_ms: ms(tm.gpu_at_build.wait),
                builds: tm.builds,
                record_submit_ms: ms(frame.record_submit),
                gpu_wait_ms: ms(frame.gpu_wait),
                gpu_frame_ms: frame.gpu_frame_ms.unwrap_or(f64::NAN),
                image_readback_ms: ms(frame.image_readback),
                reports_readback_ms: ms(frame.reports_readback + frame.timestamps_read),
                rerender_gpu_wait_ms: again.map_or(f64::NAN, |a: RenderTimings| ms(a.gpu_wait)),
                pipelines_built: stats.pipelines_built.len(),
                resources_created: stats.resources_created,
                resources_reused: stats.resources_reused,
            };
            progress(&sample);
            samples.push(sample);
        }
    }
    Ok(BenchRun { samples, startup })
}

/// What starting the session (loading, the first prepare and render) cost: with a warm
/// pipeline cache on disk, the builds here are where it shows.
#[derive(Clone, Debug, Default)]
pub struct Startup {
    /// Starting the session, from the first file read to the first frame read back.
    pub total_ms: f64,
    /// Pipelines built for the first frame.
    pub pipelines_built: usize,
    /// Composing shader sources and validating them with naga.
    pub shader_compose_ms: f64,
    /// Creating shader modules and pipelines.
    pub pipeline_build_ms: f64,
    /// The driver's pipeline cache on disk: where, and what opening it found.
    pub(crate) pipeline_cache: String,
}

/// A benchmark run: the session's start and every timed edit.
pub struct BenchRun {
    /// What starting the session cost.
    pub startup: Startup,
    /// Every timed edit, in the order made.
    pub samples: Vec<ReloadSample>,
}

/// The reload that handled `file` (bounded wait), or its error.
fn reload_of(session: &mut ReloadSession, file: &Path) -> Result<Reload, String> {
    let name = file.file_name().unwrap_or_default();
    let deadline = Instant::now() + Duration::from_secs(60);
    while let Some(left) = deadline.checked_duration_since(Instant::now()) {
        let Some(r) = session.wait(left) else { break };
        if r.changed.iter().any(|c| c.file_name() == Some(name)) {
            return match &r.outcome {
                Ok(_) => Ok(r),
                Err(e) => Err(e.clone()),
            };
        }
    }
    Err("no reload within 60 s".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_exactly_the_number_after_the_marker() {
        let t = "kind: LightCulling(tile: 16, variant: Frustum, capacity: 256),";
        assert_eq!(
            replace_number_after(t, "capacity: ", "248").unwrap(),
            "kind: LightCulling(tile: 16, variant: Frustum, capacity: 248),"
        );
        let m = "Lambert(weight: 0.65, color: (0.55, 0.03, 0.02))";
        assert_eq!(
            replace_number_after(m, MATERIAL_MARKER, "0.5499").unwrap(),
            "Lambert(weight: 0.65, color: (0.5499, 0.03, 0.02))"
        );
        assert!(replace_number_after(t, "absent: ", "1").is_none());
        assert_eq!(
            fixed_lists(
                "LightCulling(tile: 16, variant: Frustum, lists: Compact(max_indices: 64)),"
            ),
            "LightCulling(tile: 16, variant: Frustum, capacity: 256),"
        );
        assert!(replace_number_after("capacity: x", "capacity: ", "1").is_none());
    }

    #[test]
    fn every_edit_differs_from_the_one_before() {
        for kind in EditKind::ALL {
            let original = match kind {
                EditKind::Shader => format!("fn w() -> f32 {{ {SHADER_LINE} }}"),
                EditKind::Material => format!("{MATERIAL_MARKER}0.55, 0.03, 0.02))"),
                EditKind::Graph => "capacity: 256)".to_string(),
            };
            let t = Target {
                kind,
                file: PathBuf::from("x"),
                original: original.clone(),
                salt: 0,
            };
            let mut last = original;
            for i in 0..40 {
                let next = t.edited(i).unwrap();
                assert_ne!(next, last, "{kind} edit {i}");
                last = next;
            }
        }
    }

    /// The shipped graph mentions `capacity: 256` in a comment above the culling pass:
    /// the graph edit must change the pass, not the comment (it did, and built nothing).
    #[test]
    fn the_graph_edit_changes_the_culling_pass_not_a_comment() {
        let text = "// `capacity: 256` instead gives fixed lists\n\
                    kind: LightCulling(tile: 16, variant: Frustum, lists: Compact(max_indices: 64)),\n";
        let fixed = fixed_lists(text);
        assert!(
            fixed.contains("variant: Frustum, capacity: 256)"),
            "{fixed}"
        );
        let edited = replace_number_after(&fixed, GRAPH_MARKER, "252").unwrap();
        assert!(edited.starts_with("// `capacity: 256` instead"), "{edited}");
        assert!(
            edited.contains("variant: Frustum, capacity: 252)"),
            "{edited}"
        );
        let shipped = include_str!("../../../graphs/forward_plus.ron");
        let fixed = fixed_lists(shipped);
        let edited = replace_number_after(&fixed, GRAPH_MARKER, "252").unwrap();
        assert!(
            edited.contains("capacity: 252)"),
            "the shipped graph's culling pass"
        );
    }

    /// Salted shader edits differ from every other salt's and the unsalted ones, also
    /// once the WGSL literal is rounded to f32 (what reaches the driver).
    #[test]
    fn salted_shader_edits_are_distinct_in_f32() {
        let original = format!("fn w() -> f32 {{ {SHADER_LINE} }}");
        let scale = |salt: u32, i: usize| -> f32 {
            let t = Target {
                kind: EditKind::Shader,
                file: PathBuf::from("x"),
                original: original.clone(),
                salt,
            };
            let text = t.edited(i).unwrap();
            let number = text
                .split("return ")
                .nth(1)
                .unwrap()
                .split(' ')
                .next()
                .unwrap();
            number.parse::<f32>().unwrap()
        };
        let mut seen = std::collections::HashSet::new();
        for salt in [0, 1, 2, 511, 1023] {
            for i in 0..40 {
                assert!(
                    seen.insert(scale(salt, i).to_bits()),
                    "salt {salt} edit {i}"
                );
            }
        }
    }
}
