//! Transparency with its own light lists (graphs/transparent.ron): the culled image must
//! equal the brute-force graph with the same blending order (graphs/
//! transparent_brute_force.ron) on the built-in glass scene (quads in front of, between
//! and behind opaque boxes, one against the sky, lights among them), for every culling
//! variant; so must glass over the compute-first frame (graphs/default.ron); blended
//! meshes are drawn back to front; without blended meshes the transparency passes are
//! skipped and the image is exactly Forward+'s (or the plain compute-first frame's).
//!
//! Tolerance: 2e-6 relative (as tests/culling_exact.rs). A culled light contributes
//! exactly zero and lists keep ascending light order, so both graphs sum the same
//! non-zero terms in the same order, and blending happens in the same order on the same
//! fixed-function hardware; the only slack is the shader compiler contracting a
//! multiply-add differently in the list loop and the all-lights loop (one f32 rounding,
//! 6e-8, per term over a few dozen terms per pixel and two blended layers).

mod common;
use common::glass::{check_glass_layers, differing, GlassLayers};
use common::*;
use glam::{Vec2, Vec3, Vec4};
use lightgraph::graph::{self, CullReason, FrameSize};
use lightgraph::scene::builtin;
use lightgraph::scene::{AlphaMode, Camera, Mesh, Scene, SurfaceMaterial};
use lightgraph::shader::ShaderLibrary;
use std::path::Path;

const W: u32 = 160;
const H: u32 = 90;
const TOL: f32 = 2e-6;

fn graph_file(name: &str) -> String {
    std::fs::read_to_string(graph_path(name)).unwrap()
}

fn glass() -> Scene {
    builtin::by_name("glass").expect("the built-in glass scene")
}

#[test]
fn culled_transparency_equals_brute_force_for_every_variant() {
    let scene = glass();
    assert!(scene.features().has_transparent);
    let mut r = renderer();
    let reference = render_file(&mut r, "transparent_brute_force.ron", &scene, W, H);
    assert_eq!(reference.image.len(), (W * H) as usize);
    // The glass must show: against the opaque-only frame (blended meshes skipped) it
    // changes a large share of the pixels.
    let opaque = render_file(&mut r, "forward_plus.ron", &scene, W, H);
    let changed = differing(&reference.image, &opaque.image);
    assert!(
        changed > (W * H / 10) as usize,
        "only {changed} pixels show glass: the scene tests nothing"
    );
    let text = graph_file("transparent.ron");
    let default = "LightCulling(tile: 16, variant: Frustum, lists: Compact(max_indices: 16777216))";
    assert_eq!(text.matches(default).count(), 2);
    for (tile, variant, lists) in [
        (16, "Frustum", "lists: Compact(max_indices: 16777216)"),
        (8, "Frustum", "lists: Compact(max_indices: 16777216)"),
        (16, "HalfZ", "lists: Compact(max_indices: 16777216)"),
        (16, "DepthMask", "lists: Compact(max_indices: 16777216)"),
        (
            16,
            "Clustered(slices: 16)",
            "lists: Compact(max_indices: 16777216)",
        ),
        // The fixed layout reads the same through the transparent pass.
        (16, "Frustum", "capacity: 256"),
        (16, "Clustered(slices: 16)", "capacity: 256"),
    ] {
        let g = text.replace(
            default,
            &format!("LightCulling(tile: {tile}, variant: {variant}, {lists})"),
        );
        let culled = render_text(&mut r, &g, &scene, W, H);
        let (err, at) = max_rel_diff(&culled.image, &reference.image);
        assert!(
            err <= TOL,
            "tile {tile} {variant} {lists}: error {err:e} at pixel ({}, {}) (culled {:?}, reference {:?})",
            at as u32 % W,
            at as u32 / W,
            culled.image[at],
            reference.image[at]
        );
        // The transparent lists are culled, not every light.
        let t = culled
            .culling
            .iter()
            .find(|c| c.pass == "transparent_culling")
            .expect("a report of the transparent culling pass");
        let per_tile = t.per_tile();
        let listed: u32 = per_tile.iter().sum();
        assert!(
            (listed as usize) < per_tile.len() * scene.lights.len() / 4,
            "{variant}: transparent lists hold {listed} lights over {} tiles",
            per_tile.len()
        );
        assert!(listed > 0, "{variant}: transparent lists are empty");
    }
}

/// The opaque lists are not enough for glass: shading it from them must be caught by the
/// comparison above (this is the failure the transparent lists exist to prevent).
#[test]
fn opaque_lists_for_glass_differ_from_brute_force() {
    let scene = glass();
    let mut r = renderer();
    let reference = render_file(&mut r, "transparent_brute_force.ron", &scene, W, H);
    let wrong = graph_file("transparent.ron").replace(
        r#""light_properties", "transparent_lists", "hdr"]"#,
        r#""light_properties", "light_lists", "hdr"]"#,
    );
    assert_ne!(wrong, graph_file("transparent.ron"));
    let culled = render_text(&mut r, &wrong, &scene, W, H);
    let (err, _) = max_rel_diff(&culled.image, &reference.image);
    assert!(
        err > 1e-3,
        "shading glass from the opaque lists is not caught ({err:e})"
    );
}

/// Renders `[graph, opaque]` (glass over a frame, and that frame's graph without glass)
/// and `[reference, opaque_reference]` likewise, and checks that the glass shows (it
/// changes over a tenth of the frame's pixels) and adds no error of its own: the
/// composite differs from the reference by at most the opaque layers' difference plus
/// TOL of the reference's peak. Returns the frame, the opaque layers' difference and the
/// peak.
fn glass_adds_no_error(
    r: &mut lightgraph::render::Renderer,
    scene: &Scene,
    [graph, opaque]: [&str; 2],
    [reference, opaque_reference]: [&str; 2],
) -> (lightgraph::render::FrameResult, f32, f32) {
    let reference_frame = render_file(r, reference, scene, W, H);
    let frame = render_file(r, graph, scene, W, H);
    assert_eq!(frame.image.len(), (W * H) as usize);
    let opaque_reference = render_file(r, opaque_reference, scene, W, H);
    let opaque_frame = render_file(r, opaque, scene, W, H);
    let layers = GlassLayers {
        frame: &frame.image,
        opaque: &opaque_frame.image,
        reference: &reference_frame.image,
        opaque_reference: &opaque_reference.image,
    };
    let (opaque_err, peak) = check_glass_layers(graph, W, TOL, &layers);
    (frame, opaque_err, peak)
}

/// Glass over the compute-first frame (graphs/default.ron: compute rasterizer, compute
/// shading, then the transparency passes on its depth) against forward brute force with
/// the same blending order.
///
/// Tolerance: the opaque layer is shaded from the visibility buffer (the point rebuilt
/// from the triangle, not interpolated by the rasterizer), so it differs from forward
/// shading by a few f32 ulps of position turned into radiance; that difference is
/// measured here on the same scene with the glass left out (brute_force.ron against
/// visibility_compute_raster.ron: 5.5e-5 absolute, 5e-5 of the peak, on lavapipe at
/// 160x90) and must stay within twice that. Glass blends over it with weight 1 − α ≤ 1, and the glass itself is shaded by
/// the same code from lists that hold every light reaching it (culled lights add exactly
/// 0), so the composite may differ by at most the opaque difference plus TOL of the peak
/// for the contraction slack of the glass terms.
#[test]
fn glass_over_the_compute_first_frame_equals_brute_force() {
    let scene = glass();
    let mut r = renderer();
    // The opaque layers alone: these graphs have no transparency pass and skip the glass.
    let (frame, opaque_err, peak) = glass_adds_no_error(
        &mut r,
        &scene,
        ["default.ron", "visibility_compute_raster.ron"],
        ["transparent_brute_force.ron", "brute_force.ron"],
    );
    assert!(
        opaque_err <= 1e-4 * peak,
        "the opaque compute-first frame differs from brute force by {opaque_err:e} (peak {peak})"
    );
    // Its depth rasterized in compute too (an R32Float transparent depth), by the opaque
    // triangles' rasterizer: one raster pass in the frame.
    let rasters: Vec<&str> = frame.rasters.iter().map(|r| r.pass.as_str()).collect();
    assert_eq!(rasters, ["compute_raster"], "{:?}", frame.rasters);
    // The glass was culled into its own lists, on the compute rasterizer's depth.
    let t = frame
        .culling
        .iter()
        .find(|c| c.pass == "transparent_culling")
        .expect("a report of the transparent culling pass");
    let listed: u32 = t.per_tile().iter().sum();
    assert!(listed > 0, "transparent lists are empty");
    assert!(
        (listed as usize) < t.per_tile().len() * scene.lights.len() / 4,
        "transparent lists hold {listed} lights"
    );
}

/// With the glass's lists ending at the farthest glass (`transparent_far`, which the
/// compute rasterizer keeps beside the nearest) where the opaque surface lies farther:
/// fewer lights listed than graphs/default.ron's ranges, which run on to the opaque
/// surface, and the same image to the bit (every light that reaches a glass surface is
/// still listed, in the same order, and a culled light adds exactly nothing). On the
/// glass scene and on AlphaBlendModeTest's textured panels.
#[test]
fn the_farthest_glass_shortens_the_glass_lists_and_changes_no_pixel() {
    let with_far = common::glass::default_with_farthest_glass();
    let without_far = graph_file("default.ron");
    let listed = |f: &lightgraph::render::FrameResult| -> u64 {
        let c = f
            .culling
            .iter()
            .find(|c| c.pass == "transparent_culling")
            .expect("a report of the transparent culling pass");
        c.counts.iter().map(|&n| n as u64).sum()
    };
    // The model with 64 random lights through its bounds (it brings none of its own).
    let mut model = khronos_model("AlphaBlendModeTest");
    let (lo, hi) = model.bounds().expect("the model's bounds");
    let size = (hi - lo).length();
    let mut rng = Rng(11);
    model.lights = (0..64)
        .map(|_| random_light(&mut rng, lo, hi, 0.1 * size, 0.4 * size))
        .collect();
    let mut r = renderer();
    for (what, scene) in [("glass", glass()), ("AlphaBlendModeTest", model)] {
        let near_only = render_text_with(&mut r, &without_far, &scene, W, H, false);
        let bounded = render_text_with(&mut r, &with_far, &scene, W, H, false);
        let (short, long) = (listed(&bounded), listed(&near_only));
        eprintln!(
            "{what}: glass lists hold {short} lights bounded by the farthest glass, {long} without"
        );
        assert!(short > 0, "{what}: no glass lists");
        assert!(short < long, "{what}: {short} against {long}");
        assert_eq!(bounded.image.len(), (W * H) as usize);
        assert_eq!(differing(&bounded.image, &near_only.image), 0, "{what}");
    }
}

/// Glass over tiled deferred (graphs/tiled_deferred_transparent.ron) is glass over
/// Forward+ (transparent.ron): the same depth prepass, transparent depth, transparent
/// lists and `TransparentShading` pass, blended over an opaque layer that deferred and
/// Forward+ shade with the same lights in the same order. On lavapipe the two images are
/// identical; the bound is the opaque layers' own difference (tiled_deferred_prepass
/// against forward_plus) plus TOL of the peak, as for the compute-first frame above.
#[test]
fn glass_over_tiled_deferred_equals_glass_over_forward_plus() {
    let scene = glass();
    let mut r = renderer();
    glass_adds_no_error(
        &mut r,
        &scene,
        [
            "tiled_deferred_transparent.ron",
            "tiled_deferred_prepass.ron",
        ],
        ["transparent.ron", "forward_plus.ron"],
    );
}

/// The same on real content: Khronos AlphaBlendModeTest (textured, normal-mapped opaque,
/// masked and blended meshes). The opaque layer is textured here, so deferred samples with
/// stored uv derivatives where Forward+ samples implicitly (tests/deferred_textured.rs)
/// and the images differ in the last steps of the filter weights. Measured on lavapipe at
/// 160×90: FLIP mean 6.0e-6 with glass, 1.6e-3 with the glass left out
/// (tiled_deferred_prepass); the bound is about 4× the first and 64× below the second.
#[test]
fn glass_over_tiled_deferred_matches_forward_plus_on_a_textured_model() {
    use lightgraph::bench::metrics::{compare, CompareOptions};
    let dir = tempfile::tempdir().unwrap();
    let model = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/assets/khronos/AlphaBlendModeTest/AlphaBlendModeTest.gltf");
    let file = dir.path().join("alpha_modes.ron");
    std::fs::write(
        &file,
        format!("Scene(models: [(path: {:?})])", model.display().to_string()),
    )
    .unwrap();
    let mut scene = lightgraph::scene::load(&file).expect("scene loads").scene;
    scene.add_headlight_if_unlit();
    assert!(scene.features().has_transparent);
    assert!(scene
        .materials
        .iter()
        .any(|m| m.base_color_texture.is_some()));
    let mut r = renderer();
    let forward = render_file(&mut r, "transparent.ron", &scene, W, H);
    let flip = |image: &[[f32; 4]]| {
        assert_eq!(image.len(), forward.image.len());
        let m = compare(&forward.image, image, W, H, &CompareOptions::default()).unwrap();
        m.flip_mean.unwrap()
    };
    let deferred = render_file(&mut r, "tiled_deferred_transparent.ron", &scene, W, H);
    let without_glass = render_file(&mut r, "tiled_deferred_prepass.ron", &scene, W, H);
    let (with, without) = (flip(&deferred.image), flip(&without_glass.image));
    eprintln!("FLIP mean with glass {with:e}, glass left out {without:e}");
    const BOUND: f64 = 2.5e-5;
    assert!(
        without > 10.0 * BOUND,
        "the glass hardly shows: {without:e}"
    );
    assert!(
        with <= BOUND,
        "FLIP mean {with:e} against glass over Forward+"
    );
}

fn emissive_quad(name: &str, material: usize, z: f32, x0: f32) -> Mesh {
    let mut m = Mesh {
        name: name.into(),
        material,
        ..Default::default()
    };
    for (a, b) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
        m.positions.push(Vec3::new(x0 + 2.0 * a, -1.0 + 2.0 * b, z));
        m.normals.push(Vec3::Z);
        m.uvs.push(Vec2::new(a, b));
        m.tangents.push(Vec4::new(1.0, 0.0, 0.0, 1.0));
    }
    m.indices = vec![0, 1, 2, 0, 2, 3];
    m
}

fn emissive_glass(name: &str, rgb: Vec3) -> SurfaceMaterial {
    SurfaceMaterial {
        name: name.into(),
        base_color: Vec4::new(0.0, 0.0, 0.0, 0.5),
        emissive: rgb,
        alpha_mode: AlphaMode::Blend,
        ..Default::default()
    }
}

/// Two half-transparent emissive quads that overlap, the near one first in the scene:
/// back to front, the overlap is near × ½ + far × ¼; the scene's order would give the
/// reverse weights.
#[test]
fn blended_back_to_front_whatever_the_scene_order() {
    let scene = Scene {
        name: "two_panes".into(),
        meshes: vec![
            emissive_quad("near_red", 0, -3.0, -1.5),
            emissive_quad("far_blue", 1, -5.0, -0.5),
        ],
        materials: vec![
            emissive_glass("red", Vec3::new(1.0, 0.0, 0.0)),
            emissive_glass("blue", Vec3::new(0.0, 0.0, 1.0)),
        ],
        camera: Camera {
            eye: Vec3::ZERO,
            target: Vec3::new(0.0, 0.0, -1.0),
            up: Vec3::Y,
            fov_y: 60f32.to_radians(),
            near: 0.1,
            far: 50.0,
        },
        ..Default::default()
    };
    let mut r = renderer();
    // default.ron: no opaque triangle at all for its compute rasterizer.
    for graph in [
        "transparent_brute_force.ron",
        "transparent.ron",
        "default.ron",
    ] {
        let f = render_file(&mut r, graph, &scene, 64, 64);
        // The frame's centre sees both quads (near x in [-1.5, 0.5], far in [-0.5, 1.5]).
        let p = f.image[(32 * 64 + 32) as usize];
        let want = [0.5, 0.0, 0.25];
        for c in 0..3 {
            assert!(
                (p[c] - want[c]).abs() < 1e-5,
                "{graph}: overlap {p:?}, want {want:?} (near over far)"
            );
        }
    }
}

/// The passes `when: Transparent` dropped from `compiled`, sorted.
fn skipped_without_glass(compiled: &graph::CompiledGraph) -> Vec<&str> {
    let mut skipped: Vec<&str> = compiled
        .culled
        .iter()
        .filter(|c| matches!(&c.reason, CullReason::WhenFalse(f) if f == "Transparent"))
        .map(|c| c.name.as_str())
        .collect();
    skipped.sort();
    skipped
}

#[test]
fn without_blended_meshes_the_transparency_passes_are_skipped() {
    let scene = random_scene(24, 15);
    assert!(!scene.features().has_transparent);
    let checked = graph::check_text(
        Path::new("transparent.ron"),
        &graph_file("transparent.ron"),
        &ShaderLibrary::builtin(),
    )
    .unwrap();
    let size = FrameSize {
        width: W,
        height: H,
        lights: scene.lights.len() as u32,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    assert_eq!(
        skipped_without_glass(&compiled),
        [
            "transparent_culling",
            "transparent_prepass",
            "transparent_shading"
        ]
    );
    assert_eq!(compiled.passes.len(), 3);
    let mut r = renderer();
    let plain = render_file(&mut r, "forward_plus.ron", &scene, W, H);
    let with = render_file(&mut r, "transparent.ron", &scene, W, H);
    assert_eq!(differing(&plain.image, &with.image), 0);
    assert!(
        plain.image.iter().any(|p| p[0] > 0.0),
        "a dark frame tests nothing"
    );
}

/// The default graph (graphs/default.ron) on a scene without blended meshes: its
/// transparency passes are skipped and what runs is the plain compute-first frame
/// (graphs/visibility_compute_raster.ron), pass for pass, with the same image bit for bit
/// (its Depth32Float depth holds the bits the R32Float one holds: the draw resolve and the
/// compute resolve agree exactly, tests/compute_raster.rs).
#[test]
fn without_blended_meshes_the_default_graph_is_the_compute_first_frame() {
    let scene = random_scene(24, 15);
    assert!(!scene.features().has_transparent);
    let size = FrameSize {
        width: W,
        height: H,
        lights: scene.lights.len() as u32,
    };
    let compile = |name: &str| {
        let checked = graph::check_text(
            Path::new(name),
            &graph_file(name),
            &ShaderLibrary::builtin(),
        )
        .unwrap();
        graph::compile(checked, &scene.features(), size)
    };
    let default = compile("default.ron");
    let plain = compile("visibility_compute_raster.ron");
    let passes = |g: &graph::CompiledGraph| {
        g.passes
            .iter()
            .map(|p| (p.name.to_string(), p.kind.clone()))
            .collect::<Vec<_>>()
    };
    assert_eq!(passes(&default), passes(&plain));
    assert_eq!(default.passes.len(), 3);
    // ComputeRaster resolves in compute, as in the plain frame: its depth is an R32Float
    // storage texture, never an attachment (a Depth32Float depth is resolved by a
    // full-screen draw, several times slower on GPUs that run graphics on few SMs).
    let depth = |g: &graph::CompiledGraph| {
        let planned = g.plan.get("depth").expect("a planned depth");
        g.plan.physical[planned.physical].clone()
    };
    let (d, p) = (depth(&default), depth(&plain));
    assert!(
        matches!(
            d.desc,
            graph::plan::PhysicalDesc::Texture {
                format: graph::TextureFormat::R32Float,
                samples: 1,
                ..
            }
        ),
        "{:?}",
        d.desc
    );
    assert_eq!(d.desc, p.desc);
    assert!(
        d.texture_usage
            .contains(wgpu::TextureUsages::STORAGE_BINDING)
            && !d
                .texture_usage
                .contains(wgpu::TextureUsages::RENDER_ATTACHMENT),
        "{:?}",
        d.texture_usage
    );
    assert_eq!(
        skipped_without_glass(&default),
        ["transparent_culling", "transparent_shading"]
    );
    let mut r = renderer();
    let a = render_file(&mut r, "visibility_compute_raster.ron", &scene, W, H);
    let b = render_file(&mut r, "default.ron", &scene, W, H);
    assert_eq!(a.image.len(), (W * H) as usize);
    assert_eq!(differing(&a.image, &b.image), 0);
    assert!(
        a.image.iter().any(|p| p[0] > 0.0),
        "a dark frame tests nothing"
    );
    // Not only the same passes and image: the same shaders. default.ron's shading reads
    // the shadow mask and its glass the BVH; without casters neither may switch on the
    // shadowed light loop (it costs shading time for nothing), so every pipeline of
    // default.ron is one the plain frame already put in the cache.
    // A renderer of its own: the shared one's cache already holds default.ron's pipelines.
    let mut fresh = lightgraph::render::Renderer::headless().expect("a wgpu adapter");
    let read = |g: &str| std::fs::read_to_string(graph_path(g)).unwrap();
    let plain = prepare_text(
        &mut fresh,
        &read("visibility_compute_raster.ron"),
        &scene,
        W,
        H,
        false,
    )
    .unwrap();
    assert!(
        !plain.stats().pipelines_built.is_empty(),
        "a fresh cache builds"
    );
    let default = prepare_text(&mut fresh, &read("default.ron"), &scene, W, H, false).unwrap();
    assert!(
        default.stats().pipelines_built.is_empty(),
        "default.ron without glass or casters built {:?}",
        default.stats().pipelines_built
    );
}
