//! Linear HDR images on disk: 32-bit float RGBA OpenEXR (lossless, bit-exact round trip) and
//! tonemapped sRGB PNG (through [`Tonemap`], the same mapping FLIP sees).

use super::pixel::HdrPixel;
use super::tonemap::Tonemap;
use std::path::{Path, PathBuf};

/// An image-file error; every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ImageIoError {
    /// Encoding or decoding failed.
    #[error("{}: {source}", path.display())]
    Image {
        /// The file.
        path: PathBuf,
        /// The codec error.
        #[source]
        source: image::ImageError,
    },
    /// The pixel slice does not match `width * height`.
    #[error("{}: {len} pixels given for a {width}x{height} image", path.display())]
    SizeMismatch {
        /// The file.
        path: PathBuf,
        /// Pixels given.
        len: usize,
        /// Declared width.
        width: u32,
        /// Declared height.
        height: u32,
    },
    /// Creating the parent directory failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
}

/// A linear HDR RGBA image read back from disk.
#[derive(Debug, Clone, PartialEq)]
pub struct HdrImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major linear RGBA pixels, `width * height` of them.
    pub pixels: Vec<[f32; 4]>,
}

pub(crate) fn check_size(
    path: &Path,
    len: usize,
    width: u32,
    height: u32,
) -> Result<(), ImageIoError> {
    if len as u64 != width as u64 * height as u64 {
        return Err(ImageIoError::SizeMismatch {
            path: path.to_path_buf(),
            len,
            width,
            height,
        });
    }
    Ok(())
}

fn create_parent(path: &Path) -> Result<(), ImageIoError> {
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|source| ImageIoError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    }
    Ok(())
}

fn image_err(path: &Path) -> impl FnOnce(image::ImageError) -> ImageIoError + '_ {
    move |source| ImageIoError::Image {
        path: path.to_path_buf(),
        source,
    }
}

/// Write linear HDR pixels as a 32-bit float RGBA OpenEXR file (RGB input gets alpha 1).
/// Creates the parent directory. Values are stored exactly (no half floats, lossless).
pub fn write_exr<P: HdrPixel>(
    path: impl AsRef<Path>,
    pixels: &[P],
    width: u32,
    height: u32,
) -> Result<(), ImageIoError> {
    let path = path.as_ref();
    check_size(path, pixels.len(), width, height)?;
    create_parent(path)?;
    let raw: Vec<f32> = pixels.iter().flat_map(|p| p.rgba()).collect();
    let img = image::Rgba32FImage::from_raw(width, height, raw)
        .expect("buffer length checked against width * height");
    img.save_with_format(path, image::ImageFormat::OpenExr)
        .map_err(image_err(path))
}

/// Read an OpenEXR (or any HDR format the `image` crate decodes) as linear RGBA `f32`.
/// RGB files get alpha 1.
pub fn read_exr(path: impl AsRef<Path>) -> Result<HdrImage, ImageIoError> {
    let path = path.as_ref();
    let reader = image::ImageReader::open(path)
        .map_err(|source| ImageIoError::Io {
            path: path.to_path_buf(),
            source,
        })?
        .with_guessed_format()
        .map_err(|source| ImageIoError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    let img = reader.decode().map_err(image_err(path))?.into_rgba32f();
    let (width, height) = img.dimensions();
    let pixels = img
        .into_raw()
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    Ok(HdrImage {
        width,
        height,
        pixels,
    })
}

/// Tonemap linear HDR pixels with `tonemap` and write an 8-bit sRGB RGB PNG.
pub fn write_png_tonemapped<P: HdrPixel>(
    path: impl AsRef<Path>,
    pixels: &[P],
    width: u32,
    height: u32,
    tonemap: &Tonemap,
) -> Result<(), ImageIoError> {
    let path = path.as_ref();
    check_size(path, pixels.len(), width, height)?;
    write_png_rgb8(path, tonemap.image_to_srgb8(pixels), width, height)
}

/// Write tightly packed 8-bit RGB (already display-encoded) as a PNG. Creates the parent directory.
pub fn write_png_rgb8(
    path: impl AsRef<Path>,
    rgb8: Vec<u8>,
    width: u32,
    height: u32,
) -> Result<(), ImageIoError> {
    let path = path.as_ref();
    check_size(path, rgb8.len() / 3, width, height)?;
    create_parent(path)?;
    let img = image::RgbImage::from_raw(width, height, rgb8)
        .expect("buffer length checked against width * height");
    img.save_with_format(path, image::ImageFormat::Png)
        .map_err(image_err(path))
}
