//! The reload benchmark's samples summarised per edit kind and per pipeline, and
//! written as CSV and Markdown.

use super::{BenchRun, EditKind, ReloadBenchConfig, ReloadSample};
use crate::bench::report::{summarize, TimingSummary};
use crate::reload::WatchConfig;
use crate::render::PipelineBuild;
use std::fmt::Write as _;
use std::time::Duration;

/// Per kind: the summary of the total and the median of each part.
pub struct KindSummary {
    /// The edit kind summarised.
    pub kind: EditKind,
    /// Number of edits of this kind.
    pub samples: usize,
    /// Edit → new frame on the GPU (what a viewer shows).
    pub frame: TimingSummary,
    /// Edit → new frame read back.
    pub total: TimingSummary,
    /// (column name, median ms) for each part of the breakdown.
    pub(crate) parts: Vec<(&'static str, f64)>,
    /// (column name, median ms) for the parts of pipeline build and render.
    pub(crate) details: Vec<(&'static str, f64)>,
    /// Samples whose first build began with the GPU still busy, of those that built.
    pub(crate) gpu_busy_at_build: (usize, usize),
    /// Median pipelines built per edit.
    pub(crate) pipelines_built: f64,
    /// Median GPU resources kept from the frame before per edit.
    pub(crate) resources_reused: f64,
    /// Median GPU resources created per edit.
    pub(crate) resources_created: f64,
}

type Part = (&'static str, fn(&ReloadSample) -> f64);

const PARTS: [Part; 8] = [
    ("watch (events + settle)", |s| s.watch_ms),
    ("material/scene load", |s| s.assets_ms),
    ("graph compile", |s| s.graph_ms),
    ("shader compose + naga", |s| s.shader_compose_ms),
    ("pipeline build", |s| s.pipeline_build_ms),
    ("other prepare", |s| s.prepare_other_ms),
    ("render + readback", |s| s.render_ms),
    ("(same frame again)", |s| s.rerender_ms),
];

/// The parts of "pipeline build" and "render + readback" (not adding up to the total:
/// `GPU frame` overlaps `submit → GPU done`).
const DETAILS: [Part; 10] = [
    ("compose + build, wall", |s| s.build_wall_ms),
    ("build: create_shader_module", |s| s.shader_module_ms),
    ("build: create_*_pipeline", |s| s.pipeline_create_ms),
    ("wait for idle GPU before build", |s| {
        s.gpu_wait_before_build_ms
    }),
    ("render: record + submit", |s| s.record_submit_ms),
    ("render: submit → GPU done", |s| s.gpu_wait_ms),
    ("GPU frame (timestamps)", |s| s.gpu_frame_ms),
    ("render: image readback", |s| s.image_readback_ms),
    ("render: reports readback", |s| s.reports_readback_ms),
    ("(again: submit → GPU done)", |s| s.rerender_gpu_wait_ms),
];

fn median_of(values: Vec<f64>) -> f64 {
    summarize(&values).map_or(f64::NAN, |t| t.median)
}

/// One summary per edit kind that has samples, in [`EditKind::ALL`] order.
pub fn summarize_kinds(samples: &[ReloadSample]) -> Vec<KindSummary> {
    EditKind::ALL
        .iter()
        .filter_map(|&kind| {
            let of: Vec<&ReloadSample> = samples.iter().filter(|s| s.kind == kind).collect();
            let median = |f: &dyn Fn(&ReloadSample) -> f64| {
                median_of(of.iter().map(|s| f(s)).filter(|v| !v.is_nan()).collect())
            };
            let total = summarize(&of.iter().map(|s| s.total_ms).collect::<Vec<_>>())?;
            let frame = summarize(
                &of.iter()
                    .map(|s| s.frame_ms)
                    .filter(|v| !v.is_nan())
                    .collect::<Vec<_>>(),
            )?;
            let built: Vec<bool> = of.iter().filter_map(|s| s.gpu_busy_at_build).collect();
            Some(KindSummary {
                kind,
                samples: of.len(),
                frame,
                total,
                parts: PARTS.iter().map(|(name, f)| (*name, median(f))).collect(),
                details: DETAILS.iter().map(|(name, f)| (*name, median(f))).collect(),
                gpu_busy_at_build: (built.iter().filter(|b| **b).count(), built.len()),
                pipelines_built: median(&|s| s.pipelines_built as f64),
                resources_reused: median(&|s| s.resources_reused as f64),
                resources_created: median(&|s| s.resources_created as f64),
            })
        })
        .collect()
}

/// Per edit kind and pipeline (pass: shader `material`): how often it was built and the
/// median of its compose, module and pipeline-creation times (ms).
pub struct PipelineSummary {
    /// The edit kind that made the builds.
    pub(crate) kind: EditKind,
    /// The pipeline, as `pass: shader material`.
    pub name: String,
    pub(crate) builds: usize,
    pub(crate) compose_ms: f64,
    pub(crate) module_ms: f64,
    pub(crate) create_ms: f64,
}

/// One summary per (edit kind, pipeline) built, sorted by kind then name.
pub fn summarize_pipelines(samples: &[ReloadSample]) -> Vec<PipelineSummary> {
    let mut by: std::collections::BTreeMap<(EditKind, String), Vec<&PipelineBuild>> =
        Default::default();
    for s in samples {
        for b in &s.builds {
            by.entry((s.kind, b.name())).or_default().push(b);
        }
    }
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    by.into_iter()
        .map(|((kind, name), builds)| PipelineSummary {
            kind,
            name,
            builds: builds.len(),
            compose_ms: median_of(builds.iter().map(|b| ms(b.compose)).collect()),
            module_ms: median_of(builds.iter().map(|b| ms(b.module)).collect()),
            create_ms: median_of(builds.iter().map(|b| ms(b.create)).collect()),
        })
        .collect()
}

/// Every sample as one CSV row (times in milliseconds), with a header line.
pub fn to_csv(samples: &[ReloadSample]) -> String {
    let mut out = String::from(
        "kind,index,total_ms,watch_ms,assets_ms,graph_ms,shader_compose_ms,pipeline_build_ms,\
         prepare_other_ms,render_ms,rerender_ms,pipelines_built,resources_created,resources_reused,\
         shader_module_ms,pipeline_create_ms,gpu_busy_at_build,gpu_wait_before_build_ms,\
         record_submit_ms,gpu_wait_ms,gpu_frame_ms,image_readback_ms,reports_readback_ms,\
         rerender_gpu_wait_ms,slowest_pipeline,slowest_pipeline_create_ms,build_wall_ms,frame_ms\n",
    );
    for s in samples {
        let slowest = s.builds.iter().max_by(|a, b| a.create.cmp(&b.create));
        let _ = writeln!(
            out,
            "{},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{},{},{},\
             {:.3},{:.3},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},\"{}\",{:.3},{:.3},{:.3}",
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
            s.resources_reused,
            s.shader_module_ms,
            s.pipeline_create_ms,
            match s.gpu_busy_at_build {
                Some(true) => "1",
                Some(false) => "0",
                None => "",
            },
            s.gpu_wait_before_build_ms,
            s.record_submit_ms,
            s.gpu_wait_ms,
            s.gpu_frame_ms,
            s.image_readback_ms,
            s.reports_readback_ms,
            s.rerender_gpu_wait_ms,
            slowest.map_or(String::new(), |b| b.name().replace('"', "'")),
            slowest.map_or(0.0, |b| b.create.as_secs_f64() * 1e3),
            s.build_wall_ms,
            s.frame_ms,
        );
    }
    out
}

/// One row per pipeline built: which edit, which pass and pipeline, and its times.
pub fn pipelines_csv(samples: &[ReloadSample]) -> String {
    let mut out = String::from("kind,index,pass,pipeline,compose_ms,module_ms,create_ms\n");
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    for s in samples {
        for b in &s.builds {
            let _ = writeln!(
                out,
                "{},{},\"{}\",\"{}\",{:.3},{:.3},{:.3}",
                s.kind,
                s.index,
                b.pass.replace('"', "'"),
                b.pipeline.replace('"', "'"),
                ms(b.compose),
                ms(b.module),
                ms(b.create)
            );
        }
    }
    out
}

/// Markdown: the setup, then per kind the total (median, p10, p90) and the median of
/// each part, the parts of pipeline build and render, and each pipeline built.
pub fn to_markdown(
    run: &BenchRun,
    config: &ReloadBenchConfig,
    adapter: &str,
    watch: &WatchConfig,
) -> String {
    let samples = &run.samples;
    let mut out = String::new();
    let _ = writeln!(out, "# Hot reload: edit to new frame\n");
    let _ = writeln!(
        out,
        "Adapter: {adapter}. Scene: harada geometry, boxes in `car_paint.ron`, {} random \
         lights; `forward_plus.ron`; {}×{}; {} edits of each kind, interleaved. Watcher: \
         batches cut {} ms after a saved file's last event (debounce {} ms otherwise). Edit \
         salt {}; {} frames rendered and {} more in flight right before each edit; {}; \
         pipelines of different passes built {}. Times from the file write returning to the new frame \
         read back.\n\n\
         **Edit → new frame** runs from the file write returning to the new frame's GPU work \
         being done: what the viewer (`lightgraph view`) shows, since it presents the output \
         texture without reading it back. **Edit → read back** adds copying the \
         Rgba32Float image to the CPU (what `watch --out` and this benchmark's image need); \
         the breakdown below adds up to it.\n",
        config.lights,
        config.width,
        config.height,
        config.repeats,
        watch.settle.min(watch.debounce).as_millis(),
        watch.debounce.as_millis(),
        config.salt,
        config.viewer_frames,
        config.frames_in_flight,
        if config.wait_for_idle_before_build {
            "waiting for an idle GPU before building"
        } else {
            "building without waiting for the GPU"
        },
        if config.sequential_builds {
            "one after another"
        } else {
            "in parallel"
        }
    );
    let st = &run.startup;
    let _ = writeln!(
        out,
        "Session start: {:.1} ms; {} pipelines built (compose + naga {:.1} ms, build {:.1} ms). \
         Pipeline cache: {}.\n",
        st.total_ms,
        st.pipelines_built,
        st.shader_compose_ms,
        st.pipeline_build_ms,
        st.pipeline_cache
    );
    let kinds = summarize_kinds(samples);
    let _ = writeln!(
        out,
        "| edit | **edit → new frame** (viewer): median | p10 | p90 | edit → read back: median | p10 | p90 |"
    );
    let _ = writeln!(out, "|---|--:|--:|--:|--:|--:|--:|");
    for k in &kinds {
        let _ = writeln!(
            out,
            "| {} | **{:.1} ms** | {:.1} ms | {:.1} ms | {:.1} ms | {:.1} ms | {:.1} ms |",
            k.kind,
            k.frame.median,
            k.frame.p10,
            k.frame.p90,
            k.total.median,
            k.total.p10,
            k.total.p90
        );
    }
    let _ = writeln!(
        out,
        "\nMedian of each part (ms); the parts before \"(same frame again)\" add up to the \
         total, which does not include that last one: the new frame rendered a second time, \
         to tell the frame itself from first-use work in the driver. With pipelines built \
         in parallel, \"shader compose + naga\" and \"pipeline build\" add up every \
         thread's time; what they took together is \"compose + build, wall\" below, and \
         \"other prepare\" is the rest of prepare.\n"
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
    let _ = writeln!(
        out,
        "\nPipeline build and render in detail (median ms). \"GPU busy at build\": edits whose \
         first pipeline build began while earlier frames were still on the GPU. A driver that \
         compiles on first use shows it in \"submit → GPU done\" against the same frame \
         again; \"GPU frame\" is the sum of the passes' timestamps.\n"
    );
    let _ = write!(out, "| edit |");
    for (name, _) in DETAILS {
        let _ = write!(out, " {name} |");
    }
    let _ = writeln!(out, " GPU busy at build |");
    let _ = writeln!(out, "|---|{}--:|", "--:|".repeat(DETAILS.len()));
    for k in &kinds {
        let _ = write!(out, "| {} |", k.kind);
        for (_, v) in &k.details {
            let _ = write!(out, " {v:.1} |");
        }
        let (busy, of) = k.gpu_busy_at_build;
        let _ = writeln!(out, " {busy} of {of} |");
    }
    let pipelines = summarize_pipelines(samples);
    if !pipelines.is_empty() {
        let _ = writeln!(
            out,
            "\nEach pipeline built (pass: shader `material`), median ms.\n\n\
             | edit | pipeline | builds | compose + naga | create_shader_module | create_*_pipeline |\n\
             |---|---|--:|--:|--:|--:|"
        );
        for p in &pipelines {
            let _ = writeln!(
                out,
                "| {} | {} | {} | {:.1} | {:.1} | {:.1} |",
                p.kind, p.name, p.builds, p.compose_ms, p.module_ms, p.create_ms
            );
        }
    }
    out
}
