//! The examples are built with the suite (`cargo test --all-targets`); the headless one
//! also runs here, as a library user would run it, and must write its PNG.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The example binary beside this test's own (target/<profile>/examples/), built (or
/// found up to date) by cargo first: `cargo test --all-targets` compiles the examples but
/// need not refresh that path, and a stale binary would run an older library against
/// today's shaders.
fn example(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("the test binary's path");
    let profile_dir = exe
        .parent()
        .and_then(Path::parent)
        .expect("target/<profile>/deps");
    let path = profile_dir.join("examples").join(name);
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(cargo)
        .args(["build", "--release", "--example", name])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .status()
        .expect("cargo runs");
    assert!(status.success(), "building example {name} failed");
    path
}

/// Runs example `name` with `inputs` (paths under the project) and an output PNG in a
/// fresh folder, and returns the PNG it wrote, checked to be the documented 640×360.
fn run_for_png(name: &str, inputs: &[&str]) -> image::RgbImage {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("frame.png");
    let run = Command::new(example(name))
        .args(inputs.iter().map(|i| root.join(i)))
        .arg(&out)
        .output()
        .expect("the example runs");
    assert!(
        run.status.success(),
        "{name} failed: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let png = image::open(&out).expect("a PNG was written").to_rgb8();
    assert_eq!(
        png.dimensions(),
        (640, 360),
        "the example's documented size"
    );
    png
}

#[test]
fn the_headless_example_writes_its_png() {
    let png = run_for_png(
        "headless_png",
        &["scenes/harada.ron", "graphs/visibility_compute_raster.ron"],
    );
    // Harada's floor and boxes fill most of the lower half under 3,072 lights; an
    // unlit, black or blank frame would light almost nothing (the sky above is black).
    let lit = png.pixels().filter(|p| p.0.iter().any(|&c| c > 8)).count();
    let share = lit as f64 / (640.0 * 360.0);
    assert!(
        share > 0.3,
        "only {:.1}% of the frame is lit",
        share * 100.0
    );
}

/// Pixels of exactly the outline's colour (4, 3, 0.5) after the PNG's tonemap.
fn outline_pixels(png: &image::RgbImage) -> usize {
    let outline = lightgraph::bench::tonemap::Tonemap::default().to_srgb8([4.0, 3.0, 0.5]);
    png.pixels().filter(|p| p.0 == outline).count()
}

#[test]
fn the_custom_pass_example_outlines_the_silhouettes() {
    let png = run_for_png("custom_pass", &["scenes/harada.ron"]);
    // Harada's boxes against the floor and the black sky: thousands of silhouette pixels
    // (about 3% of the frame); lit surfaces never reach the outline's exact colour.
    let share = outline_pixels(&png) as f64 / (640.0 * 360.0);
    assert!(
        (0.01..0.2).contains(&share),
        "{:.2}% of the frame is outline",
        share * 100.0
    );
}
