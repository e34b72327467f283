//! Benchmark reports: one [`BenchRow`] per (scene, technique, parameters, light count, size) run,
//! written as CSV, a Markdown table and PNG plots.
//!
//! Plots use plotters' bitmap backend with the `ab_glyph` text renderer and a bundled font
//! (DejaVu Sans Mono, `src/bench/fonts/`, Bitstream Vera licence), so they need no system fonts
//! and render the same on CI. The PNGs are encoded by the `image` crate.

use super::metrics::{ImageMetrics, NonFinitePixel};
use plotters::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One benchmark measurement. Optional fields are `None` where they do not apply (the reference
/// has no error against itself to speak of; brute force has no tiles).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct BenchRow {
    /// Scene name or file.
    pub scene: String,
    /// Graph / technique name (e.g. `forward_plus`); plots group series by this.
    pub technique: String,
    /// Free-form parameters, e.g. `tile=16 depth_bins=32`.
    pub params: String,
    /// Number of lights in the scene.
    pub light_count: u32,
    /// Render width.
    pub width: u32,
    /// Render height.
    pub height: u32,
    /// `wgpu::AdapterInfo::name`.
    pub adapter: String,
    /// GPU frame time (the sum of the per-pass timestamps) over the timed frames, ms; `None`
    /// when nothing was timed (the adapter has no timestamp queries).
    pub frame_ms: Option<TimingSummary>,
    /// Why `frame_ms` is `None` (e.g. "the adapter has no timestamp queries").
    pub untimed: Option<String>,
    /// GPU time of each pass over the timed frames, ms, in schedule order (empty when untimed).
    pub pass_ms: Vec<(String, TimingSummary)>,
    /// RMSE against the reference (linear).
    pub rmse: Option<f64>,
    /// Largest absolute channel error against the reference.
    pub max_abs: Option<f64>,
    /// Largest relative channel error against the reference (floor: see
    /// [`super::metrics::REL_ERROR_FLOOR`]).
    pub max_rel: Option<f64>,
    /// PSNR against the reference, dB (`inf` when identical).
    pub psnr: Option<f64>,
    /// Mean FLIP against the reference.
    pub flip_mean: Option<f64>,
    /// Lights listed per tile (or cluster) over lights that really touch it; 1 is exact culling.
    pub listed_exact_ratio: Option<f64>,
    /// Largest per-tile light count.
    pub max_lights_per_tile: Option<u32>,
    /// Tiles whose list overflowed.
    pub overflow_tiles: Option<u32>,
    /// Pixels of the output with a NaN channel.
    pub nan_pixels: Option<u64>,
    /// Pixels of the output with an infinite channel and no NaN.
    pub inf_pixels: Option<u64>,
    /// The first NaN / infinite pixels of the output, row-major (all of them are counted above).
    pub non_finite_examples: Vec<NonFinitePixel>,
    /// Pixels of the output with some non-zero channel: 0 means the point shows no light at all.
    pub lit_pixels: Option<u64>,
}

impl BenchRow {
    /// Fill the error fields (RMSE, max abs, max rel, PSNR, FLIP mean, NaN and Inf pixels of the
    /// test image) from a comparison against the reference.
    pub fn set_metrics(&mut self, m: &ImageMetrics) {
        self.rmse = Some(m.rmse);
        self.max_abs = Some(m.max_abs);
        self.max_rel = Some(m.max_rel);
        self.psnr = Some(m.psnr);
        self.flip_mean = m.flip_mean;
        self.nan_pixels = Some(m.test_non_finite.nan_pixels as u64);
        self.inf_pixels = Some(m.test_non_finite.inf_pixels as u64);
    }

    /// Sum of the per-pass median times, if any pass was timed.
    pub fn passes_ms_total(&self) -> Option<f64> {
        (!self.pass_ms.is_empty()).then(|| self.pass_ms.iter().map(|(_, t)| t.median).sum())
    }
}

/// Median and 10th / 90th percentiles of a set of timings.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct TimingSummary {
    /// Median.
    pub median: f64,
    /// 10th percentile.
    pub p10: f64,
    /// 90th percentile.
    pub p90: f64,
}

/// Percentile of sorted samples with linear interpolation between closest ranks.
fn percentile_sorted(sorted: &[f64], p: f64) -> f64 {
    let pos = p * (sorted.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = pos.ceil() as usize;
    sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - lo as f64)
}

/// Median, p10 and p90 (linear interpolation between closest ranks) of the finite samples;
/// `None` if there are none.
pub fn summarize(samples: &[f64]) -> Option<TimingSummary> {
    let mut s: Vec<f64> = samples.iter().copied().filter(|x| x.is_finite()).collect();
    if s.is_empty() {
        return None;
    }
    s.sort_by(f64::total_cmp);
    Some(TimingSummary {
        median: percentile_sorted(&s, 0.5),
        p10: percentile_sorted(&s, 0.1),
        p90: percentile_sorted(&s, 0.9),
    })
}

/// A report-writing error; names the file.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// Creating or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// Drawing a plot failed.
    #[error("{}: plot: {message}", path.display())]
    Plot {
        /// The file.
        path: PathBuf,
        /// What plotters said.
        message: String,
    },
    /// Encoding a plot failed.
    #[error(transparent)]
    Image(#[from] super::image_io::ImageIoError),
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn write_file(path: &Path, text: &str) -> Result<(), ReportError> {
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(io_err(path))?;
    }
    std::fs::write(path, text).map_err(io_err(path))
}

/// Pass names over all rows, in first-seen order.
fn pass_names(rows: &[BenchRow]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for row in rows {
        for (name, _) in &row.pass_ms {
            if !names.contains(name) {
                names.push(name.clone());
            }
        }
    }
    names
}

fn pass_ms(row: &BenchRow, name: &str) -> Option<TimingSummary> {
    row.pass_ms.iter().find(|(n, _)| n == name).map(|(_, t)| *t)
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn opt<T: ToString>(v: Option<T>) -> String {
    v.map(|v| v.to_string()).unwrap_or_default()
}

/// The fixed CSV columns, in order; per-pass columns follow, three per pass name seen in any
/// row (first-seen order): `pass_ms:<name>` (median), `pass_ms_p10:<name>`, `pass_ms_p90:<name>`,
/// empty where a row lacks that pass. Time columns are empty, not 0, for untimed rows.
pub const CSV_COLUMNS: [&str; 23] = [
    "scene",
    "technique",
    "params",
    "light_count",
    "width",
    "height",
    "adapter",
    "frame_ms_median",
    "frame_ms_p10",
    "frame_ms_p90",
    "rmse",
    "max_abs",
    "max_rel",
    "psnr",
    "flip_mean",
    "listed_exact_ratio",
    "max_lights_per_tile",
    "overflow_tiles",
    "nan_pixels",
    "inf_pixels",
    "lit_pixels",
    "pass_count",
    "passes_ms_total",
];

/// The rows as CSV (RFC 4180 quoting; floats in Rust's shortest round-trip form, `inf` for an
/// infinite PSNR, empty for `None`).
pub fn to_csv(rows: &[BenchRow]) -> String {
    let passes = pass_names(rows);
    let mut out = String::new();
    let mut header: Vec<String> = CSV_COLUMNS.iter().map(|s| s.to_string()).collect();
    for p in &passes {
        for column in ["pass_ms", "pass_ms_p10", "pass_ms_p90"] {
            header.push(csv_field(&format!("{column}:{p}")));
        }
    }
    out.push_str(&header.join(","));
    out.push('\n');
    for r in rows {
        let t = r.frame_ms;
        let mut f = vec![
            csv_field(&r.scene),
            csv_field(&r.technique),
            csv_field(&r.params),
            r.light_count.to_string(),
            r.width.to_string(),
            r.height.to_string(),
            csv_field(&r.adapter),
            opt(t.map(|t| t.median)),
            opt(t.map(|t| t.p10)),
            opt(t.map(|t| t.p90)),
            opt(r.rmse),
            opt(r.max_abs),
            opt(r.max_rel),
            opt(r.psnr),
            opt(r.flip_mean),
            opt(r.listed_exact_ratio),
            opt(r.max_lights_per_tile),
            opt(r.overflow_tiles),
            opt(r.nan_pixels),
            opt(r.inf_pixels),
            opt(r.lit_pixels),
            r.pass_ms.len().to_string(),
            opt(r.passes_ms_total()),
        ];
        for p in &passes {
            let t = pass_ms(r, p);
            f.extend([
                opt(t.map(|t| t.median)),
                opt(t.map(|t| t.p10)),
                opt(t.map(|t| t.p90)),
            ]);
        }
        out.push_str(&f.join(","));
        out.push('\n');
    }
    out
}

/// The non-finite pixels the rows list, as CSV: one line per pixel with its point.
pub fn non_finite_csv(rows: &[BenchRow]) -> String {
    let mut out = String::from("scene,technique,params,light_count,width,height,kind,x,y,r,g,b\n");
    for r in rows {
        for p in &r.non_finite_examples {
            let _ = writeln!(
                out,
                "{},{},{},{},{},{},{},{},{},{},{},{}",
                csv_field(&r.scene),
                csv_field(&r.technique),
                csv_field(&r.params),
                r.light_count,
                r.width,
                r.height,
                p.kind(),
                p.x,
                p.y,
                p.rgb[0],
                p.rgb[1],
                p.rgb[2]
            );
        }
    }
    out
}

/// Why time plots cannot be drawn for these rows, if they cannot.
pub fn untimed_reason(rows: &[BenchRow]) -> Option<String> {
    if rows.is_empty() {
        return Some("no rows".into());
    }
    if rows.iter().any(|r| r.frame_ms.is_some()) {
        return None;
    }
    let mut reasons: Vec<&str> = rows
        .iter()
        .map(|r| r.untimed.as_deref().unwrap_or("not measured"))
        .collect();
    reasons.sort_unstable();
    reasons.dedup();
    Some(reasons.join("; "))
}

fn md_cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

fn md_num(v: Option<f64>, digits: usize) -> String {
    match v {
        None => "–".to_string(),
        Some(x) if x.is_infinite() && x > 0.0 => "∞".to_string(),
        Some(x) if x != 0.0 && (x.abs() < 1e-3 || x.abs() >= 1e6) => format!("{x:.2e}"),
        Some(x) => format!("{x:.digits$}"),
    }
}

/// The rows as GitHub-flavoured Markdown: a results table, a note when nothing was timed, then
/// a per-pass table (median, p10–p90 per pass name) if any row has timed passes.
pub fn to_markdown(rows: &[BenchRow]) -> String {
    let mut out = String::new();
    out.push_str("| scene | technique | params | lights | size | adapter | median ms | p10 | p90 | RMSE | max abs | max rel | PSNR dB | FLIP | listed/exact | max/tile | overflow | NaN px | Inf px | lit px |\n");
    out.push_str(
        "|---|---|---|--:|--:|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n",
    );
    for r in rows {
        let t = r.frame_ms;
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {}x{} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            md_cell(&r.scene),
            md_cell(&r.technique),
            md_cell(&r.params),
            r.light_count,
            r.width,
            r.height,
            md_cell(&r.adapter),
            md_num(t.map(|t| t.median), 3),
            md_num(t.map(|t| t.p10), 3),
            md_num(t.map(|t| t.p90), 3),
            md_num(r.rmse, 5),
            md_num(r.max_abs, 4),
            md_num(r.max_rel, 4),
            md_num(r.psnr, 2),
            md_num(r.flip_mean, 4),
            md_num(r.listed_exact_ratio, 3),
            opt(r.max_lights_per_tile),
            opt(r.overflow_tiles),
            opt(r.nan_pixels),
            opt(r.inf_pixels),
            opt(r.lit_pixels),
        );
    }
    if let Some(reason) = untimed_reason(rows).filter(|_| !rows.is_empty()) {
        let _ = writeln!(
            out,
            "\nNo GPU times ({reason}): the time columns are empty and the time plots were not drawn."
        );
    }
    let passes = pass_names(rows);
    if !passes.is_empty() {
        out.push_str(
            "\nPer-pass GPU time, ms: median (p10–p90):\n\n| scene | technique | params | lights |",
        );
        for p in &passes {
            let _ = write!(out, " {} |", md_cell(p));
        }
        out.push_str("\n|---|---|---|--:|");
        for _ in &passes {
            out.push_str("--:|");
        }
        out.push('\n');
        for r in rows {
            let _ = write!(
                out,
                "| {} | {} | {} | {} |",
                md_cell(&r.scene),
                md_cell(&r.technique),
                md_cell(&r.params),
                r.light_count
            );
            for p in &passes {
                let cell = match pass_ms(r, p) {
                    Some(t) => format!(
                        "{} ({}–{})",
                        md_num(Some(t.median), 3),
                        md_num(Some(t.p10), 3),
                        md_num(Some(t.p90), 3)
                    ),
                    None => "–".into(),
                };
                let _ = write!(out, " {cell} |");
            }
            out.push('\n');
        }
    }
    out
}

/// Write [`to_csv`] to `path` (creating the parent directory).
pub fn write_csv(path: impl AsRef<Path>, rows: &[BenchRow]) -> Result<(), ReportError> {
    write_file(path.as_ref(), &to_csv(rows))
}

/// Write [`to_markdown`] to `path` (creating the parent directory).
pub fn write_markdown(path: impl AsRef<Path>, rows: &[BenchRow]) -> Result<(), ReportError> {
    write_file(path.as_ref(), &to_markdown(rows))
}

static FONT: &[u8] = include_bytes!("fonts/DejaVuSansMono.ttf");

fn register_fonts() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        for family in ["sans-serif", "serif", "monospace"] {
            plotters::style::register_font(family, plotters::style::FontStyle::Normal, FONT)
                .unwrap_or_else(|_| panic!("bundled font is a valid TrueType font"));
        }
    });
}

/// Size of the plot PNGs.
pub const PLOT_SIZE: (u32, u32) = (1024, 640);

/// A point: (x, median, p10, p90).
type Point = (f64, f64, f64, f64);
/// Labelled series of points, each sorted by x, in legend order.
type Series = Vec<(String, Vec<Point>)>;

/// Axis label: integers as integers, otherwise up to 4 significant digits, scientific notation
/// outside `[1e-3, 1e5)`.
fn axis_label(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    if x.abs() < 1e-3 || x.abs() >= 1e5 {
        return format!("{x:.1e}");
    }
    if x.fract() == 0.0 {
        return format!("{x:.0}");
    }
    let digits = (3 - x.abs().log10().floor() as i32).clamp(0, 6) as usize;
    let s = format!("{x:.digits$}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

fn render_plot(
    path: &Path,
    title: &str,
    x_desc: &str,
    log_x: bool,
    series: &Series,
) -> Result<(), ReportError> {
    register_fonts();
    let (w, h) = PLOT_SIZE;
    let mut buf = vec![0u8; (w * h * 3) as usize];
    let plot_err = |e: &dyn std::fmt::Display| ReportError::Plot {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(&e))?;
        let pts = series.iter().flat_map(|(_, p)| p);
        let (mut x0, mut x1, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
        for &(x, _, _, yh) in pts {
            x0 = x0.min(x);
            x1 = x1.max(x);
            y1 = y1.max(yh);
        }
        if !x0.is_finite() {
            (x0, x1) = (1.0, 10.0);
        }
        if log_x {
            x0 = x0.max(1e-12);
            x1 = x1.max(x0 * 10.0);
            (x0, x1) = (x0 / 1.5, x1 * 1.5);
        } else {
            let pad = ((x1 - x0) * 0.05).max(x1.abs() * 0.05).max(1e-9);
            // Errors are non-negative: start the axis at 0 so "exact" sits on the axis.
            (x0, x1) = (if x0 >= 0.0 { 0.0 } else { x0 - pad }, x1 + pad);
        }
        let y1 = if y1 > 0.0 { y1 * 1.1 } else { 1.0 };
        let mut builder = ChartBuilder::on(&root);
        builder
            .caption(title, ("sans-serif", 24))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(72);
        macro_rules! draw {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(x_desc)
                    .x_label_formatter(&|x: &f64| axis_label(*x))
                    .y_label_formatter(&|y: &f64| axis_label(*y))
                    .y_desc("frame time, median (ms); bars p10-p90")
                    .draw()
                    .map_err(|e| plot_err(&e))?;
                for (i, (name, points)) in series.iter().enumerate() {
                    let color = Palette99::pick(i).to_rgba();
                    chart
                        .draw_series(LineSeries::new(
                            points.iter().map(|p| (p.0, p.1)),
                            color.stroke_width(2),
                        ))
                        .map_err(|e| plot_err(&e))?
                        .label(name.as_str())
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                        });
                    chart
                        .draw_series(
                            points
                                .iter()
                                .map(|p| Circle::new((p.0, p.1), 4, color.filled())),
                        )
                        .map_err(|e| plot_err(&e))?;
                    chart
                        .draw_series(points.iter().map(|p| {
                            PathElement::new(vec![(p.0, p.2), (p.0, p.3)], color.stroke_width(1))
                        }))
                        .map_err(|e| plot_err(&e))?;
                }
                chart
                    .configure_series_labels()
                    .position(SeriesLabelPosition::UpperLeft)
                    .background_style(&WHITE.mix(0.85))
                    .border_style(&BLACK)
                    .draw()
                    .map_err(|e| plot_err(&e))?;
            }};
        }
        if log_x {
            draw!(builder
                .build_cartesian_2d((x0..x1).log_scale(), 0.0..y1)
                .map_err(|e| plot_err(&e))?);
        } else {
            draw!(builder
                .build_cartesian_2d(x0..x1, 0.0..y1)
                .map_err(|e| plot_err(&e))?);
        }
        root.present().map_err(|e| plot_err(&e))?;
    }
    super::image_io::write_png_rgb8(path, buf, w, h)?;
    Ok(())
}

/// Plot median frame time (p10–p90 bars) against light count (log x), one line per technique.
pub fn plot_time_vs_lights(path: impl AsRef<Path>, rows: &[BenchRow]) -> Result<(), ReportError> {
    let mut series: BTreeMap<String, Vec<Point>> = BTreeMap::new();
    for r in rows.iter().filter(|r| r.light_count > 0) {
        if let Some(t) = r.frame_ms {
            series.entry(r.technique.clone()).or_default().push((
                r.light_count as f64,
                t.median,
                t.p10,
                t.p90,
            ));
        }
    }
    let series: Series = series
        .into_iter()
        .map(|(name, mut points)| {
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            (name, points)
        })
        .collect();
    render_plot(
        path.as_ref(),
        "Frame time vs light count",
        "lights (log)",
        true,
        &series,
    )
}

/// Plot median frame time (p10–p90 bars) against RMSE (linear x from 0; rows without RMSE are
/// left out), one series per technique, points joined in order of RMSE (a parameter sweep then
/// draws its time/error trade-off curve). If the rows hold several light counts, each
/// (technique, light count) pair is its own series, labelled `technique @ N lights`, so points
/// of different scene sizes are never joined.
pub fn plot_time_vs_error(path: impl AsRef<Path>, rows: &[BenchRow]) -> Result<(), ReportError> {
    let with_error = || {
        rows.iter()
            .filter(|r| r.rmse.is_some_and(f64::is_finite) && r.frame_ms.is_some())
    };
    let first_count = with_error().next().map(|r| r.light_count);
    let several_counts = with_error().any(|r| Some(r.light_count) != first_count);
    let mut series: BTreeMap<(String, u32), Vec<Point>> = BTreeMap::new();
    for r in with_error() {
        if let (Some(e), Some(t)) = (r.rmse, r.frame_ms) {
            let key = (
                r.technique.clone(),
                if several_counts { r.light_count } else { 0 },
            );
            series
                .entry(key)
                .or_default()
                .push((e, t.median, t.p10, t.p90));
        }
    }
    let series: Series = series
        .into_iter()
        .map(|((technique, lights), mut points)| {
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            let name = if several_counts {
                format!("{technique} @ {lights} lights")
            } else {
                technique
            };
            (name, points)
        })
        .collect();
    render_plot(
        path.as_ref(),
        "Frame time vs error",
        "RMSE vs reference (linear)",
        false,
        &series,
    )
}

/// Files written by [`write_report`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReportFiles {
    /// `results.csv`
    pub csv: PathBuf,
    /// `results.md`
    pub markdown: PathBuf,
    /// `non_finite_pixels.csv`: the listed NaN / Inf pixels of every row.
    pub non_finite: PathBuf,
    /// `time_vs_lights.png`, unless no row was timed.
    pub time_vs_lights: Option<PathBuf>,
    /// `time_vs_error.png`, unless no row was timed.
    pub time_vs_error: Option<PathBuf>,
    /// Why the plots were not drawn, if they were not.
    pub plots_skipped: Option<String>,
}

/// Write `results.csv`, `results.md`, `non_finite_pixels.csv` and, when some row was timed,
/// `time_vs_lights.png` and `time_vs_error.png` into `dir` (created if missing). Without times
/// the plots would be nonsense: they are left out (a stale one from an earlier run is removed)
/// and `plots_skipped` says why.
pub fn write_report(dir: impl AsRef<Path>, rows: &[BenchRow]) -> Result<ReportFiles, ReportError> {
    let dir = dir.as_ref();
    let lights_png = dir.join("time_vs_lights.png");
    let error_png = dir.join("time_vs_error.png");
    let skipped = untimed_reason(rows);
    let files = ReportFiles {
        csv: dir.join("results.csv"),
        markdown: dir.join("results.md"),
        non_finite: dir.join("non_finite_pixels.csv"),
        time_vs_lights: skipped.is_none().then(|| lights_png.clone()),
        time_vs_error: skipped.is_none().then(|| error_png.clone()),
        plots_skipped: skipped,
    };
    write_csv(&files.csv, rows)?;
    write_markdown(&files.markdown, rows)?;
    write_file(&files.non_finite, &non_finite_csv(rows))?;
    match (&files.time_vs_lights, &files.time_vs_error) {
        (Some(l), Some(e)) => {
            plot_time_vs_lights(l, rows)?;
            plot_time_vs_error(e, rows)?;
        }
        _ => {
            for stale in [&lights_png, &error_png] {
                match std::fs::remove_file(stale) {
                    Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                        return Err(io_err(stale)(e))
                    }
                    _ => {}
                }
            }
        }
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::axis_label;

    #[test]
    fn axis_labels_are_short() {
        assert_eq!(axis_label(0.0), "0");
        assert_eq!(axis_label(1000.0), "1000");
        assert_eq!(axis_label(0.15000000000000002), "0.15");
        assert_eq!(axis_label(0.39999999), "0.4");
        assert_eq!(axis_label(12.5), "12.5");
        assert_eq!(axis_label(2e-5), "2.0e-5");
    }
}
