//! Mip chains of material textures: the CPU generator's levels (known 4×4 → 2×2 → 1×1
//! values, sRGB averaged in linear light, odd sizes), and on lavapipe a checkerboard plane
//! receding to the horizon through Forward+ (`textureSample`, the rasterizer's
//! derivatives) and the visibility buffer (`textureSampleGrad`, derivatives from the
//! barycentrics): the two agree, and far pixels are the checker's mean (minification
//! filters instead of aliasing).

mod common;
use common::*;
use glam::{Vec2, Vec3};
use lightgraph::bench::metrics::{compare, CompareOptions};
use lightgraph::render::texture_mips::{chain_bytes, level_count, mip_chain, MipChain};
use lightgraph::scene::{Camera, Light, Mesh, Scene, SurfaceMaterial, TextureImage};
use std::sync::Arc;

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

const W: u32 = 256;
const H: u32 = 160;
const EYE_HEIGHT: f32 = 1.5;
const FOV_Y: f32 = std::f32::consts::FRAC_PI_3;
/// Checker cells 12.5 cm wide: 8×8 cells of 8×8 texels in a texture repeated every metre.
const METRES_PER_UV: f32 = 1.0;

/// A black-and-white sRGB checker, `cells` a side (linear mean exactly 0.5); or white.
fn texture(size: u32, cells: u32, white: bool) -> TextureImage {
    let mut rgba8 = Vec::with_capacity((size * size * 4) as usize);
    for y in 0..size {
        for x in 0..size {
            let odd = (x * cells / size + y * cells / size) % 2 == 1;
            let v = if white || odd { 255 } else { 0 };
            rgba8.extend([v, v, v, 255]);
        }
    }
    TextureImage {
        name: if white { "white" } else { "checker" }.into(),
        width: size,
        height: size,
        rgba8,
        srgb: true,
    }
}

/// A 400 m × 400 m ground plane receding from the camera to the horizon (the camera looks
/// level, so the horizon is the middle row), lit only by ambient light so its radiance is
/// albedo/π times a constant everywhere and the texture alone varies it.
fn plane_scene(tex: TextureImage) -> Scene {
    let mut s = random_scene(0, 1);
    s.name = tex.name.clone();
    s.materials = vec![SurfaceMaterial {
        name: "ground".into(),
        base_color_texture: Some(Arc::new(tex)),
        ..Default::default()
    }];
    let mut m = Mesh {
        name: "ground".into(),
        material: 0,
        ..Default::default()
    };
    for (x, z) in [
        (-200.0, 2.0),
        (200.0, 2.0),
        (200.0, -398.0),
        (-200.0, -398.0),
    ] {
        m.positions.push(Vec3::new(x, 0.0, z));
        m.normals.push(Vec3::Y);
        m.uvs.push(Vec2::new(x, z) / METRES_PER_UV);
        m.tangents.push(Vec3::X.extend(1.0));
    }
    m.indices.extend([0, 1, 2, 0, 2, 3]);
    s.meshes = vec![m];
    // One light far out of reach: the light lists are never empty, and it lights nothing.
    s.lights = vec![Light::point(
        Vec3::new(0.0, 50.0, 5000.0),
        1.0,
        Vec3::ONE,
        1.0,
    )];
    s.ambient = Vec3::ONE;
    s.camera = Camera {
        eye: Vec3::new(0.0, EYE_HEIGHT, 0.0),
        target: Vec3::new(0.0, EYE_HEIGHT, -10.0),
        up: Vec3::Y,
        fov_y: FOV_Y,
        near: 0.1,
        far: 1000.0,
    };
    s
}

/// The ground distance seen at the centre of row `y` (None above the horizon).
fn ground_distance(y: u32) -> Option<f32> {
    let below = ((y as f32 + 0.5) / H as f32 * 2.0 - 1.0) * (FOV_Y / 2.0).tan();
    (below > 0.0).then(|| EYE_HEIGHT / below)
}

/// Rows whose ground lies between 12 m and 300 m: there a pixel spans over 0.69 m of
/// ground along the view (h·α/θ² with α = tan(fov/2)/(H/2) the pixel's angle and θ the
/// row's below the horizon: over 44 texels, mip level 5.4 and beyond, past level 4 where
/// each texel already averages 2×2 cells), so a filtered texture is its mean; without
/// mips each pixel picks one cell, black or white.
fn far_rows() -> Vec<u32> {
    (0..H)
        .filter(|&y| ground_distance(y).is_some_and(|d| (12.0..300.0).contains(&d)))
        .collect()
}

/// How far the checker's far pixels stray from half the white plane's (its linear
/// mean): the worst pixel's |checker/white − 0.5|.
fn far_deviation(checker: &[[f32; 4]], white: &[[f32; 4]]) -> f32 {
    let mut worst = 0.0f32;
    for y in far_rows() {
        for x in 0..W {
            let i = (y * W + x) as usize;
            for c in 0..3 {
                worst = worst.max((checker[i][c] / white[i][c] - 0.5).abs());
            }
        }
    }
    worst
}

/// The worst channel error relative to max(|reference|, 1e-3 of the frame's peak), and
/// the pixel's index.
fn worst_rel(out: &[[f32; 4]], reference: &[[f32; 4]]) -> (f32, usize) {
    let peak = reference
        .iter()
        .flat_map(|p| p[..3].to_vec())
        .fold(0.0f32, f32::max);
    out.iter()
        .zip(reference)
        .map(|(a, b)| {
            (0..3)
                .map(|c| (a[c] - b[c]).abs() / b[c].abs().max(1e-3 * peak))
                .fold(
                    0.0f32,
                    |w, d| if d.is_nan() { f32::INFINITY } else { w.max(d) },
                )
        })
        .enumerate()
        .fold((0.0, 0), |w, (i, d)| if d > w.0 { (d, i) } else { w })
}

#[test]
fn checker_to_the_horizon_filters_the_same_in_forward_plus_and_the_visibility_buffer() {
    assert!(far_rows().len() >= 8, "far rows: {:?}", far_rows());
    let mut r = renderer();
    let checker = plane_scene(texture(64, 8, false));
    let white = plane_scene(texture(64, 8, true));
    let fwd = render_file(&mut r, "forward_plus.ron", &checker, W, H);
    let vis = render_file(&mut r, "visibility_buffer.ron", &checker, W, H);
    let fwd_white = render_file(&mut r, "forward_plus.ron", &white, W, H);
    let vis_white = render_file(&mut r, "visibility_buffer.ron", &white, W, H);
    let lit = fwd.image.iter().filter(|p| p[1] > 0.0).count();
    assert!(lit > (W * H / 3) as usize, "only {lit} ground pixels");

    let m = compare(&fwd.image, &vis.image, W, H, &CompareOptions::default()).unwrap();
    let flip = m.flip_mean.unwrap();
    let (worst, at) = worst_rel(&vis.image, &fwd.image);
    let (x, y) = (at as u32 % W, at as u32 / W);
    let (far_fwd, far_vis) = (
        far_deviation(&fwd.image, &fwd_white.image),
        far_deviation(&vis.image, &vis_white.image),
    );
    println!(
        "visibility vs Forward+: FLIP mean {flip:.3e}, worst rel {worst:.3e} at ({x}, {y}), {:.1} m, RMSE {:.3e}, bad pixels {}; \
         far |checker/white - 0.5|: Forward+ {far_fwd:.3e}, visibility {far_vis:.3e} ({} rows)",
        ground_distance(y).unwrap_or(f32::INFINITY),
        m.rmse,
        m.bad_pixels,
        far_rows().len()
    );
    let mut failures = Vec::new();
    if far_fwd > FAR_BOUND || far_vis > FAR_BOUND {
        failures.push(format!(
            "far pixels are not the checker's mean: Forward+ {far_fwd}, visibility {far_vis} (bound {FAR_BOUND})"
        ));
    }
    if flip > PLANE_FLIP_BOUND || worst > PLANE_WORST || m.bad_pixels > 0 {
        failures.push(format!(
            "visibility vs Forward+: FLIP mean {flip} (bound {PLANE_FLIP_BOUND}), worst {worst} (bound {PLANE_WORST}): {m}"
        ));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Far pixels' bound on |checker/white − 0.5|. Measured on lavapipe at 256×160
/// (2026-12-02): 1.3e-2 in both paths (the 8-bit sRGB texel and llvmpipe's 8-bit filter
/// weights); with one mip level (the upload mutated to `mip_level_count: 1`) 0.5 in both:
/// every far pixel is a black or white cell.
const FAR_BOUND: f32 = 0.05;
/// Visibility buffer against Forward+. Measured on lavapipe at 256×160 (2026-12-02): FLIP
/// mean 1.0e-4, worst relative 8.7e-3 (at 2.9 m, llvmpipe's 8-bit sub-texel weights as in
/// tests/visibility_buffer.rs), no pixel over 1e-3. With the visibility shader's
/// gradients zeroed (level 0 everywhere): FLIP mean 6.5e-2, worst 0.97, 18063 bad pixels;
/// with per-pixel forward differences instead of the quad's coarse ones: FLIP mean
/// 2.5e-3, worst 0.37 (a pixel's level off by up to a one-pixel shift of the
/// derivative), 3836 bad pixels. Bounds a few times the measured, far below either.
const PLANE_FLIP_BOUND: f64 = 5e-4;
const PLANE_WORST: f32 = 3e-2;
