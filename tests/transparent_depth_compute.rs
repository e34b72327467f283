//! `TransparentDepth` into an R32Float texture: the blended triangles rasterized by the
//! compute rasterizer must give the depth the raster units draw into a Depth32Float
//! (both faces, nearest wins) but for a counted few edge pixels, on the built-in glass
//! scene and on Khronos's AlphaBlendModeTest (textured, with blended panels); and the
//! pass must have run in compute (its raster report), not fallen back.
//! The same bounds as the opaque compute rasterizer against the depth prepass
//! (tests/common/compute_raster.rs: `MAX_COVERAGE_DIFF`, `DEPTH_TOLERANCE`, and why).

mod common;
use common::compute_raster::{
    has_atomics, DEPTH_TOLERANCE, MAX_COVERAGE_DIFF, TRANSPARENT_COMPARE,
};
use common::*;
use lightgraph::render::FrameResult;
use lightgraph::scene::{builtin, Scene};

/// Odd sizes: partial tiles and blocks at the right and bottom edges.
const W: u32 = 333;
const H: u32 = 197;

/// The frame and the two depths' values.
fn both_depths(scene: &Scene) -> (FrameResult, Vec<f32>, Vec<f32>) {
    let mut r = renderer();
    let prepared = prepare_text(&mut r, TRANSPARENT_COMPARE, scene, W, H, false).expect("prepare");
    let result = prepared.render(&r).expect("render");
    let read = |name: &str| -> Vec<f32> {
        let bits = prepared.read_texture_bits(&r, name).expect("readback");
        assert_eq!(bits.len(), (W * H) as usize, "{name}: one value a pixel");
        bits.into_iter().map(f32::from_bits).collect()
    };
    let (cr, hw) = (read("transparent_cr"), read("transparent_hw"));
    (result, cr, hw)
}

/// Pixels covered by both, by one only, and the largest depth difference where both
/// cover (1.0 is the far plane: nothing blended there).
fn compare(cr: &[f32], hw: &[f32]) -> (usize, usize, f32) {
    let (mut both, mut one, mut depth) = (0, 0, 0f32);
    for (&c, &h) in cr.iter().zip(hw) {
        match (c < 1.0, h < 1.0) {
            (true, true) => {
                both += 1;
                depth = depth.max((c - h).abs());
            }
            (false, false) => {}
            _ => one += 1,
        }
    }
    (both, one, depth)
}

fn matches_the_raster_units(what: &str, scene: &Scene, min_covered: usize) {
    let (frame, cr, hw) = both_depths(scene);
    let (both, one, depth) = compare(&cr, &hw);
    eprintln!("{what}: {both} pixels covered by both, {one} by one only, depth within {depth:e}");
    assert!(
        frame.fallbacks.is_empty(),
        "{what}: fell back: {:?}",
        frame.fallbacks
    );
    let report = frame
        .rasters
        .iter()
        .find(|r| r.pass == "cr")
        .expect("the compute pass's raster report");
    assert_eq!(
        (
            report.serial_triangles,
            report.serial_tiles,
            report.serial_blocks
        ),
        (0, 0, 0),
        "{what}: {report:?}"
    );
    assert!(
        both >= min_covered,
        "{what}: {both} blended pixels: nothing compared"
    );
    assert!(one <= cr.len() / MAX_COVERAGE_DIFF, "{what}: {one} pixels");
    assert!(depth <= DEPTH_TOLERANCE, "{what}: depth {depth:e}");
}

#[test]
fn compute_transparent_depth_matches_the_raster_units() {
    if !has_atomics() {
        return;
    }
    let glass = builtin::by_name("glass").expect("the built-in glass scene");
    // Quads in front of, between and behind boxes, and one against the sky.
    matches_the_raster_units("glass", &glass, 5_000);
    // The blended panels on the textured bed, seen by the model's framing: 787 pixels
    // at this size on lavapipe.
    matches_the_raster_units(
        "AlphaBlendModeTest",
        &khronos_model("AlphaBlendModeTest"),
        500,
    );
}
