//! Pixel formats accepted by the bench functions: linear HDR RGB or RGBA in `f32`.

/// A linear HDR pixel: `[f32; 3]` (RGB) or `[f32; 4]` (RGBA, alpha is ignored by the metrics).
pub trait HdrPixel: Copy {
    /// Linear RGB, alpha dropped.
    fn rgb(self) -> [f32; 3];
    /// Linear RGBA; RGB pixels get alpha 1.
    fn rgba(self) -> [f32; 4];
}

impl HdrPixel for [f32; 3] {
    fn rgb(self) -> [f32; 3] {
        self
    }
    fn rgba(self) -> [f32; 4] {
        [self[0], self[1], self[2], 1.0]
    }
}

impl HdrPixel for [f32; 4] {
    fn rgb(self) -> [f32; 3] {
        [self[0], self[1], self[2]]
    }
    fn rgba(self) -> [f32; 4] {
        self
    }
}

/// Rec. 709 / sRGB relative luminance of a linear RGB value.
pub fn luminance(rgb: [f32; 3]) -> f32 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}
