//! One benchmark measurement ([`BenchRow`]) and timing summaries (median, p10, p90).

use crate::bench::metrics::{ImageMetrics, NonFinitePixel};
use serde::{Deserialize, Serialize};

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
    /// Timed rounds (each ran every graph of the point in turn) and the smallest and
    /// largest of this graph's round medians, ms: the spread between rounds.
    pub rounds: Option<u32>,
    /// Smallest of this graph's round medians, ms.
    pub round_ms_min: Option<f64>,
    /// Largest of this graph's round medians, ms.
    pub round_ms_max: Option<f64>,
    /// Wall-clock seconds the point's warm-up took (all its graphs together).
    pub warmup_s: Option<f64>,
    /// Moving lights (a sweep's `animate:`): CPU milliseconds of one frame's light update,
    /// the median over the point's frames: `PreparedFrame::move_lights_to` (the motions'
    /// phases, the moving casters and indirect lights, the passes' light state; the GPU
    /// evaluates the rest, in the `light_motion` pass time).
    pub light_update_cpu_ms: Option<f64>,
    /// The GPU's SM clock before the point's warm-up and after its last round, and its
    /// maximum, MHz (`nvidia-smi`; `None` elsewhere).
    pub sm_mhz_start: Option<u32>,
    /// SM clock after the point's last round, MHz.
    pub sm_mhz_end: Option<u32>,
    /// The GPU's maximum SM clock, MHz.
    pub sm_mhz_max: Option<u32>,
    /// GPU time of each pass over the timed frames, ms, in schedule order (empty when untimed).
    pub pass_ms: Vec<(String, TimingSummary)>,
    /// RMSE against the reference (linear).
    pub rmse: Option<f64>,
    /// Largest absolute channel error against the reference.
    pub max_abs: Option<f64>,
    /// Largest relative channel error against the reference (floor: see
    /// [`crate::bench::metrics::REL_ERROR_FLOOR`]).
    pub max_rel: Option<f64>,
    /// PSNR against the reference, dB (`inf` when identical).
    pub psnr: Option<f64>,
    /// Mean FLIP against the reference.
    pub flip_mean: Option<f64>,
    /// Relative MSE against the reference (`ImageMetrics::rel_mse`).
    pub rel_mse: Option<f64>,
    /// Seeds the seed columns are over (a sweep's `seeds`), when measured.
    pub seeds: Option<u32>,
    /// The mean over channels of each channel's sample variance over the seeds, weighted
    /// as `rel_mse` weighs a squared error ([`crate::bench::SeedSpread::rel_variance`]).
    pub seed_rel_variance: Option<f64>,
    /// The squared bias of the seeds' mean against the reference on the same scale
    /// ([`crate::bench::SeedSpread::rel_bias2`]).
    pub seed_rel_bias2: Option<f64>,
    /// Lights listed per tile (or cluster) over lights that really touch it; 1 is exact culling.
    pub listed_exact_ratio: Option<f64>,
    /// Largest per-tile light count.
    pub max_lights_per_tile: Option<u32>,
    /// Lists (tiles, halves, clusters) that lost lights: past a fixed capacity, or past
    /// the end of a compact index array.
    pub overflow_tiles: Option<u32>,
    /// The first culling pass's lists: `fixed:CAPACITY` or `compact:MAX_INDICES`.
    pub list_storage: Option<String>,
    /// Their buffer (header, entries, index pool), MiB.
    pub list_mib: Option<f64>,
    /// Light indices the lists hold, and (compact lists) the indices they wanted.
    pub list_indices: Option<u64>,
    /// Light indices the compact lists wanted (more than `list_indices` when the index array
    /// overflowed).
    pub list_indices_wanted: Option<u64>,
    /// Compact lists whose fill disagreed with their count, or whose offset is not the
    /// sum of the counts before them (0 unless something is wrong).
    pub list_mismatched: Option<u32>,
    /// The culling pass's name, to find its time in `pass_ms`.
    pub list_pass: Option<String>,
    /// Pixels of the output with a NaN channel.
    pub nan_pixels: Option<u64>,
    /// Pixels of the output with an infinite channel and no NaN.
    pub inf_pixels: Option<u64>,
    /// The first NaN / infinite pixels of the output, row-major (all of them are counted above).
    pub non_finite_examples: Vec<NonFinitePixel>,
    /// Pixels of the output with some non-zero channel: 0 means the point shows no light at all.
    pub lit_pixels: Option<u64>,
    /// The graph whose image the error columns compare against (e.g. `brute_force`); `None`
    /// when no reference was rendered.
    pub reference: Option<String>,
    /// Ray-cast shadow rays traced this frame (every `ShadowRayJobs` pass together).
    pub shadow_rays: Option<u64>,
    /// Rays traced over the `ShadowRayCast` passes' median GPU time, rays a second (`None`
    /// when untimed).
    pub shadow_rays_per_s: Option<f64>,
    /// Shadow jobs past the job buffer's capacity (those lights are lit unshadowed).
    pub shadow_jobs_dropped: Option<u64>,
    /// Pixels with more than 128 shadow-casting lights (the rest are lit unshadowed).
    pub shadow_overflow_pixels: Option<u64>,
    /// Job and mask buffers of the shadow passes, MiB.
    pub shadow_buffers_mib: Option<f64>,
    /// The scene's shadow BVH on the GPU (nodes and triangles), MiB, when a pass that runs
    /// reads it.
    pub bvh_mib: Option<f64>,
    /// How long building that BVH took on the CPU, ms.
    pub bvh_build_ms: Option<f64>,
    /// Shadow atlases: texture and view table, MiB.
    pub atlas_mib: Option<f64>,
    /// Shadow-casting lights in view given a tile, and those without room (unshadowed).
    pub atlas_shadowed: Option<u64>,
    /// Shadow-casting lights in view left without a tile (lit unshadowed).
    pub atlas_dropped: Option<u64>,
    /// Atlas views (tiles) rendered: one per spot light, six per point light or wide spot.
    pub atlas_views: Option<u64>,
    /// Of those, the views the measured frame drew: all, or with `cache: true` the ones
    /// whose light or tile changed (the rest were kept from the frame before).
    pub atlas_views_rendered: Option<u64>,
    /// (pixel, light) pairs a ShadowCompare pass checked, and the fraction where the
    /// atlas disagrees with ray-cast shadows, per filter.
    pub shadow_pairs: Option<u64>,
    /// Fraction of `shadow_pairs` where the atlas filtered with `Pcf5x5` (25 taps) disagrees
    /// with ray-cast shadows.
    pub pair_error_pcf5: Option<f64>,
    /// Fraction of `shadow_pairs` where the atlas filtered with `Hardware2x2` (one tap)
    /// disagrees with ray-cast shadows.
    pub pair_error_2x2: Option<f64>,
    /// Light linked lists: heads and link pool, MiB.
    pub link_mib: Option<f64>,
    /// Links kept per list pixel, and the resolution divisor (1, 4, 8).
    pub links_per_list_pixel: Option<f64>,
    /// The link pool's resolution divisor (1, 4 or 8).
    pub link_scale: Option<u32>,
    /// Links past the pool (those lights are missing at their pixels).
    pub links_dropped: Option<u64>,
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
        self.rel_mse = Some(m.rel_mse);
        self.nan_pixels = Some(m.test_non_finite.nan_pixels as u64);
        self.inf_pixels = Some(m.test_non_finite.inf_pixels as u64);
    }

    /// Sum of the per-pass median times, if any pass was timed.
    pub(crate) fn passes_ms_total(&self) -> Option<f64> {
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
