//! The one tonemapper of the project: exposure, then a tone curve, then the sRGB transfer
//! function. FLIP (which works on LDR sRGB8), PNG output and the heat maps all go through it, so a
//! PNG written by `render --out x.png` is exactly what FLIP compared.

use super::pixel::HdrPixel;
use serde::{Deserialize, Serialize};

/// Tone curve applied per channel after exposure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum ToneCurve {
    /// `x / (1 + x)`: never clips, so large HDR differences still show in LDR (the default).
    #[default]
    Reinhard,
    /// Krzysztof Narkowicz's fit of the ACES filmic curve, clamped to `[0, 1]`.
    AcesFitted,
    /// Plain clamp to `[0, 1]` (for images that are already display-referred).
    Clamp,
}

/// Exposure (in stops) plus a [`ToneCurve`].
///
/// Non-finite input is mapped deterministically: NaN and `-inf` become 0 (black), `+inf` becomes
/// 1 (white). Negative values are clamped to 0 before the curve.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Tonemap {
    /// Exposure in stops: the linear input is multiplied by `2^exposure_ev`.
    pub exposure_ev: f32,
    /// The tone curve.
    pub(crate) curve: ToneCurve,
}

impl Tonemap {
    /// A tonemapper with the given exposure (stops) and curve.
    pub fn new(exposure_ev: f32, curve: ToneCurve) -> Self {
        Self { exposure_ev, curve }
    }

    /// Tonemap one linear channel to display-linear `[0, 1]` (before the sRGB transfer function).
    pub(crate) fn map_channel(&self, x: f32) -> f32 {
        if x.is_nan() {
            return 0.0;
        }
        if x.is_infinite() {
            return if x > 0.0 { 1.0 } else { 0.0 };
        }
        let x = (x * self.exposure_ev.exp2()).max(0.0);
        let y = match self.curve {
            ToneCurve::Reinhard => {
                if x.is_finite() {
                    x / (1.0 + x)
                } else {
                    1.0
                }
            }
            ToneCurve::AcesFitted => {
                let (a, b, c, d, e) = (2.51, 0.03, 2.43, 0.59, 0.14);
                (x * (a * x + b)) / (x * (c * x + d) + e)
            }
            ToneCurve::Clamp => x,
        };
        if y.is_finite() {
            y.clamp(0.0, 1.0)
        } else {
            1.0
        }
    }

    /// Tonemap a linear RGB value to display-linear RGB in `[0, 1]`.
    pub(crate) fn map_rgb(&self, rgb: [f32; 3]) -> [f32; 3] {
        rgb.map(|c| self.map_channel(c))
    }

    /// Tonemap a linear RGB value to 8-bit sRGB.
    pub fn to_srgb8(&self, rgb: [f32; 3]) -> [u8; 3] {
        self.map_rgb(rgb).map(|c| quantize8(linear_to_srgb(c)))
    }

    /// Tonemap a whole image to tightly packed 8-bit sRGB (`3 * pixels.len()` bytes).
    pub fn image_to_srgb8<P: HdrPixel>(&self, pixels: &[P]) -> Vec<u8> {
        let mut out = Vec::with_capacity(pixels.len() * 3);
        for p in pixels {
            out.extend_from_slice(&self.to_srgb8(p.rgb()));
        }
        out
    }
}

/// The sRGB transfer function (linear `[0, 1]` to encoded `[0, 1]`).
pub fn linear_to_srgb(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Inverse of [`linear_to_srgb`].
pub fn srgb_to_linear(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.040_45 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// Round a `[0, 1]` value to 8 bits.
pub(crate) fn quantize8(x: f32) -> u8 {
    (x.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reinhard_is_monotone_and_bounded() {
        let t = Tonemap::default();
        assert_eq!(t.map_channel(0.0), 0.0);
        assert!((t.map_channel(1.0) - 0.5).abs() < 1e-6);
        let mut prev = 0.0;
        for i in 1..1000 {
            let y = t.map_channel(i as f32 * 0.37);
            assert!(y > prev && y < 1.0);
            prev = y;
        }
    }

    #[test]
    fn non_finite_is_deterministic() {
        for curve in [ToneCurve::Reinhard, ToneCurve::AcesFitted, ToneCurve::Clamp] {
            let t = Tonemap::new(0.0, curve);
            assert_eq!(t.map_channel(f32::NAN), 0.0);
            assert_eq!(t.map_channel(f32::INFINITY), 1.0);
            assert_eq!(t.map_channel(f32::NEG_INFINITY), 0.0);
            assert_eq!(t.map_channel(f32::MAX), 1.0);
        }
    }

    #[test]
    fn exposure_doubles() {
        let t = Tonemap::new(1.0, ToneCurve::Clamp);
        assert_eq!(t.map_channel(0.25), 0.5);
    }

    #[test]
    fn srgb_round_trip() {
        for i in 0..=100 {
            let x = i as f32 / 100.0;
            assert!((srgb_to_linear(linear_to_srgb(x)) - x).abs() < 1e-5);
        }
        assert_eq!(quantize8(linear_to_srgb(1.0)), 255);
        assert_eq!(quantize8(linear_to_srgb(0.0)), 0);
    }
}
