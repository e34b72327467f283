//! Edit-to-new-frame latency of hot reload, for a shader, a material and a graph edit.
//!
//! The project's shaders, `graphs/forward_plus.ron` and `materials/car_paint.ron` are
//! copied into a work folder with a scene file (the harada geometry, the boxes painted
//! with the car paint, N random lights). A [`ReloadSession`] renders it; then the
//! benchmark makes real edits in turn (shader: the range window's scale; material: the
//! pigment's red; graph: the culling pass's list capacity), each with a value the edit
//! before did not use (and the session drops pipelines only replaced frames used), so
//! every edit rebuilds what it really must. The clock starts when the file
//! write has returned (so the watcher's debounce is included) and stops when the new
//! frame has been read back.

use super::report::{summarize, TimingSummary};
use crate::reload::{Reload, ReloadSession, SceneSource, WatchConfig};
use crate::render::Renderer;
use crate::shader::assets::{Project, RootSource};
use crate::shader::ShaderLibrary;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use thiserror::Error;

#[derive(Debug, Error)]
pub enum ReloadBenchError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: the text to edit is not there: {what}", file.display())]
    EditTarget { file: PathBuf, what: String },
    #[error("starting the reload session: {0}")]
    Session(String),
    #[error("{kind} edit {index}: {}: {message}", file.display())]
    Reload {
        kind: EditKind,
        index: usize,
        file: PathBuf,
        message: String,
    },
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ReloadBenchError + '_ {
    move |source| ReloadBenchError::Io {
        path: path.to_path_buf(),
        source,
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum EditKind {
    Shader,
    Material,
    Graph,
}

impl EditKind {
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

#[derive(Clone, Debug)]
pub struct ReloadBenchConfig {
    /// Where shaders/, graphs/ and materials/ are looked for first (the built-in copies
    /// fill in what is not there).
    pub project: PathBuf,
    /// An empty folder to copy them into and edit there.
    pub work: PathBuf,
    pub width: u32,
    pub height: u32,
    pub lights: u32,
    /// Edits of each kind.
    pub repeats: usize,
}

/// One timed edit, in milliseconds.
#[derive(Clone, Debug)]
pub struct ReloadSample {
    pub kind: EditKind,
    pub index: usize,
    /// File write returned → new frame read back.
    pub total_ms: f64,
    /// File write returned → the watcher delivered the batch (debounce and event delivery).
    pub watch_ms: f64,
    /// Reading and uploading changed materials / scene.
    pub assets_ms: f64,
    /// Parsing, validating and compiling the graph.
    pub graph_ms: f64,
    /// Composing shader sources and validating them with naga.
    pub shader_compose_ms: f64,
    /// Creating shader modules and pipelines.
    pub pipeline_build_ms: f64,
    /// The rest of prepare: resources, bind groups, layouts.
    pub prepare_other_ms: f64,
    /// Executing the frame and reading it back.
    pub render_ms: f64,
    /// The same frame rendered again right after (not part of the latency): what of
    /// `render_ms` was the frame itself rather than first-use work in the driver.
    pub rerender_ms: f64,
    pub pipelines_built: usize,
    pub resources_created: usize,
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
    let Some(start) = text.find("lists: Compact(max_indices: ") else {
        return text.to_string();
    };
    let end = start + text[start..].find(')').map_or(0, |e| e + 1);
    format!("{}capacity: 256{}", &text[..start], &text[end..])
}

/// `text` with the number right after the first `marker` replaced by `value`.
fn replace_number_after(text: &str, marker: &str, value: &str) -> Option<String> {
    let start = text.find(marker)? + marker.len();
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
}

impl Target {
    fn load(kind: EditKind, file: PathBuf) -> Result<Self, ReloadBenchError> {
        let original = std::fs::read_to_string(&file).map_err(io(&file))?;
        let t = Target {
            kind,
            file,
            original,
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
                    self.original.replace(
                        SHADER_LINE,
                        &format!(
                            "return {:.4} * clamp(1.0 - r * r, 0.0, 1.0);",
                            1.0 + 1e-4 * step
                        ),
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
) -> Result<Vec<ReloadSample>, ReloadBenchError> {
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
        Target::load(EditKind::Shader, shaders.join(SHADER_FILE))?,
        Target::load(EditKind::Material, material)?,
        Target::load(EditKind::Graph, graph.clone())?,
    ];

    let renderer = Renderer::new(gpu, ShaderLibrary::new(&shaders));
    let mut session = ReloadSession::new(
        renderer,
        &graph,
        SceneSource::File(scene),
        config.width,
        config.height,
        &[],
    )
    .map_err(ReloadBenchError::Session)?;

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
            std::fs::write(&t.file, &text).map_err(io(&t.file))?;
            let written = Instant::now();
            let reload = reload_of(&mut session, &t.file).map_err(failed)?;
            let ms = |d: Duration| d.as_secs_f64() * 1e3;
            let (stats, rerender_ms) = match session.prepared() {
                Some(p) => {
                    let start = Instant::now();
                    p.render(&session.renderer)
                        .map_err(|e| failed(e.to_string()))?;
                    (p.stats().clone(), ms(start.elapsed()))
                }
                None => (Default::default(), f64::NAN),
            };
            let tm = reload.timings;
            let sample = ReloadSample {
                kind: t.kind,
                index,
                total_ms: ms(reload.finished.saturating_duration_since(written)),
                watch_ms: ms(reload.received.saturating_duration_since(written)),
                assets_ms: ms(tm.assets),
                graph_ms: ms(tm.graph),
                shader_compose_ms: ms(tm.shader_compose),
                pipeline_build_ms: ms(tm.pipeline_build),
                prepare_other_ms: ms(tm
                    .prepare
                    .saturating_sub(tm.shader_compose + tm.pipeline_build)),
                render_ms: ms(tm.render),
                rerender_ms,
                pipelines_built: stats.pipelines_built.len(),
                resources_created: stats.resources_created,
                resources_reused: stats.resources_reused,
            };
            progress(&sample);
            samples.push(sample);
        }
    }
    Ok(samples)
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

/// Per kind: the summary of the total and the median of each part.
pub struct KindSummary {
    pub kind: EditKind,
    pub samples: usize,
    pub total: TimingSummary,
    /// (column name, median ms) for each part of the breakdown.
    pub parts: Vec<(&'static str, f64)>,
    pub pipelines_built: f64,
    pub resources_reused: f64,
    pub resources_created: f64,
}

type Part = (&'static str, fn(&ReloadSample) -> f64);

const PARTS: [Part; 8] = [
    ("watch (debounce + events)", |s| s.watch_ms),
    ("material/scene load", |s| s.assets_ms),
    ("graph compile", |s| s.graph_ms),
    ("shader compose + naga", |s| s.shader_compose_ms),
    ("pipeline build", |s| s.pipeline_build_ms),
    ("other prepare", |s| s.prepare_other_ms),
    ("render + readback", |s| s.render_ms),
    ("(same frame again)", |s| s.rerender_ms),
];

pub fn summarize_kinds(samples: &[ReloadSample]) -> Vec<KindSummary> {
    EditKind::ALL
        .iter()
        .filter_map(|&kind| {
            let of: Vec<&ReloadSample> = samples.iter().filter(|s| s.kind == kind).collect();
            let median = |f: &dyn Fn(&ReloadSample) -> f64| {
                summarize(&of.iter().map(|s| f(s)).collect::<Vec<_>>()).map(|t| t.median)
            };
            let total = summarize(&of.iter().map(|s| s.total_ms).collect::<Vec<_>>())?;
            Some(KindSummary {
                kind,
                samples: of.len(),
                total,
                parts: PARTS
                    .iter()
                    .map(|(name, f)| (*name, median(f).unwrap_or(f64::NAN)))
                    .collect(),
                pipelines_built: median(&|s| s.pipelines_built as f64).unwrap_or(f64::NAN),
                resources_reused: median(&|s| s.resources_reused as f64).unwrap_or(f64::NAN),
                resources_created: median(&|s| s.resources_created as f64).unwrap_or(f64::NAN),
            })
        })
        .collect()
}

pub fn to_csv(samples: &[ReloadSample]) -> String {
    let mut out = String::from(
        "kind,index,total_ms,watch_ms,assets_ms,graph_ms,shader_compose_ms,pipeline_build_ms,\
         prepare_other_ms,render_ms,rerender_ms,pipelines_built,resources_created,resources_reused\n",
    );
    for s in samples {
        let _ = writeln!(
            out,
            "{},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{},{},{}",
            s.kind,
            s.index,
            s.total_ms,
            s.watch_ms,
            s.assets_ms,
            s.graph_ms,
            s.shader_compose_ms,
            s.pipeline_build_ms,
            s.prepare_other_ms,
            s.render_ms,
            s.rerender_ms,
            s.pipelines_built,
            s.resources_created,
            s.resources_reused
        );
    }
    out
}

/// Markdown: the setup, then per kind the total (median, p10, p90) and the median of
/// each part.
pub fn to_markdown(
    samples: &[ReloadSample],
    config: &ReloadBenchConfig,
    adapter: &str,
    watch: &WatchConfig,
) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# Hot reload: edit to new frame\n");
    let _ = writeln!(
        out,
        "Adapter: {adapter}. Scene: harada geometry, boxes in `car_paint.ron`, {} random \
         lights; `forward_plus.ron`; {}×{}; {} edits of each kind, interleaved. Watcher \
         debounce {} ms. Times from the file write returning to the new frame read back.\n",
        config.lights,
        config.width,
        config.height,
        config.repeats,
        watch.debounce.as_millis()
    );
    let kinds = summarize_kinds(samples);
    let _ = writeln!(out, "| edit | median | p10 | p90 |");
    let _ = writeln!(out, "|---|--:|--:|--:|");
    for k in &kinds {
        let _ = writeln!(
            out,
            "| {} | {:.1} ms | {:.1} ms | {:.1} ms |",
            k.kind, k.total.median, k.total.p10, k.total.p90
        );
    }
    let _ = writeln!(
        out,
        "\nMedian of each part (ms); the parts before \"(same frame again)\" add up to the \
         total, which does not include that last one: the new frame rendered a second time, \
         to tell the frame itself from first-use work in the driver.\n"
    );
    let _ = write!(out, "| edit |");
    for (name, _) in PARTS {
        let _ = write!(out, " {name} |");
    }
    let _ = writeln!(out, " pipelines built | resources reused / created |");
    let _ = writeln!(out, "|---|{}--:|--:|", "--:|".repeat(PARTS.len()));
    for k in &kinds {
        let _ = write!(out, "| {} |", k.kind);
        for (_, v) in &k.parts {
            let _ = write!(out, " {v:.1} |");
        }
        let _ = writeln!(
            out,
            " {} | {} / {} |",
            k.pipelines_built, k.resources_reused, k.resources_created
        );
    }
    out
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
            };
            let mut last = original;
            for i in 0..40 {
                let next = t.edited(i).unwrap();
                assert_ne!(next, last, "{kind} edit {i}");
                last = next;
            }
        }
    }
}
