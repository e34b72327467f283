//! Tiled deferred with MSAA (graphs/tiled_deferred_msaa.ron, _8x): a multisampled
//! G-buffer and deferred shading that shades every distinct sample and stores the mean.
//! Its image must equal the brute-force MSAA forward render after that render's resolve
//! (graphs/msaa_brute_force.ron, msaa_8x_brute_force.ron), at every count of 4 and 8 the
//! adapter offers (lavapipe: 4), on the MSAA tests' scenes with edges: random boxes,
//! sub-pixel bars (culling from every sample) and flat emissive boxes of three materials
//! (pixels whose samples hold several materials). Each comparison also checks that the
//! scene has edge pixels whose mean is far from their first sample, so a deferred pass
//! that shaded sample 0 alone (or one sample per material) could not pass.
//!
//! Tolerance: 2e-6 of the frame's peak (`max_rel_diff`), the bound of tests/msaa.rs and
//! tests/culling_exact.rs for one light loop in two pipelines (the same non-zero terms
//! in the same order; only the compiler's multiply-add contraction differs, in a fragment
//! shader here and a compute shader there). The mean adds the same per-sample colours in
//! sample order as the resolve, except at pixels whose samples hold several materials:
//! there the sum is regrouped by material (each material's dispatch adds its samples to
//! the partial sum of the ones before), at most n - 1 = 7 roundings of 2^-24 of a sum no
//! larger than the peak, 4e-7 at 8×: inside the bound.

mod common;
use common::msaa::*;
use common::*;
use lightgraph::scene::Scene;

const W: u32 = MSAA_W;
const H: u32 = MSAA_H;
const TOL: f32 = 2e-6;

/// The deferred MSAA graph and its brute-force reference at `n` samples (4 or 8).
fn graphs_at(n: u32) -> (String, String) {
    match n {
        4 => (
            graph_file("tiled_deferred_msaa.ron"),
            graph_file("msaa_brute_force.ron"),
        ),
        8 => (
            graph_file("tiled_deferred_msaa_8x.ron"),
            graph_file("msaa_8x_brute_force.ron"),
        ),
        _ => unreachable!("{n} samples"),
    }
}

/// The deferred MSAA image against brute-force MSAA after its resolve, at every count of
/// 4 and 8 the adapter offers; the scene must have pixels where shading sample 0 alone
/// would be caught.
fn check_resolved(scene: &Scene) {
    let mut r = renderer();
    let counts = offered(&r, &[4, 8]);
    assert!(
        counts.contains(&4),
        "the adapter lacks 4× MSAA for Rgba32Float"
    );
    for n in counts {
        let (deferred, brute) = graphs_at(n);
        let want = render_text(&mut r, &brute, scene, W, H);
        let samples = render_text(&mut r, &samples_graph(&brute, n, W, H), scene, W, H);
        let got = render_text(&mut r, &deferred, scene, W, H);
        assert_eq!(got.image.len(), (W * H) as usize);
        let (err, at) = max_rel_diff(&got.image, &want.image);
        assert!(
            err <= TOL,
            "{} at {n}×: deferred MSAA differs from brute force by {err:e} at ({}, {}): {:?} vs {:?}",
            scene.name,
            at as u32 % W,
            at as u32 / W,
            got.image[at],
            want.image[at]
        );
        // Pixels where the mean is far (1e-3 of the peak, 500× the tolerance) from the
        // first sample: shading sample 0 alone fails at every one of them.
        let peak = want
            .image
            .iter()
            .flat_map(|p| p[..3].iter().copied())
            .fold(1e-6f32, f32::max);
        let far_from_sample_0 = (0..(W * H) as usize)
            .filter(|&i| {
                let first = samples.image[i * n as usize];
                (0..3).any(|c| (want.image[i][c] - first[c]).abs() > 1e-3 * peak)
            })
            .count();
        eprintln!(
            "{} at {n}×: max error {err:e}, {far_from_sample_0} pixels whose mean is far from sample 0",
            scene.name
        );
        assert!(
            far_from_sample_0 > 20,
            "{} at {n}×: only {far_from_sample_0} edge pixels: the scene cannot tell sample 0 from the mean",
            scene.name
        );
    }
}

#[test]
fn deferred_msaa_equals_brute_force_msaa_on_random_boxes() {
    check_resolved(&random_scene(40, 4));
}

#[test]
fn deferred_msaa_equals_brute_force_msaa_on_sub_pixel_bars() {
    check_resolved(&thin_bars_scene());
}

/// Three emissive materials meeting at edges: pixels whose samples hold two or three
/// materials, summed across the materials' dispatches.
#[test]
fn deferred_msaa_equals_brute_force_msaa_across_materials() {
    check_resolved(&flat_scene());
}

/// Edge pixels are the mean of every sample: on the flat scene each edge pixel of the
/// deferred image lies at the mean of the brute-force samples, which differs from each
/// of its distinct samples (so neither sample 0 alone nor any one surface passes), and
/// the samples of many of them belong to different materials.
#[test]
fn edge_pixels_are_the_mean_of_every_sample() {
    let scene = flat_scene();
    let mut r = renderer();
    let n = 4;
    let samples = render_text(
        &mut r,
        &samples_graph(&graph_file("msaa_brute_force.ron"), n, W, H),
        &scene,
        W,
        H,
    );
    let got = render_file(&mut r, "tiled_deferred_msaa.ron", &scene, W, H);
    let (mut edges, mut mixed) = (0, 0);
    for i in 0..(W * H) as usize {
        let s = &samples.image[i * n as usize..(i + 1) * n as usize];
        if s.iter().all(|v| v == &s[0]) {
            continue;
        }
        edges += 1;
        // The flat materials' colours differ: distinct colours are distinct materials.
        let lit: Vec<&[f32; 4]> = s.iter().filter(|v| v[3] > 0.0).collect();
        if lit.iter().any(|v| *v != lit[0]) {
            mixed += 1;
        }
        for c in 0..4 {
            let mean = s.iter().map(|v| v[c]).sum::<f32>() / n as f32;
            assert!(
                (got.image[i][c] - mean).abs() <= 1e-6,
                "pixel ({}, {}) channel {c}: {} is not the mean {mean} of {s:?}",
                i as u32 % W,
                i as u32 / W,
                got.image[i][c]
            );
        }
    }
    eprintln!("{edges} edge pixels, {mixed} with samples of two or more materials");
    assert!(edges > 100, "only {edges} edge pixels");
    assert!(mixed > 20, "only {mixed} pixels with several materials");
}

/// benches/sweeps/msaa.ron (and msaa_8x.ron where the adapter has 8×) through the code
/// `lightgraph bench` runs, at this file's tiny size with 64 lights instead of 1920×1080
/// with 1,024-4,096: every graph renders, each is compared with its own reference, and
/// the MSAA graphs agree with brute force at their sample count. Tolerance: the stress
/// sweep's (tests/stress_sweep.rs: 2e-6 of the pixel, or of 1e-3 of the peak for dark
/// pixels); tiled_deferred.ron (no prepass: the G-buffer's own depth test keeps the first
/// of two equal depths, brute force the last) is only required to run.
#[test]
fn msaa_sweeps_run_at_a_tiny_size() {
    use lightgraph::bench::sweep::{self, Sweep};
    let mut r = renderer();
    let has_8x = offered(&r, &[8]).contains(&8);
    let names: &[&str] = if has_8x {
        &["msaa.ron", "msaa_8x.ron"]
    } else {
        &["msaa.ron"]
    };
    for name in names {
        let path = lightgraph::project_root().join("benches/sweeps").join(name);
        let mut plan = Sweep::load(&path).expect("the sweep parses");
        plan.resolutions = vec![(W, H)];
        plan.lights = vec![64];
        (plan.warmup, plan.warmup_seconds, plan.frames, plan.rounds) = (1, 0.0, 1, 1);
        let rows = sweep::run(&plan, path.parent().unwrap(), &mut r, |_| {}).expect("sweep");
        assert_eq!(rows.len(), plan.point_count(), "{name}");
        for row in &rows {
            let graph = format!("{}.ron", row.technique);
            let reference = plan.reference_for(&graph).trim_end_matches(".ron");
            eprintln!(
                "{name}: {} against {:?}: max rel {:?}",
                row.technique, row.reference, row.max_rel
            );
            assert_eq!(row.reference.as_deref(), Some(reference), "{name}: {graph}");
            assert_eq!(row.nan_pixels, Some(0), "{name}: {graph}");
            if graph != "tiled_deferred.ron" {
                let e = row.max_rel.expect("an error column");
                assert!(e <= 2e-6, "{name}: {graph} against {reference}: {e:e}");
            }
        }
        let ran: Vec<&str> = rows.iter().map(|r| r.technique.as_str()).collect();
        assert!(
            ran.iter().any(|t| t.starts_with("tiled_deferred_msaa")),
            "{name}: {ran:?}"
        );
    }
}
