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
    /// Mip levels in the chain, level 0 included.
    pub levels: u32,
    /// RGBA8 texels of every level, largest first.
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

// Tested in tests/texture_mips.rs (known levels, sRGB, odd sizes) with the GPU checks.
