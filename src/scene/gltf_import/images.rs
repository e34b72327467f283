//! Images and textures: decoded once per image (and once per colour space), a warning and a
//! neutral texture when missing or undecodable.

use super::Importer;
use crate::scene::error::SceneError;
use crate::scene::types::TextureImage;
use std::sync::Arc;

impl Importer {
    /// A texture, or `None` with a warning when the image is missing or undecodable (the
    /// material's factor then applies alone: a neutral texture).
    pub(super) fn texture(
        &mut self,
        image: usize,
        srgb: bool,
        slot: &str,
    ) -> Option<Arc<TextureImage>> {
        if let Some(t) = self.textures.get(&(image, srgb)) {
            return t.clone();
        }
        let rgba = self.decode_image(image, slot);
        let t = rgba.map(|img| {
            Arc::new(TextureImage {
                name: self.image_name(image),
                width: img.width(),
                height: img.height(),
                rgba8: img.as_raw().clone(),
                srgb,
            })
        });
        self.textures.insert((image, srgb), t.clone());
        t
    }

    fn image_name(&self, image: usize) -> String {
        self.image_names
            .get(image)
            .cloned()
            .unwrap_or_else(|| format!("image{image}"))
    }

    fn decode_image(&mut self, index: usize, slot: &str) -> Option<Arc<image::RgbaImage>> {
        if let Some(i) = self.images.get(&index) {
            return i.clone();
        }
        let result = self.try_decode_image(index);
        let out = match result {
            Ok(img) => Some(Arc::new(img)),
            Err(msg) => {
                self.warn(format!(
                    "{slot}: image {index}: {msg}; using a neutral texture"
                ));
                None
            }
        };
        self.images.insert(index, out.clone());
        out
    }

    fn try_decode_image(&self, index: usize) -> Result<image::RgbaImage, String> {
        let src = self.image_sources.get(index).ok_or("no such image")?;
        let bytes: Vec<u8> = match src {
            ImageSource::Missing => return Err("the image has neither uri nor bufferView".into()),
            ImageSource::Uri(uri) => {
                self.read_uri(uri, &format!("image {index}"))
                    .map_err(|e| match e {
                        SceneError::Invalid { message, .. } => message,
                        e => e.to_string(),
                    })?
            }
            ImageSource::View {
                buffer,
                offset,
                length,
            } => {
                let buf = &self.buffers[*buffer];
                buf.get(*offset..offset.saturating_add(*length))
                    .ok_or("bufferView is out of bounds")?
                    .to_vec()
            }
        };
        let reader = image::ImageReader::new(std::io::Cursor::new(&bytes))
            .with_guessed_format()
            .map_err(|e| e.to_string())?;
        let (w, h) = reader
            .into_dimensions()
            .map_err(|e| format!("cannot decode: {e}"))?;
        if w as u64 * h as u64 > self.limits.max_image_pixels {
            return Err(format!(
                "{w}×{h} pixels exceeds the limit of {}",
                self.limits.max_image_pixels
            ));
        }
        let img = image::load_from_memory(&bytes).map_err(|e| format!("cannot decode: {e}"))?;
        Ok(img.to_rgba8())
    }
}

pub(super) enum ImageSource {
    Missing,
    Uri(String),
    View {
        buffer: usize,
        offset: usize,
        length: usize,
    },
}
