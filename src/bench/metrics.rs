//! Error metrics between a reference and a test image, both linear HDR RGB(A) `f32`, row-major.
//!
//! Conventions (the same for every metric here):
//! - Differences are per channel on linear RGB; alpha is ignored.
//! - A pixel with a NaN or infinite channel in *either* image is left out of RMSE, max-abs and
//!   PSNR (one NaN would make them all NaN and hide the size of every other error); it is counted
//!   in [`NonFinite`] for its image and always counts as a bad pixel.
//! - FLIP is computed on both images tonemapped to sRGB8 by the same [`Tonemap`] (FLIP is an LDR
//!   metric), through the `nv-flip` crate (NVIDIA's reference C++ implementation).

use super::image_io::{read_exr, write_png_rgb8, ImageIoError};
use super::pixel::{luminance, HdrPixel};
use super::tonemap::Tonemap;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A comparison of images of different sizes, or a slice that does not match its size.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MetricsError {
    /// The reference and test slices do not both hold `width * height` pixels.
    #[error("image size mismatch: {width}x{height} expects {expected} pixels, reference has {reference}, test has {test}")]
    SizeMismatch {
        /// Declared width.
        width: u32,
        /// Declared height.
        height: u32,
        /// `width * height`.
        expected: usize,
        /// Reference pixel count.
        reference: usize,
        /// Test pixel count.
        test: usize,
    },
    /// Statistics over seeds need at least two images (one has no variance).
    #[error("the spread over seeds needs at least 2 images, got {images}")]
    TooFewImages {
        /// Images given.
        images: usize,
    },
}

/// What to compute in [`compare`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CompareOptions {
    /// A pixel is *bad* when its largest absolute channel difference is strictly above this
    /// (linear units), or when it is non-finite in either image.
    pub bad_pixel_threshold: f32,
    /// Compute the FLIP mean (costs a C++ FLIP pass; off for quick checks).
    pub flip: bool,
    /// Tonemapper used to bring both images to sRGB8 for FLIP.
    pub tonemap: Tonemap,
    /// FLIP viewing condition, pixels per degree of visual angle
    /// (`nv_flip::DEFAULT_PIXELS_PER_DEGREE` is 67: a 0.7 m distance from a 0.7 m wide 4K screen).
    pub pixels_per_degree: f32,
}

impl Default for CompareOptions {
    fn default() -> Self {
        Self {
            bad_pixel_threshold: 1e-3,
            flip: true,
            tonemap: Tonemap::default(),
            pixels_per_degree: nv_flip::DEFAULT_PIXELS_PER_DEGREE,
        }
    }
}

/// NaN / infinite pixel counts of one image (a pixel counts once, NaN first).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct NonFinite {
    /// Pixels with at least one NaN channel.
    pub nan_pixels: usize,
    /// Pixels with no NaN but at least one infinite channel.
    pub inf_pixels: usize,
}

/// Relative errors are measured against `max(|ref|, REL_ERROR_FLOOR × peak)`, the peak being the
/// brightest reference channel. A pure relative error is meaningless where the reference is 0
/// or nearly so (any residue is "infinitely" wrong); an error below a thousandth of the frame's
/// peak is also under what an 8-bit display resolves once exposed for that peak (1/255), so it
/// is judged against that floor. The floor scales with the image, so scenes lit at 1e-6 and at
/// 1e6 are held to the same standard.
pub const REL_ERROR_FLOOR: f64 = 1e-3;

/// The result of [`compare`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ImageMetrics {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Pixels finite in both images (the ones RMSE, max-abs and PSNR are over).
    pub compared_pixels: usize,
    /// Root mean square of the per-channel differences over the compared pixels (0 if none).
    pub rmse: f64,
    /// Largest absolute per-channel difference over the compared pixels.
    pub max_abs: f64,
    /// Largest per-channel `|test − ref| / max(|ref|, max_rel_floor)` over the compared pixels:
    /// the error relative to the pixel, or to the floor for dark pixels.
    pub max_rel: f64,
    /// The floor of `max_rel`: [`REL_ERROR_FLOOR`] × the largest finite reference channel
    /// (`f64::MIN_POSITIVE` for a black reference, so any light there counts as huge).
    pub max_rel_floor: f64,
    /// `10 log10(peak² / MSE)` in dB; `f64::INFINITY` when MSE is 0 (identical images).
    pub psnr: f64,
    /// The PSNR peak: the largest luminance (Rec. 709) of a finite reference pixel, or 1.0 if that
    /// is smaller (so a dark reference does not inflate PSNR).
    pub psnr_peak: f64,
    /// Pixels whose largest channel difference is above the threshold, plus non-finite pixels.
    pub bad_pixels: usize,
    /// The threshold used for `bad_pixels`.
    pub bad_pixel_threshold: f32,
    /// Non-finite pixels in the reference.
    pub reference_non_finite: NonFinite,
    /// Non-finite pixels in the test image.
    pub test_non_finite: NonFinite,
    /// Mean FLIP error in `[0, 1]` of the tonemapped images, if requested and the image is not empty.
    pub flip_mean: Option<f64>,
    /// Relative MSE: the mean over the compared pixels' channels of
    /// `(test − ref)² / (ref² + REL_MSE_EPSILON)`, the error measure of the denoising and
    /// resampling literature, where a dark pixel's error weighs as much as a bright one's.
    pub rel_mse: f64,
}

/// Added to `ref²` in [`ImageMetrics::rel_mse`] so black reference pixels stay finite.
pub const REL_MSE_EPSILON: f64 = 0.01;

/// The weight of a squared channel error in [`ImageMetrics::rel_mse`] where the reference
/// channel is `reference`: `1 / (ref² + REL_MSE_EPSILON)`. The seed statistics
/// ([`crate::bench::seed_spread`]) use it too, so they share rel_mse's scale.
pub(crate) fn rel_mse_weight(reference: f32) -> f64 {
    1.0 / ((reference as f64).powi(2) + REL_MSE_EPSILON)
}

impl std::fmt::Display for ImageMetrics {
    /// One line per metric, for `lightgraph compare` and test failure messages.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "size        {}x{}", self.width, self.height)?;
        writeln!(f, "RMSE        {:.6e}", self.rmse)?;
        writeln!(f, "max abs     {:.6e}", self.max_abs)?;
        writeln!(
            f,
            "max rel     {:.6e} (floor {:.3e})",
            self.max_rel, self.max_rel_floor
        )?;
        writeln!(
            f,
            "PSNR        {:.3} dB (peak {:.4})",
            self.psnr, self.psnr_peak
        )?;
        if let Some(flip) = self.flip_mean {
            writeln!(f, "FLIP mean   {flip:.6}")?;
        }
        writeln!(
            f,
            "bad pixels  {} (> {} or non-finite)",
            self.bad_pixels, self.bad_pixel_threshold
        )?;
        write!(
            f,
            "non-finite  reference: {} NaN, {} inf; test: {} NaN, {} inf",
            self.reference_non_finite.nan_pixels,
            self.reference_non_finite.inf_pixels,
            self.test_non_finite.nan_pixels,
            self.test_non_finite.inf_pixels
        )
    }
}

/// Error of [`compare_files`]: a file could not be read, or the sizes differ.
#[derive(Debug, thiserror::Error)]
pub enum CompareFilesError {
    /// Reading one of the files failed.
    #[error(transparent)]
    Read(#[from] ImageIoError),
    /// The images have different sizes.
    #[error("{} is {}x{} but {} is {}x{}", reference.display(), reference_size.0, reference_size.1, test.display(), test_size.0, test_size.1)]
    SizeMismatch {
        /// Reference file.
        reference: PathBuf,
        /// Its size.
        reference_size: (u32, u32),
        /// Test file.
        test: PathBuf,
        /// Its size.
        test_size: (u32, u32),
    },
}

/// Read two HDR files (EXR) and [`compare`] them.
pub fn compare_files(
    reference: impl AsRef<Path>,
    test: impl AsRef<Path>,
    options: &CompareOptions,
) -> Result<ImageMetrics, CompareFilesError> {
    let (rp, tp) = (reference.as_ref(), test.as_ref());
    let r = read_exr(rp)?;
    let t = read_exr(tp)?;
    if (r.width, r.height) != (t.width, t.height) {
        return Err(CompareFilesError::SizeMismatch {
            reference: rp.to_path_buf(),
            reference_size: (r.width, r.height),
            test: tp.to_path_buf(),
            test_size: (t.width, t.height),
        });
    }
    Ok(compare(&r.pixels, &t.pixels, r.width, r.height, options)
        .expect("sizes come from the decoded images"))
}

/// A NaN or infinite pixel and where it is.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NonFinitePixel {
    /// Column.
    pub x: u32,
    /// Row (0 at the top).
    pub y: u32,
    /// Linear RGB as rendered.
    pub(crate) rgb: [f32; 3],
}

impl NonFinitePixel {
    /// "NaN" or "Inf" (NaN wins, as in [`NonFinite`]).
    pub fn kind(&self) -> &'static str {
        if classify(self.rgb).0 {
            "NaN"
        } else {
            "Inf"
        }
    }
}

/// NaN and infinite pixel counts of one image (row-major, `width` wide), and the first `limit`
/// such pixels in row-major order.
pub fn non_finite_pixels<P: HdrPixel>(
    image: &[P],
    width: u32,
    limit: usize,
) -> (NonFinite, Vec<NonFinitePixel>) {
    let mut counts = NonFinite::default();
    let mut first = Vec::new();
    for (i, p) in image.iter().enumerate() {
        let rgb = p.rgb();
        let (nan, inf) = classify(rgb);
        counts.nan_pixels += nan as usize;
        counts.inf_pixels += inf as usize;
        if (nan || inf) && first.len() < limit {
            first.push(NonFinitePixel {
                x: (i % width.max(1) as usize) as u32,
                y: (i / width.max(1) as usize) as u32,
                rgb,
            });
        }
    }
    (counts, first)
}

fn classify(rgb: [f32; 3]) -> (bool, bool) {
    let nan = rgb.iter().any(|c| c.is_nan());
    let inf = !nan && rgb.iter().any(|c| c.is_infinite());
    (nan, inf)
}

fn check<P: HdrPixel>(
    reference: &[P],
    test: &[P],
    width: u32,
    height: u32,
) -> Result<(), MetricsError> {
    let expected = width as usize * height as usize;
    if reference.len() != expected || test.len() != expected {
        return Err(MetricsError::SizeMismatch {
            width,
            height,
            expected,
            reference: reference.len(),
            test: test.len(),
        });
    }
    Ok(())
}

/// Compare `test` against `reference` (both `width * height` pixels, row-major).
pub fn compare<P: HdrPixel>(
    reference: &[P],
    test: &[P],
    width: u32,
    height: u32,
    options: &CompareOptions,
) -> Result<ImageMetrics, MetricsError> {
    check(reference, test, width, height)?;
    let peak_channel = reference
        .iter()
        .flat_map(|p| p.rgb())
        .filter(|c| c.is_finite())
        .fold(0.0f64, |m, c| m.max(c.abs() as f64));
    let rel_floor = (REL_ERROR_FLOOR * peak_channel).max(f64::MIN_POSITIVE);
    let mut max_rel = 0.0f64;
    let mut sum_sq = 0.0f64;
    let mut sum_rel_sq = 0.0f64;
    let mut max_abs = 0.0f64;
    let mut compared = 0usize;
    let mut bad = 0usize;
    let mut peak = 1.0f64;
    let mut ref_nf = NonFinite::default();
    let mut test_nf = NonFinite::default();
    for (r, t) in reference.iter().zip(test) {
        let (r, t) = (r.rgb(), t.rgb());
        let (rn, ri) = classify(r);
        let (tn, ti) = classify(t);
        ref_nf.nan_pixels += rn as usize;
        ref_nf.inf_pixels += ri as usize;
        test_nf.nan_pixels += tn as usize;
        test_nf.inf_pixels += ti as usize;
        if rn || ri || tn || ti {
            bad += 1;
            continue;
        }
        peak = peak.max(luminance(r) as f64);
        compared += 1;
        let mut px_max = 0.0f64;
        for c in 0..3 {
            let d = (r[c] as f64 - t[c] as f64).abs();
            sum_sq += d * d;
            sum_rel_sq += d * d * rel_mse_weight(r[c]);
            px_max = px_max.max(d);
            max_rel = max_rel.max(d / (r[c].abs() as f64).max(rel_floor));
        }
        max_abs = max_abs.max(px_max);
        if px_max > options.bad_pixel_threshold as f64 {
            bad += 1;
        }
    }
    let (mse, rel_mse) = if compared == 0 {
        (0.0, 0.0)
    } else {
        let channels = (3 * compared) as f64;
        (sum_sq / channels, sum_rel_sq / channels)
    };
    let psnr = if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (peak * peak / mse).log10()
    };
    let flip_mean = if options.flip && width > 0 && height > 0 {
        Some(flip_mean_unchecked(
            reference,
            test,
            width,
            height,
            &options.tonemap,
            options.pixels_per_degree,
        ))
    } else {
        None
    };
    Ok(ImageMetrics {
        width,
        height,
        compared_pixels: compared,
        rmse: mse.sqrt(),
        max_abs,
        max_rel,
        max_rel_floor: rel_floor,
        psnr,
        psnr_peak: peak,
        bad_pixels: bad,
        bad_pixel_threshold: options.bad_pixel_threshold,
        reference_non_finite: ref_nf,
        test_non_finite: test_nf,
        flip_mean,
        rel_mse,
    })
}

fn flip_error_map<P: HdrPixel>(
    reference: &[P],
    test: &[P],
    width: u32,
    height: u32,
    tonemap: &Tonemap,
    pixels_per_degree: f32,
) -> nv_flip::FlipImageFloat {
    let r = nv_flip::FlipImageRgb8::with_data(width, height, &tonemap.image_to_srgb8(reference));
    let t = nv_flip::FlipImageRgb8::with_data(width, height, &tonemap.image_to_srgb8(test));
    nv_flip::flip(r, t, pixels_per_degree)
}

fn flip_mean_unchecked<P: HdrPixel>(
    reference: &[P],
    test: &[P],
    width: u32,
    height: u32,
    tonemap: &Tonemap,
    pixels_per_degree: f32,
) -> f64 {
    let map = flip_error_map(reference, test, width, height, tonemap, pixels_per_degree);
    nv_flip::FlipPool::from_image(&map).mean() as f64
}

/// Mean FLIP error (in `[0, 1]`) between the two images after tonemapping both with `tonemap`.
/// Returns 0 for an empty image.
pub fn flip_mean<P: HdrPixel>(
    reference: &[P],
    test: &[P],
    width: u32,
    height: u32,
    tonemap: &Tonemap,
    pixels_per_degree: f32,
) -> Result<f64, MetricsError> {
    check(reference, test, width, height)?;
    if width == 0 || height == 0 {
        return Ok(0.0);
    }
    Ok(flip_mean_unchecked(
        reference,
        test,
        width,
        height,
        tonemap,
        pixels_per_degree,
    ))
}

/// How [`difference_heatmap`] scales `|a − b|` to the colour ramp.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum HeatScale {
    /// The largest finite difference maps to the top of the ramp.
    Auto,
    /// This difference (linear units) maps to the top of the ramp; larger ones saturate.
    Fixed(f32),
}

/// Heat-map colour of `t` in `[0, 1]`: black, purple, red, orange, yellow, white (an inferno-like ramp).
pub fn heat_color(t: f32) -> [u8; 3] {
    const STOPS: [[f32; 3]; 6] = [
        [0.0, 0.0, 0.0],
        [0.34, 0.06, 0.43],
        [0.73, 0.21, 0.33],
        [0.98, 0.50, 0.09],
        [0.98, 0.85, 0.22],
        [1.0, 1.0, 1.0],
    ];
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (STOPS.len() - 1) as f32;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as f32;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    [0, 1, 2].map(|c| ((a[c] + (b[c] - a[c]) * f) * 255.0 + 0.5) as u8)
}

/// Colour of pixels that are NaN in either image in [`difference_heatmap`] (bright green).
pub const HEATMAP_NAN_COLOR: [u8; 3] = [0, 255, 0];
/// Colour of pixels that are infinite (and not NaN) in either image (cyan).
pub(crate) const HEATMAP_INF_COLOR: [u8; 3] = [0, 255, 255];

/// Per-pixel heat map of the largest absolute channel difference `max_c |a_c − b_c|`, as tightly
/// packed RGB8 (the ramp is [`heat_color`]; non-finite pixels get [`HEATMAP_NAN_COLOR`] /
/// `HEATMAP_INF_COLOR`, colours the ramp never produces). Returns the pixels and the difference
/// that maps to the top of the ramp.
pub fn difference_heatmap<P: HdrPixel>(
    reference: &[P],
    test: &[P],
    width: u32,
    height: u32,
    scale: HeatScale,
) -> Result<(Vec<u8>, f32), MetricsError> {
    check(reference, test, width, height)?;
    let diffs: Vec<Result<f32, [u8; 3]>> = reference
        .iter()
        .zip(test)
        .map(|(r, t)| {
            let (r, t) = (r.rgb(), t.rgb());
            let (rn, ri) = classify(r);
            let (tn, ti) = classify(t);
            if rn || tn {
                Err(HEATMAP_NAN_COLOR)
            } else if ri || ti {
                Err(HEATMAP_INF_COLOR)
            } else {
                Ok((0..3).map(|c| (r[c] - t[c]).abs()).fold(0.0, f32::max))
            }
        })
        .collect();
    let top = match scale {
        HeatScale::Fixed(v) => v,
        HeatScale::Auto => diffs
            .iter()
            .filter_map(|d| d.as_ref().ok().copied())
            .fold(0.0, f32::max),
    };
    let mut out = Vec::with_capacity(diffs.len() * 3);
    for d in diffs {
        let c = match d {
            Ok(d) if top > 0.0 => heat_color(d / top),
            Ok(_) => heat_color(0.0),
            Err(c) => c,
        };
        out.extend_from_slice(&c);
    }
    Ok((out, top))
}

/// Error of [`write_difference_png`]: bad sizes or an unwritable file.
#[derive(Debug, thiserror::Error)]
pub enum DiffImageError {
    /// The images do not match their size.
    #[error(transparent)]
    Metrics(#[from] MetricsError),
    /// Writing the PNG failed.
    #[error(transparent)]
    Io(#[from] ImageIoError),
}

/// Write [`difference_heatmap`] as a PNG; returns the difference at the top of the ramp.
pub fn write_difference_png<P: HdrPixel>(
    path: impl AsRef<Path>,
    reference: &[P],
    test: &[P],
    width: u32,
    height: u32,
    scale: HeatScale,
) -> Result<f32, DiffImageError> {
    let (rgb, top) = difference_heatmap(reference, test, width, height, scale)?;
    write_png_rgb8(path, rgb, width, height)?;
    Ok(top)
}

/// Write the FLIP error map (magma colour map, as the FLIP tool shows it) as a PNG.
pub fn write_flip_png<P: HdrPixel>(
    path: impl AsRef<Path>,
    reference: &[P],
    test: &[P],
    width: u32,
    height: u32,
    options: &CompareOptions,
) -> Result<(), DiffImageError> {
    check(reference, test, width, height)?;
    let path = path.as_ref();
    if width == 0 || height == 0 {
        write_png_rgb8(path, Vec::new(), width, height)?;
        return Ok(());
    }
    let map = flip_error_map(
        reference,
        test,
        width,
        height,
        &options.tonemap,
        options.pixels_per_degree,
    );
    let rgb = map.apply_color_lut(&nv_flip::magma_lut()).to_vec();
    write_png_rgb8(path, rgb, width, height)?;
    Ok(())
}
