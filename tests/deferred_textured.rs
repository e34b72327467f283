//! Every deferred graph takes every material forward shading takes: textured,
//! normal-mapped, alpha-masked and double-sided ones, from a glTF file (BoxTextured) and
//! from the textured test scene (tests/common/textured.rs: a normal-mapped checker floor,
//! masked and double-sided panels). Each graph's image against its forward counterpart
//! (the same lights, lists and shadows), by FLIP mean (bench/metrics.rs).

mod common;
use common::msaa::offered;
use common::textured::*;
use common::*;
use lightgraph::bench::metrics::{compare, CompareOptions};
use lightgraph::scene::{self, Scene};

const W: u32 = 160;
const H: u32 = 96;

/// Each deferred graph and the forward graph that shades with the same lights.
const PAIRS: &[(&str, &str)] = &[
    ("tiled_deferred.ron", "forward_plus.ron"),
    ("tiled_deferred_prepass.ron", "forward_plus.ron"),
    ("tiled_deferred_packed.ron", "forward_plus.ron"),
    (
        "tiled_deferred_depth_mask.ron",
        "forward_plus_depth_mask.ron",
    ),
    ("deferred_brute_force.ron", "brute_force.ron"),
    ("light_linked_list_deferred.ron", "light_linked_list.ron"),
    ("tiled_deferred_msaa.ron", "msaa.ron"),
    ("tiled_deferred_msaa_8x.ron", "msaa_8x.ron"),
    ("tiled_deferred_raycast_shadows.ron", "raycast_shadows.ron"),
    ("tiled_deferred_shadow_atlas.ron", "shadow_atlas.ron"),
    ("tiled_deferred_indirect_vpl.ron", "indirect_vpl.ron"),
    (
        "tiled_deferred_indirect_vpl_visibility.ron",
        "indirect_vpl_visibility.ron",
    ),
    ("tiled_deferred_transparent.ron", "transparent.ron"),
    (
        "tiled_deferred_msaa_transparent.ron",
        "transparent_msaa.ron",
    ),
    // No forward glass at 8× to set it beside; these scenes have no glass.
    ("tiled_deferred_msaa_8x_transparent.ron", "msaa_8x.ron"),
];

/// FLIP mean of a deferred image against forward's. Measured on lavapipe at 160×96
/// (2026-12-06): BoxTextured 3.6e-5, the textured scene 1.25e-4 (1.26e-4 packed), no
/// pixel over 1.1e-3 relative; its floor through a second uv set at 2.7 times the
/// frequency 2.24e-4 (2.33e-4 packed; through the first set instead 7.1e-2). Forward
/// samples with textureSample, deferred with textureSampleGrad at the stored uv and
/// derivatives, and the tangent comes back from
/// an angle, so filter weights (8-bit on lavapipe) and normal-mapped shading move in
/// their last steps. For comparison, ignoring the uv (every texel at uv 0) scores
/// FLIP 0.1-0.3. The bound is about 1.3× the worst (the second uv set, packed).
const FLIP_BOUND: f64 = 3e-4;
/// At 4× MSAA: BoxTextured 2.96e-4, the textured scene 5.24e-4, the second uv set
/// 9.83e-4. Higher: edge pixels
/// average samples whose uv derivatives lavapipe's implicit sampling takes across the
/// quad at centroid-moved positions, while the G-buffer stores dpdx of the centroid uv.
const FLIP_BOUND_MSAA: f64 = 1.2e-3;

fn scenes() -> Vec<(String, Scene)> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut box_textured =
        scene::load(&root.join("tests/assets/khronos/BoxTextured/BoxTextured.gltf"))
            .unwrap()
            .scene;
    box_textured.add_headlight_if_unlit();
    vec![
        ("BoxTextured".into(), box_textured),
        ("textured_scene".into(), textured_scene()),
        ("second_uv_set".into(), second_uv_set_scene()),
    ]
}

/// The textured scene with its floor's checker sampled through TEXCOORD_1: a second uv
/// set on the floor, scaled, rotated and offset from the first, so a G-buffer that
/// carried only the first would show the checker at another size and angle.
fn second_uv_set_scene() -> Scene {
    let mut s = textured_scene();
    s.name = "second_uv_set".into();
    s.materials[0].sampling.base_color.tex_coord = 1;
    let mut floors = 0;
    for mesh in s.meshes.iter_mut().filter(|m| m.material == 0) {
        mesh.uvs1 = mesh
            .uvs
            .iter()
            .map(|uv| glam::Vec2::new(0.6 * uv.x - 0.8 * uv.y + 0.3, 0.8 * uv.x + 0.6 * uv.y) * 2.7)
            .collect();
        floors += 1;
    }
    assert!(
        floors > 0,
        "the textured scene has no floor mesh of material 0"
    );
    s
}

/// The floor's second uv set is what the second-uv-set scene's image shows: sampled
/// through TEXCOORD_0 instead (what deferred shading did before the G-buffer carried the
/// second set), forward shading's image differs far beyond the deferred bound.
#[test]
fn the_second_uv_set_changes_the_image() {
    let mut r = renderer();
    let uv1 = second_uv_set_scene();
    let mut uv0 = uv1.clone();
    uv0.materials[0].sampling.base_color.tex_coord = 0;
    let a = render_file(&mut r, "forward_plus.ron", &uv1, W, H);
    let b = render_file(&mut r, "forward_plus.ron", &uv0, W, H);
    assert_eq!(a.image.len(), (W * H) as usize);
    let m = compare(&a.image, &b.image, W, H, &CompareOptions::default()).unwrap();
    let flip = m.flip_mean.unwrap();
    println!("TEXCOORD_1 against TEXCOORD_0: FLIP mean {flip:.3e}");
    assert!(flip > 100.0 * FLIP_BOUND, "{m}");
}

#[test]
fn every_deferred_graph_matches_forward_on_textured_scenes() {
    let mut r = renderer();
    // lavapipe offers 4× but not 8×: graphs at a count the adapter lacks are skipped.
    let eight = !offered(&r, &[8]).is_empty();
    let mut bad = Vec::new();
    for (name, s) in scenes() {
        assert!(
            s.materials.iter().any(|m| m.base_color_texture.is_some()),
            "{name}: not textured"
        );
        for (deferred, forward) in PAIRS {
            if deferred.contains("8x") && !eight {
                println!("{name:14} {deferred:36} skipped: no 8× MSAA here");
                continue;
            }
            let reference = render_file(&mut r, forward, &s, W, H);
            let out = render_file(&mut r, deferred, &s, W, H);
            assert_eq!(out.image.len(), (W * H) as usize, "{deferred}");
            assert_eq!(reference.image.len(), out.image.len(), "{forward}");
            let m = compare(
                &reference.image,
                &out.image,
                W,
                H,
                &CompareOptions::default(),
            )
            .unwrap();
            let flip = m.flip_mean.unwrap();
            let (d, _) = max_rel_diff(&out.image, &reference.image);
            println!(
                "{name:14} {deferred:36} FLIP mean {flip:.3e}, max rel {d:.3e}, bad pixels {}",
                m.bad_pixels
            );
            let bound = if deferred.contains("msaa") {
                FLIP_BOUND_MSAA
            } else {
                FLIP_BOUND
            };
            if flip.is_nan() || flip > bound {
                bad.push(format!("{name} {deferred} against {forward}: {m}"));
            }
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// A G-buffer without the surface targets cannot shade a textured material: refused at
/// prepare, naming the pass and the material (untextured scenes still render with it).
#[test]
fn a_textured_material_needs_the_surface_targets() {
    let text: String = std::fs::read_to_string(graph_path("tiled_deferred.ron"))
        .unwrap()
        .replace(
            ", \"g_surface\", \"g_uv_grad\", \"g_uv1\", \"g_uv1_grad\"",
            "",
        )
        .lines()
        .filter(|l| {
            !["g_surface", "g_uv_grad", "g_uv1", "g_uv1_grad"]
                .iter()
                .any(|t| l.contains(&format!("Texture(name: \"{t}\"")))
        })
        .map(|l| format!("{l}\n"))
        .collect();
    assert!(
        !text.contains("\"g_surface\"") && !text.contains("\"g_uv_grad\""),
        "{text}"
    );
    let (_, s) = scenes().remove(0);
    let mut r = renderer();
    let e = match prepare_text(&mut r, &text, &s, W, H, false) {
        Ok(_) => panic!("a textured material through a G-buffer without surface targets"),
        Err(e) => e.to_string(),
    };
    assert!(
        e.contains("deferred_shading")
            && e.contains(
                "reads textures, the tangent or the vertex colour: its G-buffer needs the surface targets 'g_surface' and 'g_uv_grad'"
            ),
        "{e}"
    );
}

/// Anisotropic lobes turn about the tangent, which the G-buffer carries: the showcase
/// atrium's brushed bronze (materials/brushed_metal.ron, anisotropic GGX; untextured)
/// through tiled deferred against Forward+. Measured on lavapipe at 160×96 (2026-12-06):
/// worst 2.1e-7 of the peak, FLIP mean 0; with the tangent zeroed in deferred shading
/// (as before the G-buffer held it) the worst pixel is 0.97 off and FLIP 1.9e-3. The
/// bound leaves 5× for the tangent's round trip through its angle (cos, sin).
#[test]
fn anisotropic_materials_turn_about_the_stored_tangent() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut s = scene::load(&root.join("scenes/atrium_showcase.ron"))
        .unwrap()
        .scene;
    s.add_headlight_if_unlit();
    let mut r = renderer();
    let reference = render_file(&mut r, "forward_plus.ron", &s, W, H);
    let out = render_file(&mut r, "tiled_deferred.ron", &s, W, H);
    assert_eq!(out.image.len(), (W * H) as usize);
    let (d, at) = max_rel_diff(&out.image, &reference.image);
    assert!(d <= 1e-6, "pixel {at} off by {d:e} of the peak");
}

/// The G-buffer's surface pair (`g_surface`, `g_uv_grad`) is written only when a material
/// of the scene reads the uv or the tangent: the pair is two more Rgba32Float targets, and
/// on GH100's few graphics SMs it doubled harada's G-buffer pass (1.93 → 3.81 ms at
/// 1080p). A textured scene fills it; a plain one leaves it as created (zero) and still
/// renders as forward does. The second uv set's pair (`g_uv1`, `g_uv1_grad`) likewise, only
/// for a material that samples with TEXCOORD_1.
#[test]
fn the_surface_pair_is_written_only_for_materials_that_read_it() {
    let mut r = renderer();
    let written = |r: &mut lightgraph::render::Renderer, s: &Scene, target: &str| {
        let text = std::fs::read_to_string(graph_path("tiled_deferred.ron")).unwrap();
        let frame = prepare_text(r, &text, s, W, H, false).unwrap();
        frame.execute(r).unwrap();
        let texels = frame.read_texture(r, target).unwrap();
        assert_eq!(texels.len(), (W * H) as usize, "{target}'s size");
        texels
            .iter()
            .filter(|t| t.iter().any(|&c| c != 0.0))
            .count()
    };
    let textured = written(&mut r, &textured_scene(), "g_surface");
    assert!(
        textured > (W * H / 4) as usize,
        "a textured scene fills g_surface ({textured} texels written)"
    );
    assert_eq!(
        written(&mut r, &textured_scene(), "g_uv1"),
        0,
        "a scene without TEXCOORD_1 textures leaves g_uv1 unwritten"
    );
    let uv1 = written(&mut r, &second_uv_set_scene(), "g_uv1_grad");
    assert!(
        uv1 > (W * H / 8) as usize,
        "the floor's TEXCOORD_1 checker fills g_uv1_grad ({uv1} texels written)"
    );
    let plain = random_scene(64, 5);
    assert_eq!(
        written(&mut r, &plain, "g_surface"),
        0,
        "a plain scene leaves g_surface unwritten"
    );
    let reference = render_file(&mut r, "forward_plus.ron", &plain, W, H);
    let out = render_file(&mut r, "tiled_deferred.ron", &plain, W, H);
    let (d, at) = max_rel_diff(&out.image, &reference.image);
    // Forward+ and tiled deferred sum the same culled lights in the same order: only
    // rounding of the stored position and normal differs (culling_exact.rs holds 2e-6).
    assert!(d <= 2e-6, "pixel {at} off by {d:e} of the peak");
}

/// Deferred shading groups materials as visibility shading does: the spheres' 98
/// materials and the default material of their primitives without one build one
/// deferred-shading pipeline (a fresh renderer, so nothing comes from the cache), and
/// each sphere still shades with its own constants, as Forward+ (each material's
/// constants written into its code) shades it.
#[test]
fn deferred_shading_shades_materials_that_share_their_code_in_one_dispatch() {
    let spheres = khronos_model("MetalRoughSpheresNoTextures");
    let spheres = lightgraph::bench::sweep::with_light_count(&spheres, 256);
    let text = std::fs::read_to_string(graph_path("tiled_deferred.ron")).unwrap();
    let shading = pipelines_built_from("deferred/deferred_shading.wgsl", &text, &spheres);
    assert_eq!(shading.len(), 1, "{shading:?}");
    assert!(shading[0].contains("SHARED_CODE"), "{shading:?}");
    let mut r = renderer();
    let reference = render_file(&mut r, "forward_plus.ron", &spheres, W, H);
    let out = render_text(&mut r, &text, &spheres, W, H);
    let m = compare(
        &reference.image,
        &out.image,
        W,
        H,
        &CompareOptions::default(),
    )
    .unwrap();
    let flip = m.flip_mean.unwrap();
    let (d, _) = max_rel_diff(&out.image, &reference.image);
    println!(
        "spheres tiled_deferred: FLIP mean {flip:.3e}, max rel {d:.3e}, bad pixels {}",
        m.bad_pixels
    );
    assert!(d <= SPHERES_MAX_REL, "max rel {d:e}: {m}");
}

/// The spheres' deferred image against Forward+'s, worst pixel and channel relative:
/// 7.6e-8 on lavapipe at 160×96 (2026-12-06; FLIP 0). The Rgba32Float G-buffer holds the
/// position and normal forward shading had, so only the code differs (constants read
/// from a buffer against written in): a few ulps. About 13× the measured.
const SPHERES_MAX_REL: f32 = 1e-6;
