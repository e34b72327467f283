//! Benchmark support: image error metrics (RMSE, max abs, PSNR, FLIP, bad / NaN pixels), the
//! spread of a seeded frame over seeds, the project's one tonemapper, HDR image I/O (EXR,
//! tonemapped PNG), and reports (CSV, Markdown, PNG plots). Only the sweeps and the
//! hot-reload latency benchmark need a GPU.

pub(crate) mod animate;
pub(crate) mod cases;
pub(crate) mod gpu_clock;
pub mod heatmap;
pub mod image_io;
pub mod metrics;
pub(crate) mod pixel;
pub mod progress;
pub mod reload_latency;
pub mod report;
pub mod seed_spread;
pub mod sweep;
mod sweep_columns;
pub(crate) mod timing;
pub mod tonemap;

pub use image_io::{
    read_exr, write_exr, write_png_rgb8, write_png_tonemapped, HdrImage, ImageIoError,
};
pub use metrics::non_finite_pixels;
pub use metrics::{
    compare, compare_files, difference_heatmap, flip_mean, heat_color, write_difference_png,
    write_flip_png, CompareFilesError, CompareOptions, DiffImageError, HeatScale, ImageMetrics,
    MetricsError, NonFinite, NonFinitePixel, REL_ERROR_FLOOR,
};
pub use pixel::{luminance, HdrPixel};
pub use report::{
    non_finite_csv, plot_time_vs_error, plot_time_vs_lights, plot_time_vs_seed_error, summarize,
    to_csv, to_markdown, untimed_reason, write_csv, write_markdown, write_report, BenchRow,
    ReportError, ReportFiles, TimingSummary,
};
pub use seed_spread::{seed_spread, SeedSpread, SeedSpreadAccumulator};
pub use tonemap::{linear_to_srgb, srgb_to_linear, ToneCurve, Tonemap};
