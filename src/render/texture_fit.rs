//! Textures larger than the device allows (a valid 9000×1 PNG, say) are scaled down to
//! fit, with a warning, instead of failing in wgpu's texture creation.

use crate::scene::TextureImage;

/// `image` scaled down (aspect kept, each side at least 1) so that no side exceeds
/// `max`; `None` if it already fits. The warning names `owner` (the material file, or
/// `gltf:NAME` for a glTF material) and the texture. Filters in the stored encoding (sRGB
/// bytes as they are): a fallback, not a resampler for colour-critical work.
pub fn fit_to_device(
    image: &TextureImage,
    max: u32,
    owner: &std::path::Path,
) -> Result<Option<TextureImage>, String> {
    let (w, h) = (image.width, image.height);
    if w == 0 || h == 0 || image.rgba8.len() as u64 != w as u64 * h as u64 * 4 {
        return Err(format!(
            "texture {}: {} bytes do not make {w}×{h} RGBA8 pixels",
            image.name,
            image.rgba8.len()
        ));
    }
    if w <= max && h <= max {
        return Ok(None);
    }
    let scale = max as f64 / w.max(h) as f64;
    let side = |s: u32| ((s as f64 * scale).floor() as u32).clamp(1, max);
    let (nw, nh) = (side(w), side(h));
    let src = image::RgbaImage::from_raw(w, h, image.rgba8.clone())
        .ok_or_else(|| format!("texture {}: not {w}×{h} RGBA8", image.name))?;
    let small = image::imageops::resize(&src, nw, nh, image::imageops::FilterType::Triangle);
    log::warn!(
        "material {}: texture {} is {w}×{h}, over the device's limit of {max} per side: scaled down to {nw}×{nh}",
        owner.display(),
        image.name
    );
    Ok(Some(TextureImage {
        name: image.name.clone(),
        width: nw,
        height: nh,
        rgba8: small.into_raw(),
        srgb: image.srgb,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_only_what_is_too_wide() {
        let owner = std::path::Path::new("m.ron");
        let img = |w: u32, h: u32| TextureImage {
            name: "t".into(),
            width: w,
            height: h,
            rgba8: vec![200; (w * h * 4) as usize],
            srgb: true,
        };
        assert!(fit_to_device(&img(64, 64), 64, owner).unwrap().is_none());
        let small = fit_to_device(&img(9000, 1), 8192, owner).unwrap().unwrap();
        assert_eq!((small.width, small.height), (8192, 1));
        assert_eq!(small.rgba8.len(), 8192 * 4);
        let tall = fit_to_device(&img(3, 300), 100, owner).unwrap().unwrap();
        assert_eq!((tall.width, tall.height), (1, 100));
        let mut bad = img(4, 4);
        bad.rgba8.pop();
        assert!(fit_to_device(&bad, 100, owner).is_err());
    }
}
