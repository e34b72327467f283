//! The shadow atlas drawn by the compute raster (`ShadowAtlas(raster: Compute)`) against
//! the raster pipeline's, and maps kept across frames (`cache: true`) against maps drawn
//! afresh: the atlases texel by texel, the shaded images pixel by pixel.

mod common;

use common::{renderer, shadow_room, Rng};
use glam::Vec3;
use lightgraph::render::{FrameResult, PreparedFrame, Renderer, SceneGpu};
use lightgraph::scene::{light_flags, Camera, Light, LightShape, Scene};
use std::collections::HashMap;

const W: u32 = 80;
const H: u32 = 48;
const SIDE: u32 = 512;

/// shadow_atlas.ron at a 512² atlas, drawn by `raster`, keeping maps if `cache`.
fn graph(raster: &str, cache: bool) -> String {
    graph_file("shadow_atlas.ron", raster, cache)
}

/// `file` (a graph with the shipped atlas) at a 512² atlas, drawn by `raster`.
fn graph_file(file: &str, raster: &str, cache: bool) -> String {
    let text = std::fs::read_to_string(common::graph_path(file)).unwrap();
    let format = if raster == "Compute" {
        "R32Float"
    } else {
        "Depth32Float"
    };
    let out = text
        .replace(
            "Texture(name: \"shadow_atlas\", format: Depth32Float, size: Fixed(4096, 4096))",
            &format!("Texture(name: \"shadow_atlas\", format: {format}, size: Fixed({SIDE}, {SIDE}))"),
        )
        .replace(
            "ShadowAtlas(filter: Pcf5x5, min_tile: 16, max_tile: 1024, importance: 1.0)",
            &format!("ShadowAtlas(filter: Pcf5x5, min_tile: 16, max_tile: 128, importance: 4.0, raster: {raster}, cache: {cache})"),
        );
    assert!(
        out.contains(&format!("format: {format}, size: Fixed({SIDE}")) && out.contains("cache:"),
        "{file}: the atlas replaced"
    );
    out
}

/// shadow_room with a spot light, a wide spot (six faces) and two point lights.
fn scene() -> Scene {
    let mut rng = Rng(7);
    let caster = |l: Light| Light {
        flags: light_flags::CASTS_SHADOW,
        ..l
    };
    let spot = |position: Vec3, direction: Vec3, outer: f32| {
        caster(Light {
            shape: LightShape::Spot {
                direction,
                inner_angle: outer * 0.8,
                outer_angle: outer,
            },
            ..Light::point(position, 14.0, Vec3::new(1.0, 0.9, 0.8), 6.0)
        })
    };
    Scene {
        name: "atlas room".into(),
        meshes: shadow_room(&mut rng),
        materials: vec![
            common::lambert("floor", Vec3::splat(0.8)),
            common::lambert("boxes", Vec3::new(0.7, 0.6, 0.5)),
        ],
        lights: vec![
            spot(Vec3::new(-1.0, 4.5, -3.0), Vec3::new(0.2, -1.0, -0.1), 0.6),
            spot(Vec3::new(2.0, 3.8, -5.0), Vec3::new(0.0, -1.0, 0.3), 1.2),
            caster(Light::point(
                Vec3::new(0.5, 1.8, -1.5),
                9.0,
                Vec3::new(0.9, 0.6, 0.4),
                3.0,
            )),
            caster(Light::point(
                Vec3::new(-3.0, 2.2, -6.0),
                9.0,
                Vec3::new(0.4, 0.7, 1.0),
                3.0,
            )),
        ],
        camera: Camera {
            eye: Vec3::new(0.0, 5.0, 6.0),
            target: Vec3::new(0.0, 0.0, -4.0),
            ..Default::default()
        },
        ..Default::default()
    }
}

/// `text` prepared for `scene`, with the scene's light buffers (which light updates take).
fn prepare(r: &mut Renderer, text: &str, scene: &Scene) -> (PreparedFrame, SceneGpu) {
    use lightgraph::graph::{self, FrameSize};
    let checked = graph::check_text(
        std::path::Path::new("<test>"),
        text,
        &lightgraph::shader::ShaderLibrary::builtin(),
    )
    .expect("valid graph");
    let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, scene).expect("materials");
    let size = FrameSize {
        width: W,
        height: H,
        lights: gpu.light_capacity,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    let prepared = r
        .prepare(compiled, scene, &gpu, size, false)
        .expect("prepare");
    (prepared, gpu)
}

/// A rendered frame and its atlas's texels (depth bits).
struct Drawn {
    frame: FrameResult,
    atlas: Vec<u32>,
    tiles: HashMap<(u32, u32), (u32, u32, u32)>,
}

fn draw(r: &Renderer, prepared: &PreparedFrame) -> Drawn {
    let frame = prepared.render(r).unwrap();
    let atlas = prepared.read_texture_bits(r, "shadow_atlas").unwrap();
    assert_eq!(atlas.len(), (SIDE * SIDE) as usize, "atlas size");
    let table = prepared.read_buffer(r, "shadow_views").unwrap();
    Drawn {
        frame,
        atlas,
        tiles: tiles(bytemuck::cast_slice(&table)),
    }
}

/// Each (light, face)'s tile (x, y, side) from the view table (src/kinds/shadow_atlas):
/// a header vec4, six vec4 a view (view-projection, tile in UV, ...), then per light its
/// first view + 1 with bit 31 for six faces.
fn tiles(table: &[u32]) -> HashMap<(u32, u32), (u32, u32, u32)> {
    let (side, lights, max_views) = (table[1], table[2], table[3]);
    let light_table = 4 * (1 + 6 * max_views as usize);
    let mut out = HashMap::new();
    for l in 0..lights {
        let entry = table[light_table + l as usize];
        if entry == 0 {
            continue;
        }
        let first = (entry & 0x7fff_ffff) - 1;
        let faces = if entry & 0x8000_0000 != 0 { 6 } else { 1 };
        for f in 0..faces {
            let uv = 4 * (1 + 6 * (first + f) as usize + 4);
            let lo = [table[uv], table[uv + 1]]
                .map(|b| (f32::from_bits(b) * side as f32).round() as u32);
            let hi = f32::from_bits(table[uv + 2]) * side as f32;
            out.insert((l, f), (lo[0], lo[1], hi.round() as u32 - lo[0]));
        }
    }
    out
}

/// Texels of two atlases' tiles, (light, face) by (light, face), wherever each has it.
struct TileDiff {
    texels: usize,
    /// Covered in one, the far depth in the other: a triangle's edge ran across it.
    coverage: usize,
    /// Covered in both at depths more than `DEPTH_TOL` apart.
    depth: usize,
    worst_depth: f32,
    /// Covered in both at exactly the same depth.
    exact: usize,
    covered: usize,
}

/// Depths of texels both rasterizers cover: equal bar the interpolation's rounding
/// (the plane from unsnapped vertices in both, evaluated in another order) and the
/// depth bias's rounding. 1e-5 is 80 of the bias's own units near depth 1 (2^-24 each):
/// far below what separates a caster from a receiver (the bias is ≥ 2 units plus the
/// slope term, the normal offset 1.5 texels).
const DEPTH_TOL: f32 = 1e-5;

fn compare_tiles(a: &Drawn, b: &Drawn) -> TileDiff {
    let mut d = TileDiff {
        texels: 0,
        coverage: 0,
        depth: 0,
        worst_depth: 0.0,
        exact: 0,
        covered: 0,
    };
    assert_eq!(a.tiles.len(), b.tiles.len(), "the same views");
    for (key, &(ax, ay, side)) in &a.tiles {
        let &(bx, by, bside) = b.tiles.get(key).expect("the same views");
        assert_eq!(side, bside, "{key:?}: the same tile side");
        for y in 0..side {
            for x in 0..side {
                let p = a.atlas[((ay + y) * SIDE + ax + x) as usize];
                let q = b.atlas[((by + y) * SIDE + bx + x) as usize];
                d.texels += 1;
                let far = 1.0f32.to_bits();
                if (p == far) != (q == far) {
                    d.coverage += 1;
                } else if p != far {
                    d.covered += 1;
                    d.exact += usize::from(p == q);
                    let delta = (f32::from_bits(p) - f32::from_bits(q)).abs();
                    d.worst_depth = d.worst_depth.max(delta);
                    if delta > DEPTH_TOL {
                        d.depth += 1;
                    }
                }
            }
        }
    }
    d
}

/// Coverage may differ only where a triangle edge crosses a texel centre within the
/// rounding of the two vertex transforms (a vertex stage and a compute shader may
/// contract the matrix product differently): on lavapipe none does in this scene; 1 in
/// 20,000 of the tiles' texels allowed (3 here; a flipped fill rule shows 6, with depths
/// apart on the shared edges).
fn assert_close(d: &TileDiff, what: &str) {
    eprintln!(
        "{what}: {} texels, {} coverage, {} depth (worst {:e}), {} of {} covered equal",
        d.texels, d.coverage, d.depth, d.worst_depth, d.exact, d.covered
    );
    assert!(
        d.texels > 10_000,
        "{what}: only {} texels compared",
        d.texels
    );
    assert!(
        d.coverage * 20_000 <= d.texels,
        "{what}: {} of {} texels covered in one atlas only",
        d.coverage,
        d.texels
    );
    assert_eq!(
        d.depth, 0,
        "{what}: depths apart by up to {}",
        d.worst_depth
    );
    // The constant bias (2 units of 2^(e − 23)) is below DEPTH_TOL: the same rule kept
    // most texels bit for bit (two thirds here; 3% without the constant bias).
    assert!(
        d.exact * 2 >= d.covered,
        "{what}: only {} of {} covered texels bit for bit",
        d.exact,
        d.covered
    );
}

#[test]
fn the_compute_atlas_matches_the_hardware_atlas() {
    let mut r = renderer();
    let scene = scene();
    let (hw, _) = prepare(&mut r, &graph("Hardware", false), &scene);
    let (cs, _) = prepare(&mut r, &graph("Compute", false), &scene);
    let a = draw(&r, &hw);
    let b = draw(&r, &cs);
    assert_eq!(
        a.frame.atlases[0].views,
        1 + 6 + 12,
        "{:?}",
        a.frame.atlases[0]
    );
    assert_eq!(a.tiles, b.tiles, "the same allocation");
    let report = b.frame.atlases[0]
        .raster
        .expect("the compute raster's report");
    assert_eq!(
        report.serial_triangles + report.serial_cells,
        0,
        "{report:?}"
    );
    assert!(
        report.cells > 0,
        "large triangles went through the cell list: {report:?}"
    );
    assert_close(&compare_tiles(&a, &b), "compute against hardware");
    // Shading: the same filters by hand over the same depths. lavapipe weighs its
    // comparison taps exactly, as the hand-written filter does: equal but for the
    // summation order (1e-5 of the peak; GPUs with 8-bit filter weights would differ by
    // up to 1/256 of a tap where a footprint straddles an edge).
    assert_shaded_alike(&a.frame, &b.frame, "Pcf5x5");
    let (hw, _) = prepare(
        &mut r,
        &graph("Hardware", false).replace("Pcf5x5", "Hardware2x2"),
        &scene,
    );
    let (cs, _) = prepare(
        &mut r,
        &graph("Compute", false).replace("Pcf5x5", "Hardware2x2"),
        &scene,
    );
    assert_shaded_alike(
        &hw.render(&r).unwrap(),
        &cs.render(&r).unwrap(),
        "Hardware2x2",
    );
    // Every other shader that samples the atlas: deferred, the compute-first frame, glass.
    for file in [
        "tiled_deferred_shadow_atlas.ron",
        "visibility_shadow_atlas.ron",
        "transparent_shadow_atlas.ron",
    ] {
        let (hw, _) = prepare(&mut r, &graph_file(file, "Hardware", false), &scene);
        let (cs, _) = prepare(&mut r, &graph_file(file, "Compute", false), &scene);
        assert_shaded_alike(&hw.render(&r).unwrap(), &cs.render(&r).unwrap(), file);
    }
}

fn assert_shaded_alike(hardware: &FrameResult, compute: &FrameResult, filter: &str) {
    assert_eq!(hardware.image.len(), (W * H) as usize, "image size");
    let (d, at) = common::max_rel_diff(&compute.image, &hardware.image);
    eprintln!("{filter}: shaded images apart by {d:e}");
    assert!(
        d <= 1e-5,
        "{filter}: compute against hardware atlas: {d:e} at pixel {at}"
    );
    let shadowed = hardware
        .image
        .iter()
        .zip(&compute.image)
        .filter(|(p, _)| p[0] < 1e-3)
        .count();
    assert!(
        shadowed > 100,
        "{filter}: the scene shows shadows ({shadowed} dark pixels)"
    );
}

#[test]
fn kept_maps_equal_maps_drawn_afresh() {
    for raster in ["Hardware", "Compute"] {
        let mut r = renderer();
        let start = scene();
        let (cached, gpu) = prepare(&mut r, &graph(raster, true), &start);
        let first = draw(&r, &cached);
        let views = first.frame.atlases[0].views;
        assert_eq!(
            first.frame.atlases[0].views_rendered, views,
            "{raster}: first frame"
        );
        // Nothing moved: nothing drawn, the same atlas and image.
        let still = draw(&r, &cached);
        assert_eq!(still.frame.atlases[0].views_rendered, 0, "{raster}: still");
        assert_eq!(still.atlas, first.atlas, "{raster}: still atlas");
        assert_eq!(
            still.frame.image, first.frame.image,
            "{raster}: still image"
        );
        // The first point light moves: its six faces are drawn, the rest kept.
        let mut moved = start.clone();
        moved.lights[2].position += Vec3::new(0.7, 0.3, -0.4);
        cached.update_lights(&r, &gpu, &moved.lights).unwrap();
        let after = draw(&r, &cached);
        assert_eq!(
            after.frame.atlases[0].views_rendered, 6,
            "{raster}: after the move"
        );
        // A light changing colour only keeps its maps.
        let mut tinted = moved.clone();
        tinted.lights[0].color = Vec3::new(0.2, 0.9, 0.3);
        cached.update_lights(&r, &gpu, &tinted.lights).unwrap();
        let recoloured = draw(&r, &cached);
        assert_eq!(
            recoloured.frame.atlases[0].views_rendered, 0,
            "{raster}: recoloured"
        );
        cached.update_lights(&r, &gpu, &moved.lights).unwrap();
        let after = draw(&r, &cached);
        // Against the moved scene drawn afresh: every map, placed elsewhere (hence the
        // tolerance of two rasterizations of one view at other offsets).
        let (fresh, _) = prepare(&mut r, &graph(raster, true), &moved);
        let fresh = draw(&r, &fresh);
        assert_eq!(fresh.frame.atlases[0].views_rendered, views);
        assert_close(
            &compare_tiles(&after, &fresh),
            &format!("{raster}: kept against fresh"),
        );
        // The image against the same frames drawn without the cache (a light update's
        // image and a fresh prepare's differ by themselves in ~100 of these pixels, with
        // or without the cache): equal bar the order culling sums a tile's lights in.
        let (plain, plain_gpu) = prepare(&mut r, &graph(raster, false), &start);
        draw(&r, &plain);
        plain.update_lights(&r, &plain_gpu, &moved.lights).unwrap();
        let plain = draw(&r, &plain);
        assert_eq!(plain.frame.atlases[0].views_rendered, views);
        let (d, at) = common::max_rel_diff(&after.frame.image, &plain.frame.image);
        assert!(
            d <= 2e-6,
            "{raster}: kept against drawn: {d:e} at pixel {at}"
        );
    }
}

/// The compute atlas raster's test hook (src/kinds/shadow_atlas/raster.rs): caps on its
/// record and cell lists, read when the pass is prepared.
const TEST_LIMITS: &str = "LIGHTGRAPH_ATLAS_RASTER_TEST_LIMITS";

#[test]
fn full_lists_fall_back_to_serial_rasterization_with_the_same_atlas() {
    // Set and cleared while holding the renderer: no other test prepares meanwhile.
    let mut r = renderer();
    let scene = scene();
    let (listed, _) = prepare(&mut r, &graph("Compute", false), &scene);
    let listed = draw(&r, &listed);
    let mut reports = Vec::new();
    for limits in ["records=1", "cells=3"] {
        std::env::set_var(TEST_LIMITS, limits);
        let prepared = prepare(&mut r, &graph("Compute", false), &scene);
        std::env::remove_var(TEST_LIMITS);
        let serial = draw(&r, &prepared.0);
        let report = serial.frame.atlases[0].raster.expect("compute report");
        assert!(
            report.serial_triangles + report.serial_cells > 0,
            "{limits}: nothing ran serially: {report:?}"
        );
        // An atomic min is order-independent and every path runs the same per-texel
        // code: the same atlas, bit for bit.
        let differ = serial
            .atlas
            .iter()
            .zip(&listed.atlas)
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(differ, 0, "{limits}: {differ} texels differ");
        reports.push(report);
    }
    assert!(
        reports[0].serial_triangles > 0 && reports[1].serial_cells > 0,
        "{reports:?}"
    );
    std::env::set_var(TEST_LIMITS, "cells=0");
    let e = common::prepare_text(&mut r, &graph("Compute", false), &scene, W, H, false)
        .err()
        .map(|e| e.to_string());
    std::env::remove_var(TEST_LIMITS);
    let e = e.expect("a bad hook value is refused");
    assert!(e.contains(TEST_LIMITS) && e.contains("'cells=0'"), "{e}");
}

/// `scene()` with a striped, alpha-masked panel (a mip-mapped checker whose alpha is
/// 255 and 20 in stripes, cut at 0.5) held level under the first spot light, both faces
/// casting; `solid`: the same panel opaque.
fn masked_panel_scene(solid: bool) -> Scene {
    let mut scene = scene();
    common::textured::push_striped_quad(
        &mut scene,
        "panel",
        Vec3::new(-0.8, 2.6, -3.0),
        Vec3::X * 1.2,
        Vec3::Z * 1.2,
        solid,
    );
    scene
}

/// Alpha-masked casters are alpha-tested by the compute raster (a run of the material's
/// own, each texel rebuilt as visibility shading rebuilds a pixel): its atlas is the
/// hardware atlas's, whose fragment stage discards below the cutoff, but for texels
/// where a triangle edge or the filtered alpha lies within rounding of the test
/// (`assert_close`'s 1 in 20,000; the uv footprint is the texel's 2×2 quad in both). The
/// mask cuts the panel's shadow into stripes (the solid panel's atlas differs from it
/// in many texels), and the shaded frames agree.
#[test]
fn alpha_masked_casters_are_alpha_tested_in_compute() {
    let mut r = renderer();
    let scene = masked_panel_scene(false);
    let (hw, _) = prepare(&mut r, &graph("Hardware", false), &scene);
    let (cs, _) = prepare(&mut r, &graph("Compute", false), &scene);
    let (a, b) = (draw(&r, &hw), draw(&r, &cs));
    assert_eq!(a.tiles, b.tiles, "the same allocation");
    assert_close(&compare_tiles(&a, &b), "masked: compute against hardware");
    let (solid, _) = prepare(&mut r, &graph("Compute", false), &masked_panel_scene(true));
    let solid = draw(&r, &solid);
    let cut = compare_tiles(&solid, &b);
    eprintln!("the mask cuts {} texels of the solid panel's", cut.coverage);
    assert!(cut.coverage > 200, "the mask cuts {} texels", cut.coverage);
    assert_shaded_alike(&a.frame, &b.frame, "masked Pcf5x5");
}
