//! MSAA Forward+ (graphs/msaa.ron, graphs/transparent_msaa.ron): before the resolve,
//! every sample equals the brute-force MSAA render's (graphs/msaa_brute_force.ron,
//! graphs/transparent_msaa_brute_force.ron); the resolve is the mean of the samples, and
//! its edge pixels lie between their neighbours and nearer a 4×-supersampled render than
//! the single-sample image; a sample count the adapter lacks is refused, naming the pass
//! and the counts it has.
//!
//! Samples are read through `shaders/msaa/samples.wgsl` (the graphs' resolve pass swapped
//! for one that lays every sample side by side), so the comparison sees each sample.
//! Tolerance for culled against brute force: 2e-6 relative, as tests/culling_exact.rs (the
//! same non-zero terms summed in the same order; only multiply-add contraction differs).

mod common;
use common::msaa::*;
use common::*;
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{supported_sample_counts, SceneGpu};
use lightgraph::scene::{builtin, Scene};
use lightgraph::shader::ShaderLibrary;
use std::path::Path;

const W: u32 = MSAA_W;
const H: u32 = MSAA_H;
const TOL: f32 = 2e-6;

fn check_samples(scene: &Scene, culled: &str, brute: &str) {
    let mut r = renderer();
    let counts = offered(&r, &[4, 8]);
    assert!(
        counts.contains(&4),
        "the adapter lacks 4× MSAA for Rgba32Float"
    );
    for n in counts {
        let reference = render_text(
            &mut r,
            &samples_graph(&graph_file(brute), n, W, H),
            scene,
            W,
            H,
        );
        let test = render_text(
            &mut r,
            &samples_graph(&graph_file(culled), n, W, H),
            scene,
            W,
            H,
        );
        assert_eq!(reference.image.len(), (n * W * H) as usize);
        let (err, at) = max_rel_diff(&test.image, &reference.image);
        let at = at as u32;
        assert!(
            err <= TOL,
            "{culled} at {n}×: error {err:e} at pixel ({}, {}) sample {}",
            at / n % W,
            at / (n * W),
            at % n
        );
        // MSAA must be real: edge pixels hold samples of different surfaces.
        let edges = reference
            .image
            .chunks(n as usize)
            .filter(|s| s.iter().any(|x| x != &s[0]))
            .count();
        assert!(
            edges > 20,
            "{culled} at {n}×: only {edges} pixels with differing samples"
        );
        let lit = reference
            .image
            .iter()
            .filter(|p| p[0] + p[1] + p[2] > 0.0)
            .count();
        let lit_test = test
            .image
            .iter()
            .filter(|p| p[0] + p[1] + p[2] > 0.0)
            .count();
        eprintln!(
            "{} {culled} at {n}×: {lit} lit samples (culled {lit_test}), {edges} edge pixels",
            scene.name
        );
        assert!(lit > 20, "{culled} at {n}×: only {lit} lit samples");
    }
}

#[test]
fn every_sample_equals_brute_force_msaa() {
    check_samples(&random_scene(40, 4), "msaa.ron", "msaa_brute_force.ron");
}

#[test]
fn every_sample_equals_brute_force_msaa_on_sub_pixel_bars() {
    check_samples(&thin_bars_scene(), "msaa.ron", "msaa_brute_force.ron");
}

#[test]
fn every_sample_equals_brute_force_msaa_with_transparency() {
    let glass = builtin::by_name("glass").unwrap();
    check_samples(
        &glass,
        "transparent_msaa.ron",
        "transparent_msaa_brute_force.ron",
    );
}

/// After the resolve: each pixel is the mean of its samples; edge pixels lie between the
/// colours around them and are nearer a 4×-supersampled (2×2 grid) render than the
/// single-sample image is. Tolerances: 1e-6 for the mean (four adds and a divide) and for
/// "between" (the colours are flat, so a resolved edge pixel is a convex combination of
/// colours its 3×3 single-sample neighbourhood shows); MSAA's rotated sample pattern and
/// the 2×2 grid estimate coverage from different points, so they agree only on average:
/// the mean error over edge pixels must be under 0.6 of the single-sample image's.
#[test]
fn resolved_edges_lie_between_their_neighbours() {
    let scene = flat_scene();
    let mut r = renderer();
    let resolved = render_file(&mut r, "msaa.ron", &scene, W, H);
    let samples = render_text(
        &mut r,
        &samples_graph(&graph_file("msaa.ron"), 4, W, H),
        &scene,
        W,
        H,
    );
    let single = render_file(&mut r, "brute_force.ron", &scene, W, H);
    let fine = render_file(&mut r, "brute_force.ron", &scene, 2 * W, 2 * H);
    assert_eq!(resolved.image.len(), (W * H) as usize);
    assert_eq!(fine.image.len(), (4 * W * H) as usize);
    let at = |img: &[[f32; 4]], w: u32, x: u32, y: u32| img[(y * w + x) as usize];
    let (mut edges, mut err_msaa, mut err_single) = (0usize, 0.0f64, 0.0f64);
    for y in 0..H {
        for x in 0..W {
            let p = at(&resolved.image, W, x, y);
            let s: Vec<[f32; 4]> = (0..4)
                .map(|k| at(&samples.image, 4 * W, 4 * x + k, y))
                .collect();
            for c in 0..3 {
                let mean = s.iter().map(|v| v[c]).sum::<f32>() / 4.0;
                assert!(
                    (p[c] - mean).abs() <= 1e-6,
                    "({x}, {y}): resolve {} != mean {mean}",
                    p[c]
                );
            }
            let sub: Vec<[f32; 4]> = [(0, 0), (1, 0), (0, 1), (1, 1)]
                .iter()
                .map(|&(dx, dy)| at(&fine.image, 2 * W, 2 * x + dx, 2 * y + dy))
                .collect();
            if sub.iter().all(|v| v == &sub[0]) || x == 0 || y == 0 || x + 1 == W || y + 1 == H {
                continue;
            }
            edges += 1;
            for c in 0..3 {
                let hood = (0..9).map(|k| at(&single.image, W, x + k % 3 - 1, y + k / 3 - 1)[c]);
                let (lo, hi) = hood.fold((f32::MAX, f32::MIN), |(a, b), v| (a.min(v), b.max(v)));
                assert!(
                    p[c] >= lo - 1e-6 && p[c] <= hi + 1e-6,
                    "({x}, {y}) channel {c}: resolved {} outside its neighbours [{lo}, {hi}]",
                    p[c]
                );
                let ss = sub.iter().map(|v| v[c]).sum::<f32>() / 4.0;
                err_msaa += (p[c] - ss).abs() as f64;
                err_single += (at(&single.image, W, x, y)[c] - ss).abs() as f64;
            }
        }
    }
    assert!(edges > 100, "only {edges} edge pixels");
    println!(
        "{edges} edge pixels: mean error against 4× supersampling {:.4} (MSAA) vs {:.4} (1×)",
        err_msaa / (3 * edges) as f64,
        err_single / (3 * edges) as f64
    );
    assert!(
        err_msaa < 0.6 * err_single,
        "MSAA edges ({err_msaa:.3}) not nearer the supersampled render than 1× ({err_single:.3})"
    );
}

#[test]
fn unsupported_sample_count_names_the_pass_and_the_adapters_counts() {
    let mut r = renderer();
    let fmt = |f| supported_sample_counts(f, &r.ctx.adapter, &r.ctx.device);
    let depth = fmt(wgpu::TextureFormat::Depth32Float);
    let color = fmt(wgpu::TextureFormat::Rgba32Float);
    let Some(n) = [2, 8, 16]
        .into_iter()
        .find(|n| !depth.contains(n) || !color.contains(n))
    else {
        panic!("the adapter offers every sample count ({depth:?}, {color:?}): pick another test");
    };
    // The first pass to use an unsupported texture is named: the prepass for the depth.
    let (pass, list) = if !depth.contains(&n) {
        ("depth_prepass", &depth)
    } else {
        ("forward_shading", &color)
    };
    let text = graph_file("msaa.ron").replace("samples: 4", &format!("samples: {n}"));
    let checked = graph::check_text(Path::new("msaa.ron"), &text, &ShaderLibrary::builtin())
        .expect("any power of two up to 16 validates without a device");
    let scene = random_scene(8, 1);
    let size = FrameSize {
        width: 64,
        height: 36,
        lights: 8,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, &scene).unwrap();
    let e = match r.prepare(compiled, &scene, &gpu, size, false) {
        Ok(_) => panic!("{n}× prepared on an adapter without it"),
        Err(e) => e.to_string(),
    };
    let counts = list
        .iter()
        .map(u32::to_string)
        .collect::<Vec<_>>()
        .join(", ");
    for want in [
        format!("pass '{pass}'"),
        format!("samples: {n} is not supported"),
        format!("it supports {counts}"),
        "msaa.ron:".to_string(),
    ] {
        assert!(e.contains(&want), "{want:?} not in: {e}");
    }
}
