//! The spread of a seeded estimator over seeds: the same frame rendered with S seeds, each
//! channel's sample variance over them and the squared bias of their mean against the
//! reference, both per linear RGB channel and weighted as
//! [`rel_mse`](super::ImageMetrics::rel_mse) weighs a squared error, so the three share
//! one scale: in expectation a single image's rel_mse is `rel_bias2 + rel_variance`.
//!
//! The images are streamed (Welford's running mean and sum of squared deviations, in
//! f64), so memory does not grow with the number of seeds.

use super::metrics::{rel_mse_weight, MetricsError};
use super::pixel::HdrPixel;
use serde::Serialize;

/// The result of [`SeedSpreadAccumulator::finish`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SeedSpread {
    /// Images (seeds) the statistics are over.
    pub seeds: usize,
    /// Pixels finite in the reference and in every image (the ones averaged over).
    pub compared_pixels: usize,
    /// The mean over the compared pixels' channels of `s² / (ref² + 0.01)`, `s²` the
    /// channel's unbiased sample variance over the seeds (divided by S − 1): the noise
    /// part of rel_mse.
    pub rel_variance: f64,
    /// The mean over the same channels of `((m − ref)² − s²/S) / (ref² + 0.01)`, `m` the
    /// mean over the seeds: `(m − ref)²` overstates the squared bias by the variance of
    /// the mean, `σ²/S`, which `s²/S` estimates without bias. It is the bias part of
    /// rel_mse; by chance it can fall a little below 0 where the bias is small against
    /// the noise.
    pub rel_bias2: f64,
}

/// Streams the images of one frame rendered with different seeds, then compares them
/// with the reference in [`finish`](Self::finish).
#[derive(Debug, Clone)]
pub struct SeedSpreadAccumulator {
    width: u32,
    height: u32,
    images: usize,
    /// Per pixel and channel, the running mean.
    mean: Vec<[f64; 3]>,
    /// Per pixel and channel, the running sum of squared deviations from the mean.
    deviations: Vec<[f64; 3]>,
    /// Per pixel, whether every image so far was finite there.
    finite: Vec<bool>,
}

impl SeedSpreadAccumulator {
    /// An empty accumulator for `width × height` images.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            images: 0,
            mean: vec![[0.0; 3]; n],
            deviations: vec![[0.0; 3]; n],
            finite: vec![true; n],
        }
    }

    /// Images added so far.
    pub fn images(&self) -> usize {
        self.images
    }

    /// Adds one seed's image (`width × height` pixels, row-major; alpha ignored).
    pub fn add<P: HdrPixel>(&mut self, image: &[P]) -> Result<(), MetricsError> {
        self.check(image.len(), image.len())?;
        self.images += 1;
        let n = self.images as f64;
        for (i, p) in image.iter().enumerate() {
            let rgb = p.rgb();
            if !rgb.iter().all(|c| c.is_finite()) {
                self.finite[i] = false;
            }
            if !self.finite[i] {
                continue;
            }
            for (c, &v) in rgb.iter().enumerate() {
                let v = v as f64;
                let delta = v - self.mean[i][c];
                self.mean[i][c] += delta / n;
                self.deviations[i][c] += delta * (v - self.mean[i][c]);
            }
        }
        Ok(())
    }

    /// The statistics against `reference` (same size); at least two images must have
    /// been added.
    pub fn finish<P: HdrPixel>(&self, reference: &[P]) -> Result<SeedSpread, MetricsError> {
        self.check(reference.len(), reference.len())?;
        if self.images < 2 {
            return Err(MetricsError::TooFewImages {
                images: self.images,
            });
        }
        let s = self.images as f64;
        let (mut variance, mut bias2, mut compared) = (0.0f64, 0.0f64, 0usize);
        for (i, r) in reference.iter().enumerate() {
            let r = r.rgb();
            if !self.finite[i] || !r.iter().all(|c| c.is_finite()) {
                continue;
            }
            compared += 1;
            for (c, &rc) in r.iter().enumerate() {
                let w = rel_mse_weight(rc);
                let sample_variance = self.deviations[i][c] / (s - 1.0);
                let error = self.mean[i][c] - rc as f64;
                variance += sample_variance * w;
                bias2 += (error * error - sample_variance / s) * w;
            }
        }
        let channels = (3 * compared).max(1) as f64;
        Ok(SeedSpread {
            seeds: self.images,
            compared_pixels: compared,
            rel_variance: variance / channels,
            rel_bias2: bias2 / channels,
        })
    }

    fn check(&self, reference: usize, test: usize) -> Result<(), MetricsError> {
        let expected = self.width as usize * self.height as usize;
        if reference != expected || test != expected {
            return Err(MetricsError::SizeMismatch {
                width: self.width,
                height: self.height,
                expected,
                reference,
                test,
            });
        }
        Ok(())
    }
}

/// [`SeedSpreadAccumulator`] over `images` at once.
pub fn seed_spread<P: HdrPixel>(
    reference: &[P],
    images: &[Vec<P>],
    width: u32,
    height: u32,
) -> Result<SeedSpread, MetricsError> {
    let mut acc = SeedSpreadAccumulator::new(width, height);
    for image in images {
        acc.add(image)?;
    }
    acc.finish(reference)
}
