//! Benchmark reports: one [`BenchRow`] per (scene, technique, parameters, light count, size) run,
//! written as CSV, a Markdown table and PNG plots.
//!
//! Plots use plotters' bitmap backend with the `ab_glyph` text renderer and a bundled font
//! (DejaVu Sans Mono, `src/bench/fonts/`, Bitstream Vera licence), so they need no system fonts
//! and render the same on CI. The PNGs are encoded by the `image` crate.
//!
//! `row` holds the measurement and timing summaries, `tables` the CSV and Markdown output,
//! `plots` the PNG plots; this module writes them all into one folder.

mod plots;
mod row;
mod tables;

pub use plots::{
    plot_time_vs_error, plot_time_vs_error_points, plot_time_vs_lights, plot_time_vs_seed_error,
    PLOT_SIZE,
};
pub use row::{summarize, BenchRow, TimingSummary};
pub use tables::{
    non_finite_csv, to_csv, to_markdown, untimed_reason, write_csv, write_markdown, CSV_COLUMNS,
};

use std::path::{Path, PathBuf};

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
    /// `time_vs_seed_error.png`, when rows were timed and some has seed columns.
    pub time_vs_seed_error: Option<PathBuf>,
    /// Why the plots were not drawn, if they were not.
    pub plots_skipped: Option<String>,
}

/// Write `results.csv`, `results.md`, `non_finite_pixels.csv` and, when some row was timed,
/// `time_vs_lights.png` and `time_vs_error.png` into `dir` (created if missing), and
/// `time_vs_seed_error.png` when some row has seed columns. Without times the plots would be
/// nonsense: they are left out (a stale one from an earlier run is removed) and
/// `plots_skipped` says why.
pub fn write_report(dir: impl AsRef<Path>, rows: &[BenchRow]) -> Result<ReportFiles, ReportError> {
    let dir = dir.as_ref();
    let lights_png = dir.join("time_vs_lights.png");
    let error_png = dir.join("time_vs_error.png");
    let seed_png = dir.join("time_vs_seed_error.png");
    let skipped = untimed_reason(rows);
    let seeded = rows.iter().any(|r| r.seeds.is_some());
    let files = ReportFiles {
        csv: dir.join("results.csv"),
        markdown: dir.join("results.md"),
        non_finite: dir.join("non_finite_pixels.csv"),
        time_vs_lights: skipped.is_none().then(|| lights_png.clone()),
        time_vs_error: skipped.is_none().then(|| error_png.clone()),
        time_vs_seed_error: (skipped.is_none() && seeded).then(|| seed_png.clone()),
        plots_skipped: skipped,
    };
    write_csv(&files.csv, rows)?;
    write_markdown(&files.markdown, rows)?;
    write_file(&files.non_finite, &non_finite_csv(rows))?;
    if let (Some(l), Some(e)) = (&files.time_vs_lights, &files.time_vs_error) {
        plot_time_vs_lights(l, rows)?;
        plot_time_vs_error(e, rows)?;
    }
    if let Some(s) = &files.time_vs_seed_error {
        plot_time_vs_seed_error(s, rows)?;
    }
    let drawn = [
        (&lights_png, &files.time_vs_lights),
        (&error_png, &files.time_vs_error),
        (&seed_png, &files.time_vs_seed_error),
    ];
    for (stale, _) in drawn.iter().filter(|(_, file)| file.is_none()) {
        match std::fs::remove_file(stale) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(io_err(stale)(e)),
            _ => {}
        }
    }
    Ok(files)
}
