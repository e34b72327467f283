//! The numerical stress sweep (`benches/sweeps/stress.ron`) through the code the `bench`
//! command runs: every case × every technique must give no NaN / Inf pixel and match the
//! brute-force image of the same scene.
//!
//! Tolerance: 2e-6 relative to the pixel, or to 1e-3 of the frame's peak for dark pixels
//! (`bench::REL_ERROR_FLOOR`, the measure of tests/culling_exact.rs; relative, so the 1e-6 and
//! 1e6 intensity cases are judged alike). Culled lights contribute exactly zero and lists keep
//! ascending light order, so every technique sums the same non-zero terms in the same order;
//! the only slack is the shader compiler contracting a multiply-add differently in different
//! pipelines: one f32 rounding (6e-8) per non-negative light term. Those roundings are
//! independent, so they grow like sqrt(n): about 1e-6 for the 300 lights that at most reach a
//! pixel here, and 2e-6 leaves a factor of two. A dropped light (a culling bug) or a list
//! overflow costs orders of magnitude more.

use lightgraph::bench::sweep::{self, Sweep};
use lightgraph::render::Renderer;

const TOLERANCE: f64 = 2e-6;
/// Every lit case lights at least 1 in this many pixels.
const MIN_LIT_FRACTION: u64 = 20;

#[test]
fn stress_sweep_has_no_nan_or_inf_and_matches_brute_force() {
    let path = lightgraph::project_root().join("benches/sweeps/stress.ron");
    let plan = Sweep::load(&path).expect("the stress sweep parses");
    let mut renderer = Renderer::headless().expect("a wgpu adapter (lavapipe on CI)");
    let rows = sweep::run(&plan, path.parent().unwrap(), &mut renderer, |_| {}).expect("sweep");
    assert_eq!(rows.len(), plan.point_count());

    let mut failures = Vec::new();
    let mut compared = 0;
    for r in &rows {
        let point = format!("{} {} ({} lights)", r.scene, r.technique, r.light_count);
        // The reference's own rows compare it with itself: only NaN / Inf and light count.
        let is_reference =
            plan.reference_for(&format!("{}.ron", r.technique)) == format!("{}.ron", r.technique);
        if r.nan_pixels != Some(0) || r.inf_pixels != Some(0) {
            failures.push(format!(
                "{point}: {:?} NaN and {:?} Inf pixels, first {:?}",
                r.nan_pixels, r.inf_pixels, r.non_finite_examples
            ));
        }
        if r.overflow_tiles.is_some_and(|n| n > 0) {
            failures.push(format!(
                "{point}: {:?} light lists overflowed: the case measures capacity, not numerics",
                r.overflow_tiles
            ));
        }
        if !is_reference {
            compared += 1;
            match r.max_rel {
                Some(e) if e <= TOLERANCE => {}
                e => failures.push(format!(
                    "{point}: relative error {e:?} (max abs {:?}) above {TOLERANCE:e}",
                    r.max_abs
                )),
            }
        }
        // A nearly black frame would pass everything above: each case must light a
        // good part of it (a single lit pixel tests one pixel's light loop).
        let lit = r.lit_pixels.unwrap_or(0);
        let pixels = r.width as u64 * r.height as u64;
        let dark = r.scene.ends_with("/no_lights");
        if (dark && lit != 0) || (!dark && lit * MIN_LIT_FRACTION < pixels) {
            failures.push(format!("{point}: {lit} of {pixels} pixels lit"));
        }
    }
    let references = rows.len() - compared;
    assert_eq!(
        references,
        plan.point_count() / plan.graphs.len(),
        "one reference row per case"
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn bad_cases_are_reported_with_file_and_line() {
    let text = r#"Sweep(
    scenes: ["builtin:depth_discontinuity"],
    graphs: ["brute_force.ron"],
    resolutions: [(16, 16)],
    cases: [
        (name: "fine", far: 1e6),
        (name: "zero_range", range: 0),
    ],
)"#;
    let err = Sweep::parse(text, std::path::Path::new("stress.ron"))
        .unwrap_err()
        .to_string();
    assert_eq!(
        err,
        "stress.ron: 7: cases[1] (\"zero_range\"): range 0 must be finite and > 0"
    );
    let err = Sweep::parse(&text.replace("far: 1e6", "fra: 1e6"), "s.ron".as_ref())
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("s.ron: 6:"), "{err}");
    assert!(err.contains("fra"), "{err}");
}

#[test]
fn every_shipped_sweep_parses() {
    let dir = lightgraph::project_root().join("benches/sweeps");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "ron") {
            let sweep = Sweep::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(sweep.point_count() > 0, "{}", path.display());
            count += 1;
        }
    }
    assert!(count >= 7, "only {count} sweep files in {}", dir.display());
}
