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

/// ComputeRaster with the transparent depth in its writes, as `graphs/default.ron` has it
/// (`FOLDED_PASSES`), or beside a TransparentDepth pass of its own (`ALONE_PASSES`); the
/// culling pass reads both depths, which keeps them apart in memory to the end.
fn glass_graph(passes: &str, culling_reads: &str) -> String {
    format!(
        r#"Graph(
    name: "glass_in_the_opaque_run",
    resources: [
        Texture(name: "depth", format: R32Float),
        Texture(name: "visibility", format: R32Uint),
        Texture(name: "glass", format: R32Float),
        Texture(name: "glass_far", format: R32Float),
        Texture(name: "hdr", format: Rgba32Float),
        Buffer(name: "lists"),
        Import(name: "geometry", from: Geometry),
        Import(name: "vertices", from: Vertices),
        Import(name: "triangles", from: Triangles),
        Import(name: "material_triangles", from: MaterialTriangles),
        Import(name: "light_geometry", from: LightGeometry),
        Import(name: "light_properties", from: LightProperties),
    ],
    passes: [
        {passes}
        Pass(name: "cull", kind: LightCulling(tile: 16), reads: [{culling_reads}], writes: ["lists"]),
        Pass(name: "shade", kind: VisibilityShading(lights: AllLights), reads: ["visibility", "vertices", "triangles", "material_triangles", "light_geometry", "light_properties"], writes: ["hdr"]),
    ],
    output: "hdr",
    side_effects: ["cull"],
)"#
    )
}

const FOLDED_PASSES: &str = r#"Pass(name: "cr", kind: ComputeRaster, reads: ["vertices", "triangles", "material_triangles"], writes: ["depth", "visibility", "transparent_depth=glass", "transparent_far=glass_far"]),"#;
const FOLDED_READS: &str =
    r#""depth", "transparent_depth=glass", "transparent_far=glass_far", "light_geometry""#;
const ALONE_READS: &str = r#""depth", "transparent_depth=glass", "light_geometry""#;
const ALONE_PASSES: &str = r#"Pass(name: "cr", kind: ComputeRaster, reads: ["vertices", "triangles", "material_triangles"], writes: ["depth", "visibility"]),
        Pass(name: "td", kind: TransparentDepth, reads: ["geometry"], writes: ["depth=glass"]),"#;

/// The bits of the depth, the ids, the transparent depth and (folded) the farthest
/// transparent depth through `passes`, and the rasterizer's report (the folded pass's),
/// under the rasterizer's test `limits` ("" for none).
fn depth_ids_glass(
    scene: &Scene,
    folded: bool,
    limits: &str,
) -> (Vec<Vec<u32>>, lightgraph::render::RasterReport) {
    let mut r = renderer();
    let _limits = common::compute_raster::Limits::set(limits);
    let (passes, reads, names): (_, _, &[&str]) = if folded {
        (
            FOLDED_PASSES,
            FOLDED_READS,
            &["depth", "visibility", "glass", "glass_far"],
        )
    } else {
        (ALONE_PASSES, ALONE_READS, &["depth", "visibility", "glass"])
    };
    let prepared =
        prepare_text(&mut r, &glass_graph(passes, reads), scene, W, H, false).expect("prepare");
    let result = prepared.render(&r).expect("render");
    assert!(result.fallbacks.is_empty(), "{:?}", result.fallbacks);
    let bits = names
        .iter()
        .map(|name| {
            let b = prepared.read_texture_bits(&r, name).expect("readback");
            assert_eq!(b.len(), (W * H) as usize, "{name}: one value a pixel");
            b
        })
        .collect();
    let report = result
        .rasters
        .iter()
        .find(|r| r.pass == "cr")
        .expect("the rasterizer's report")
        .clone();
    (bits, report)
}

fn differing(a: &[u32], b: &[u32]) -> usize {
    a.iter().zip(b).filter(|(x, y)| x != y).count()
}

/// The opaque run that also draws the blended triangles (their depth alone, both faces)
/// writes TransparentDepth's own run's transparent depth to the bit and leaves the opaque
/// depth and ids as a run without them writes them; also through the list-full paths
/// (setup, bin and raster covering pixels serially); its farthest glass depth lies at or
/// behind the nearest, and is the same through those paths. On the glass scene and on
/// AlphaBlendModeTest (whose masked materials ride in the same run, flagged).
#[test]
fn glass_in_the_opaque_run_equals_its_own_run() {
    if !has_atomics() {
        return;
    }
    let glass = builtin::by_name("glass").expect("the built-in glass scene");
    // Glass pixels at least, and of those with glass behind glass (the glass scene's
    // quads overlap; the model's panels stand apart).
    for (what, scene, min_glass, min_behind) in [
        ("glass", glass, 5_000, 1_000),
        (
            "AlphaBlendModeTest",
            khronos_model("AlphaBlendModeTest"),
            500,
            0,
        ),
    ] {
        let (alone, _) = depth_ids_glass(&scene, false, "");
        let (unlimited, _) = depth_ids_glass(&scene, true, "");
        // The farthest glass depth: at or behind the nearest wherever there is glass,
        // behind it where layers overlap (or a surface is seen from both sides), 1.0
        // (as the nearest) elsewhere.
        let (mut behind, mut wrong) = (0, 0);
        for (&near, &far) in unlimited[2].iter().zip(&unlimited[3]) {
            let (near, far) = (f32::from_bits(near), f32::from_bits(far));
            wrong += (far < near || (near >= 1.0 && far != 1.0)) as usize;
            behind += (near < 1.0 && far > near) as usize;
        }
        eprintln!("{what}: the farthest glass lies behind the nearest at {behind} pixels");
        assert_eq!(wrong, 0, "{what}: farthest glass depths out of order");
        assert!(
            behind >= min_behind,
            "{what}: {behind} pixels with glass behind glass"
        );
        let covered = alone[2]
            .iter()
            .filter(|&&b| f32::from_bits(b) < 1.0)
            .count();
        assert!(covered >= min_glass, "{what}: {covered} glass pixels");
        for limits in ["", "records=0", "blocks=40"] {
            let (folded, report) = depth_ids_glass(&scene, true, limits);
            eprintln!("{what}, limits '{limits}': {covered} glass pixels, {report:?}");
            let serial_work = report.serial_triangles + report.serial_tiles + report.serial_blocks;
            assert_eq!(
                serial_work > 0,
                !limits.is_empty(),
                "{what}, '{limits}': {report:?}"
            );
            for (k, name) in [(0, "depth"), (1, "ids"), (2, "glass depth")] {
                let d = differing(&folded[k], &alone[k]);
                assert_eq!(d, 0, "{what}, '{limits}': {name} differs at {d} pixels");
            }
            let d = differing(&folded[3], &unlimited[3]);
            assert_eq!(
                d, 0,
                "{what}, '{limits}': farthest glass differs at {d} pixels"
            );
        }
    }
}
