//! Full mip chains for material textures, built on the CPU at upload so that minified
//! textures filter (trilinear) instead of aliasing, in Forward+ (`textureSample`) and in
//! visibility-buffer compute shading (`textureSampleGrad`) alike.
//!
//! Each level is a box filter of the one above: every texel averages exactly the area of
//! the level above that it covers. For even sizes that is the 2×2 box; an odd side (5 →
//! 2) gives each texel 2.5 source texels (weights 1, 1, ½), so no row or column is
//! dropped or counted twice and the mean is kept at every level. Level sizes halve
//! rounding down, as WebGPU expects. Filtering runs on f32 values carried from level to
//! level (quantised to 8 bits only for upload), in linear space: sRGB colour is decoded,
//! averaged and encoded again (averaging sRGB bytes would darken a black-and-white
//! checker to 128 instead of 188); alpha and non-sRGB data are averaged as stored.
//!
//! Normal maps are filtered as their raw values, not renormalised: the material code
//! normalises after decoding (`src/material/wgsl.rs`), the texture unit's own bilinear and
//! trilinear blends average raw values too, so the levels stay consistent with the
//! filtering inside and between them; and the shortened average keeps how much the
//! normals vary (what Toksvig-style specular antialiasing would read). The generator also
//! need not know which slot a texture fills.

/// A texture's levels, largest first, packed one after another as
/// `wgpu::util::TextureDataOrder::LayerMajor` expects for one layer.
#[derive(Debug, Clone, PartialEq)]
pub struct MipChain {
    pub levels: u32,
    pub rgba8: Vec<u8>,
}

/// The number of levels down to 1×1: ⌊log2(max side)⌋ + 1.
pub fn level_count(width: u32, height: u32) -> u32 {
    32 - width.max(height).max(1).leading_zeros()
}

/// Bytes of an RGBA8 texture with every level of its chain (about 4/3 of level 0).
pub fn chain_bytes(width: u32, height: u32) -> u64 {
    (0..level_count(width, height))
        .map(|l| 4 * (width >> l).max(1) as u64 * (height >> l).max(1) as u64)
        .sum()
}

/// The full chain of a `width`×`height` RGBA8 image (level 0 as given).
pub fn mip_chain(width: u32, height: u32, rgba8: &[u8], srgb: bool) -> Result<MipChain, String> {
    if width == 0 || height == 0 || rgba8.len() as u64 != width as u64 * height as u64 * 4 {
        return Err(format!(
            "{} bytes do not make {width}×{height} RGBA8 pixels",
            rgba8.len()
        ));
    }
    let levels = level_count(width, height);
    let mut out = Vec::with_capacity(chain_bytes(width, height) as usize);
    out.extend_from_slice(rgba8);
    let decode = decode_table(srgb);
    let mut level: Vec<f32> = rgba8
        .chunks_exact(4)
        .flat_map(|p| {
            [
                decode[p[0] as usize],
                decode[p[1] as usize],
                decode[p[2] as usize],
                p[3] as f32 / 255.0,
            ]
        })
        .collect();
    let (mut w, mut h) = (width, height);
    for _ in 1..levels {
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        level = downsample(&level, w, h, nw, nh);
        (w, h) = (nw, nh);
        out.extend(level.chunks_exact(4).flat_map(|p| {
            let c = |v: f32| encode(v, srgb);
            [c(p[0]), c(p[1]), c(p[2]), unorm8(p[3])]
        }));
    }
    Ok(MipChain { levels, rgba8: out })
}

/// Byte → the value filtered: linear light for sRGB, else the unorm value.
fn decode_table(srgb: bool) -> [f32; 256] {
    std::array::from_fn(|i| {
        let v = i as f32 / 255.0;
        if !srgb {
            v
        } else if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    })
}

fn encode(v: f32, srgb: bool) -> u8 {
    let v = v.clamp(0.0, 1.0);
    if !srgb {
        unorm8(v)
    } else if v <= 0.0031308 {
        unorm8(v * 12.92)
    } else {
        unorm8(1.055 * v.powf(1.0 / 2.4) - 0.055)
    }
}

fn unorm8(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// Each target index's source texels and their weights: the overlap of the target texel's
/// footprint `[i·s, (i+1)·s)`, s = n/m, with each source texel, normalised.
fn box_weights(n: u32, m: u32) -> Vec<Vec<(usize, f32)>> {
    let s = n as f64 / m as f64;
    (0..m)
        .map(|i| {
            let (lo, hi) = (i as f64 * s, (i + 1) as f64 * s);
            (lo.floor() as u32..(hi.ceil() as u32).min(n))
                .filter_map(|j| {
                    let w = (hi.min(j as f64 + 1.0) - lo.max(j as f64)) / s;
                    (w > 1e-9).then_some((j as usize, w as f32))
                })
                .collect()
        })
        .collect()
}

/// A w×h RGBA f32 image box-filtered to nw×nh, separably (rows, then columns).
fn downsample(src: &[f32], w: u32, h: u32, nw: u32, nh: u32) -> Vec<f32> {
    let (wx, wy) = (box_weights(w, nw), box_weights(h, nh));
    let (w, nw) = (w as usize, nw as usize);
    let mut rows = vec![0.0f32; nw * h as usize * 4];
    for y in 0..h as usize {
        for (x, taps) in wx.iter().enumerate() {
            for &(j, k) in taps {
                for c in 0..4 {
                    rows[(y * nw + x) * 4 + c] += k * src[(y * w + j) * 4 + c];
                }
            }
        }
    }
    let mut out = vec![0.0f32; nw * nh as usize * 4];
    for (y, taps) in wy.iter().enumerate() {
        for &(j, k) in taps {
            for x in 0..nw {
                for c in 0..4 {
                    out[(y * nw + x) * 4 + c] += k * rows[(j * nw + x) * 4 + c];
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gray(v: &[u8]) -> Vec<u8> {
        v.iter().flat_map(|&g| [g, g, g, 255]).collect()
    }

    fn level(chain: &MipChain, w: u32, h: u32, l: u32) -> Vec<u8> {
        let start: u64 = (0..l)
            .map(|i| 4 * (w >> i).max(1) as u64 * (h >> i).max(1) as u64)
            .sum();
        let len = 4 * (w >> l).max(1) as usize * (h >> l).max(1) as usize;
        chain.rgba8[start as usize..start as usize + len]
            .chunks_exact(4)
            .map(|p| p[0])
            .collect()
    }

    #[test]
    fn four_by_four_halves_to_two_by_two_then_one() {
        #[rustfmt::skip]
        let px = gray(&[
            0, 20, 100, 100,
            40, 60, 100, 100,
            200, 200, 10, 30,
            200, 200, 50, 70,
        ]);
        let chain = mip_chain(4, 4, &px, false).unwrap();
        assert_eq!(chain.levels, 3);
        assert_eq!(chain.rgba8.len() as u64, chain_bytes(4, 4));
        assert_eq!(chain_bytes(4, 4), 4 * (16 + 4 + 1));
        assert_eq!(
            level(&chain, 4, 4, 0),
            px.chunks(4).map(|p| p[0]).collect::<Vec<_>>()
        );
        assert_eq!(level(&chain, 4, 4, 1), vec![30, 100, 200, 40]);
        // From the f32 level above: (30 + 100 + 200 + 40) / 4 = 92.5, rounded.
        assert_eq!(level(&chain, 4, 4, 2), vec![93]);
        // Alpha stays opaque.
        assert!(chain.rgba8.chunks(4).all(|p| p[3] == 255));
    }

    #[test]
    fn srgb_averages_in_linear_light() {
        // Black and white: linear mean 0.5 is sRGB 188, not the byte mean 128 (or 127.5).
        let px = gray(&[0, 255, 255, 0]);
        let chain = mip_chain(2, 2, &px, true).unwrap();
        assert_eq!(level(&chain, 2, 2, 1), vec![188]);
        let raw = mip_chain(2, 2, &px, false).unwrap();
        assert_eq!(level(&raw, 2, 2, 1), vec![128]);
        // Alpha is linear even in an sRGB texture: 0 and 255 average to 128.
        let mut a = px.clone();
        a[3] = 0;
        a[15] = 0;
        let chain = mip_chain(2, 2, &a, true).unwrap();
        assert_eq!(chain.rgba8[16 + 3], 128);
    }

    #[test]
    fn odd_sizes_weigh_the_footprint_and_keep_the_mean() {
        // 3×1 → 1×1: every texel counts once.
        let chain = mip_chain(3, 1, &gray(&[30, 60, 90]), false).unwrap();
        assert_eq!(chain.levels, 2);
        assert_eq!(level(&chain, 3, 1, 1), vec![60]);
        // 5×1 → 2×1: weights (1, 1, ½) and (½, 1, 1) over 2.5 texels.
        let chain = mip_chain(5, 1, &gray(&[0, 50, 100, 150, 250]), false).unwrap();
        assert_eq!(chain.levels, 3);
        assert_eq!(level(&chain, 5, 1, 1), vec![40, 180]);
        assert_eq!(level(&chain, 5, 1, 2), vec![110]);
        // 1×3: a one-wide side stays one wide while the other halves.
        let chain = mip_chain(1, 3, &gray(&[0, 90, 180]), false).unwrap();
        assert_eq!(level(&chain, 1, 3, 1), vec![90]);
        // 7×5 of noise: the mean survives every level (to 8-bit rounding).
        let px: Vec<u8> = (0..35u32).map(|i| (i * 97 % 256) as u8).collect();
        let mean = px.iter().map(|&v| v as f32).sum::<f32>() / 35.0;
        let chain = mip_chain(7, 5, &gray(&px), false).unwrap();
        assert_eq!(chain.levels, 3);
        assert_eq!(chain.rgba8.len() as u64, chain_bytes(7, 5));
        for l in 1..3 {
            let v = level(&chain, 7, 5, l);
            let m = v.iter().map(|&x| x as f32).sum::<f32>() / v.len() as f32;
            assert!((m - mean).abs() < 1.0, "level {l}: mean {m} vs {mean}");
        }
    }

    #[test]
    fn sizes_and_bad_input() {
        assert_eq!(level_count(1, 1), 1);
        assert_eq!(level_count(1024, 1), 11);
        assert_eq!(level_count(1000, 3), 10);
        // Mips add about a third.
        let b = chain_bytes(1024, 1024) as f64 / (4.0 * 1024.0 * 1024.0);
        assert!((b - 4.0 / 3.0).abs() < 1e-3, "{b}");
        assert!(mip_chain(2, 2, &[0; 15], false).is_err());
        assert!(mip_chain(0, 2, &[], false).is_err());
    }
}
