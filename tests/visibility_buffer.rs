//! The visibility buffer (`graphs/visibility_buffer*.ron`): triangle ids from the prepass,
//! every material shaded in compute from them. Checked against forward brute force and
//! Forward+ on lavapipe: the culling tests' scenes, a textured, normal-mapped, alpha-masked
//! and double-sided scene, textured glTF, and the ids themselves against the depth prepass
//! and the triangles' projections.
//!
//! Not exact: shading rebuilds the point from the triangle's vertices at the pixel centre
//! (perspective-correct barycentrics from clip space), where forward shading gets the
//! rasterizer's interpolated attributes. Both are f32 roundings of the same point, so
//! the error is a few ulps of the position and normal, measured below.

mod common;
use common::textured::*;
use common::*;
use glam::{Vec3, Vec4Swizzles};
use lightgraph::bench::metrics::{compare, CompareOptions};
use lightgraph::render::SceneGpu;
use lightgraph::scene::{self, AlphaMode, Light, Scene, SurfaceMaterial};

const W: u32 = 333;
const H: u32 = 197;

/// Every visibility graph: one per culling variant, linked lists, and brute force.
const GRAPHS: [&str; 6] = [
    "visibility_buffer.ron",
    "visibility_buffer_half_z.ron",
    "visibility_buffer_depth_mask.ron",
    "visibility_buffer_clustered.ron",
    "visibility_buffer_linked_list.ron",
    "visibility_buffer_brute_force.ron",
];

/// Each pixel's worst channel error relative to max(|reference|, 1e-3 of the frame's
/// peak), as in culling_exact.rs (NaN counts as infinite).
fn rel_errors(out: &[[f32; 4]], reference: &[[f32; 4]]) -> Vec<f32> {
    assert_eq!(out.len(), reference.len(), "image sizes");
    assert!(!reference.is_empty(), "empty image");
    let peak = reference
        .iter()
        .flat_map(|p| p[..3].to_vec())
        .fold(0.0f32, f32::max);
    out.iter()
        .zip(reference)
        .map(|(a, b)| {
            (0..3)
                .map(|ch| {
                    let d = (a[ch] - b[ch]).abs() / b[ch].abs().max(1e-3 * peak).max(1e-30);
                    if d.is_nan() {
                        f32::INFINITY
                    } else {
                        d
                    }
                })
                .fold(0.0, f32::max)
        })
        .collect()
}

/// The worst relative error and where.
fn worst_rel(out: &[[f32; 4]], reference: &[[f32; 4]]) -> (f32, usize) {
    rel_errors(out, reference)
        .into_iter()
        .enumerate()
        .fold((0.0, 0), |w, (i, d)| if d > w.0 { (d, i) } else { w })
}

/// The relative error 99.9% of pixels stay within.
fn p999(out: &[[f32; 4]], reference: &[[f32; 4]]) -> f32 {
    let mut e = rel_errors(out, reference);
    e.sort_by(f32::total_cmp);
    e[e.len() - 1 - e.len() / 1000]
}

/// Bounds on the relative error against the reference: the worst pixel, and the 99.9th
/// percentile (which a systematic error anywhere in the frame breaks).
#[derive(Clone, Copy)]
struct Bound {
    worst: f32,
    p999: f32,
}

/// Renders `scene` through every visibility graph and `reference`, and returns the
/// failures above `bound` (printing every graph's worst error).
fn check_graphs(scene: &Scene, reference: &str, bound: Bound) -> Vec<String> {
    let graphs: Vec<(String, String)> = GRAPHS
        .iter()
        .map(|g| {
            (
                g.to_string(),
                std::fs::read_to_string(graph_path(g)).unwrap(),
            )
        })
        .collect();
    check_graph_texts(scene, reference, bound, &graphs)
}

/// [`check_graphs`] for graphs given as (name, text).
fn check_graph_texts(
    scene: &Scene,
    reference: &str,
    bound: Bound,
    graphs: &[(String, String)],
) -> Vec<String> {
    let mut r = renderer();
    let expected = render_file(&mut r, reference, scene, W, H);
    let lit = expected
        .image
        .iter()
        .filter(|p| p[0] + p[1] + p[2] > 0.0)
        .count();
    assert!(lit > 1000, "{}: only {lit} lit pixels", scene.name);
    let mut failures = Vec::new();
    for (graph, text) in graphs {
        let out = render_text(&mut r, text, scene, W, H);
        assert!(
            out.culling.iter().all(|c| c.overflowed_lists == 0),
            "{graph}: lists overflowed"
        );
        assert!(
            out.links.iter().all(|l| l.links_dropped == 0),
            "{graph}: link pool overflowed"
        );
        let (d, i) = worst_rel(&out.image, &expected.image);
        let p = p999(&out.image, &expected.image);
        println!(
            "{:24} {graph:36} worst {d:.3e}, 99.9% within {p:.3e}",
            scene.name
        );
        if d > bound.worst || p > bound.p999 {
            failures.push(format!(
                "{} {graph}: 99.9% within {p:e}, worst {d:e} at ({}, {}): {:?} vs {:?}",
                scene.name,
                i as u32 % W,
                i as u32 / W,
                out.image[i],
                expected.image[i]
            ));
        }
    }
    failures
}

/// Against forward brute force on the culling tests' scenes (untextured Lambert, lit by
/// hundreds of point and spot lights). Measured on lavapipe at 333x197 (2026-12-02), the
/// same for all five graphs: worst 1.40e-3 (random301), 3.36e-4 (depth_discontinuities),
/// 3.46e-4 (camera_inside), 1.24e-3 (random1100); 99.9% of pixels within 3.2e-5, 4.8e-5,
/// 7.5e-5 and 6.1e-5.
/// Why not ~1e-6: the rebuilt point and the rasterizer's interpolated one are each a few
/// f32 ulps of world coordinates up to 40 m (~1e-5 m) from the true point, and a light a
/// few centimetres from a surface turns that into 2·δ/d of its radiance (1/d² falloff).
/// The bounds are about twice the worst.
const BOUND_LAMBERT: Bound = Bound {
    worst: 3e-3,
    p999: 1.5e-4,
};

/// Against forward brute force on Khronos's MetalRoughSpheresNoTextures (98 materials
/// shaded by one dispatch, 512 random lights), at 333x197 on lavapipe (2026-12-06): worst
/// 4.98e-2, 99.9% of pixels within 1.57e-3, the same to three digits as with each
/// material's constants written into its own code (measured with the code swapped): the
/// rebuilt point's few-ulp offset (see BOUND_LAMBERT), magnified by the sharp highlights
/// of the smoothest metal spheres and by lights close to their surfaces. About twice
/// the worst.
const BOUND_SPHERES: Bound = Bound {
    worst: 0.1,
    p999: 3e-3,
};

#[test]
fn every_visibility_graph_matches_brute_force_on_the_culling_scenes() {
    let mut pillar = pillar_scene(500);
    pillar.name = "depth_discontinuities".into();
    let mut near = random_scene(0, 5);
    let eye = near.camera.eye;
    let fwd = (near.camera.target - eye).normalize();
    near.lights = vec![
        Light::point(eye, 8.0, Vec3::ONE, 5.0),
        Light::point(eye + fwd * 0.05, 3.0, Vec3::new(1.0, 0.2, 0.2), 2.0),
        Light::point(eye - fwd * 2.0, 6.0, Vec3::new(0.2, 1.0, 0.2), 8.0),
    ];
    near.name = "camera_inside".into();
    let mut failures = Vec::new();
    for s in [random_scene(301, 7), pillar, near, random_scene(1100, 17)] {
        failures.extend(check_graphs(&s, "brute_force.ron", BOUND_LAMBERT));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Textured, normal-mapped, glossy, masked and back-facing surfaces against forward
/// brute force. Measured on lavapipe at 333x197 (2026-12-02, textures with mip chains,
/// texture_mips.rs): worst 8.67e-3 at one pixel of the normal-mapped floor, 99.9% within
/// 2.84e-5 (one mip level: 8.54e-3 and 2.9e-5; 1.9e-4 worst without the normal map).
/// The mip level matches because the shader's derivatives are the quad's coarse ones.
/// The outlier is the texture unit's: llvmpipe (like D3D-class GPUs) filters with 8-bit
/// sub-texel weights, so a uv that differs in its last bits can land one 1/256-texel step
/// away; on a steep normal map (0.15 a texel) lit at a grazing angle that is a few
/// percent of n·l. The 99.9th percentile shows the systematic error stays ~3e-5.
const BOUND_TEXTURED: Bound = Bound {
    worst: 1.5e-2,
    p999: 1e-4,
};

#[test]
fn textured_masked_and_double_sided_materials_match_brute_force() {
    // With the compute rasterizer too: its alpha test keeps the prepass's pixels
    // (tests/compute_raster.rs), so the same bound holds.
    let graphs: Vec<(String, String)> = GRAPHS
        .iter()
        .chain(&["visibility_compute_raster.ron"])
        .map(|g| {
            (
                g.to_string(),
                std::fs::read_to_string(graph_path(g)).unwrap(),
            )
        })
        .collect();
    let failures = check_graph_texts(
        &textured_scene(),
        "brute_force.ron",
        BOUND_TEXTURED,
        &graphs,
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn alpha_masked_cut_outs_show_what_is_behind() {
    // Alpha 0.2 under a 0.5 cutoff everywhere: the panel must vanish from the frame.
    let mut r = renderer();
    let mut s = random_scene(40, 4);
    let reference = render_file(&mut r, "visibility_buffer.ron", &s, 96, 64);
    s.materials.push(SurfaceMaterial {
        name: "masked".into(),
        base_color: glam::Vec4::new(1.0, 1.0, 1.0, 0.2),
        alpha_mode: AlphaMode::Mask(0.5),
        double_sided: true,
        ..Default::default()
    });
    let eye = s.camera.eye;
    let m = s.materials.len() - 1;
    s.meshes.push(cuboid(
        "panel",
        eye + Vec3::new(-3.0, -3.0, -1.2),
        eye + Vec3::new(3.0, 3.0, -1.0),
        m,
        false,
    ));
    let cut = render_file(&mut r, "visibility_buffer.ron", &s, 96, 64);
    let (d, at) = max_rel_diff(&cut.image, &reference.image);
    assert!(d < 1e-6, "the cut-out panel changed pixel {at} by {d}");
    s.materials[m].base_color.w = 0.9;
    let solid = render_file(&mut r, "visibility_buffer.ron", &s, 96, 64);
    let (d, _) = max_rel_diff(&solid.image, &reference.image);
    assert!(d > 0.1, "an opaque-enough panel must show: {d}");
}

/// glTF with textures through the visibility buffer against Forward+ (the same culled
/// lists), with the FLIP mean and the worst relative error (bench/metrics.rs). Measured
/// on lavapipe at 333x197 (2026-12-02): see the bounds in the test.
#[test]
fn textured_gltf_matches_forward_plus() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let files = [
        root.join("scenes/cornell_box/scene.gltf"),
        root.join("tests/assets/khronos/BoxTextured/BoxTextured.gltf"),
    ];
    let mut r = renderer();
    let mut bad = Vec::new();
    for path in &files {
        let mut s = scene::load(path).unwrap().scene;
        s.add_headlight_if_unlit();
        // BoxTextured's sampler minifies NEAREST_MIPMAP_LINEAR: a nearest texel flips at
        // a texel edge where the two paths' uv differ by an ulp (2 pixels over 1e-3,
        // measured). What is compared here is the paths' derivatives and filtering, so
        // trilinear; tests/gltf_materials.rs checks glTF samplers in both paths.
        for m in &mut s.materials {
            m.sampling = Default::default();
        }
        let reference = render_file(&mut r, "forward_plus.ron", &s, W, H);
        let out = render_file(&mut r, "visibility_buffer.ron", &s, W, H);
        let m = compare(
            &reference.image,
            &out.image,
            W,
            H,
            &CompareOptions::default(),
        )
        .unwrap();
        let flip = m.flip_mean.unwrap();
        let (d, _) = worst_rel(&out.image, &reference.image);
        println!(
            "{:20} FLIP mean {flip:.3e}, max rel {d:.3e}, RMSE {:.3e}, bad pixels {}",
            path.file_name().unwrap().to_string_lossy(),
            m.rmse,
            m.bad_pixels
        );
        if flip > FLIP_BOUND || d > GLTF_WORST || m.bad_pixels > 0 {
            bad.push(format!("{}: {m}", path.display()));
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// The glTF comparison's bounds. Measured on lavapipe at 333x197 (2026-12-02): the
/// Cornell box (untextured) FLIP mean 0, worst relative 5.1e-6; BoxTextured FLIP mean
/// 7.4e-6, worst relative 5.4e-4 with mip chains (6.5e-6 and 1.5e-3 with one level; 8-bit
/// filter weights, as in BOUND_TEXTURED); no pixel
/// over the metric's 1e-3 threshold. Bounds a few times the measured.
const FLIP_BOUND: f64 = 5e-5;
const GLTF_WORST: f32 = 5e-3;

/// The ids and the depth of a visibility pass next to a depth prepass, read through
/// `shaders/visibility/ids_and_depth.wgsl`: x the visibility depth, y the prepass depth,
/// z the id (-1 for none).
const IDS_GRAPH: &str = r#"Graph(
    name: "ids",
    resources: [
        Texture(name: "depth", format: Depth32Float),
        Texture(name: "prepass_depth", format: Depth32Float),
        Texture(name: "visibility", format: R32Uint),
        Texture(name: "ids", format: Rgba32Float),
        Import(name: "geometry", from: Geometry),
    ],
    passes: [
        Pass(name: "vis", kind: VisibilityBuffer, reads: ["geometry"], writes: ["depth", "visibility"]),
        Pass(name: "pre", kind: DepthPrepass, reads: ["geometry"], writes: ["prepass_depth"]),
        Pass(
            name: "read",
            kind: Compute(shader: "visibility/ids_and_depth.wgsl", dispatch: PerPixel(workgroup: (8, 8))),
            reads: ["depth", "prepass_depth", "visibility"],
            writes: ["ids"],
        ),
    ],
    output: "ids",
)"#;

/// Every pixel the depth prepass covers has an id and no other pixel does, the two
/// depths agree to the bit, and each id names a triangle whose projection holds the
/// pixel centre (f64 on the CPU, within rasterizer snapping).
#[test]
fn ids_cover_exactly_the_prepass_depth_and_name_the_triangle_there() {
    for s in [textured_scene(), pillar_scene(10)] {
        let mut r = renderer();
        let out = render_text(&mut r, IDS_GRAPH, &s, W, H);
        // Triangle id -> (scene mesh, triangle in it), in draw order.
        let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, &s).unwrap();
        let mut owner = Vec::new();
        for mesh in gpu.opaque_draws() {
            let gm = &gpu.meshes[mesh];
            assert_eq!(gm.first_triangle as usize, owner.len());
            owner.extend((0..gm.index_count / 3).map(|t| (gm.scene_mesh, t as usize)));
        }
        let vp = (s.camera.projection(W as f32 / H as f32) * s.camera.view()).as_dmat4();
        let (mut covered, mut checked) = (0, 0);
        let mut errors = Vec::new();
        for (i, p) in out.image.iter().enumerate() {
            let (x, y) = (i as u32 % W, i as u32 / W);
            if p[0].to_bits() != p[1].to_bits() {
                errors.push(format!("({x}, {y}): depth {} vs prepass {}", p[0], p[1]));
            }
            let has_id = p[2] >= 0.0;
            if has_id != (p[1] < 1.0) {
                errors.push(format!("({x}, {y}): id {} at prepass depth {}", p[2], p[1]));
            }
            if !has_id {
                continue;
            }
            covered += 1;
            let Some(&(mesh, t)) = owner.get(p[2] as usize) else {
                errors.push(format!("({x}, {y}): id {} past the triangles", p[2]));
                continue;
            };
            let m = &s.meshes[mesh];
            let corners: Vec<glam::DVec4> = m.indices[3 * t..3 * t + 3]
                .iter()
                .map(|&v| vp * m.positions[v as usize].as_dvec3().extend(1.0))
                .collect();
            if corners.iter().any(|c| c.w <= 0.0) {
                continue; // crosses the camera plane: no 2D triangle to test against
            }
            let px: Vec<glam::DVec2> = corners
                .iter()
                .map(|c| {
                    let n = c.xy() / c.w;
                    glam::DVec2::new((n.x + 1.0) * 0.5 * W as f64, (1.0 - n.y) * 0.5 * H as f64)
                })
                .collect();
            let centre = glam::DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            let area = (px[1] - px[0]).perp_dot(px[2] - px[0]);
            // Signed distance in pixels to each edge, positive inside for either winding;
            // the rasterizer snaps vertices to 1/256 pixel.
            let inside = [(0, 1), (1, 2), (2, 0)].iter().all(|&(a, b)| {
                let e = px[b] - px[a];
                e.perp_dot(centre - px[a]) * area.signum() / e.length() >= -0.02
            });
            checked += 1;
            if !inside {
                errors.push(format!(
                    "({x}, {y}): id {} is triangle {t} of '{}', which does not cover the pixel",
                    p[2], m.name
                ));
            }
        }
        println!(
            "{}: {covered} pixels with ids, {checked} checked against their triangle",
            s.name
        );
        assert!(
            covered > (W * H / 2) as usize,
            "{}: only {covered} covered",
            s.name
        );
        let n = errors.len();
        errors.truncate(10);
        assert!(
            n == 0,
            "{}: {n} errors, first: {}",
            s.name,
            errors.join("\n")
        );
    }
}

/// `graph_text` with its VisibilityShading pass set to light loop `kind` (`Staged`,
/// `RangeFirst`, `GroupList`, `Forward`, optionally followed by `, workgroup: 8`).
fn with_loop(graph_text: &str, kind: &str) -> String {
    let on = [
        "VisibilityShading(lights: Culled)",
        "VisibilityShading(lights: AllLights)",
    ];
    let found = on
        .iter()
        .find(|k| graph_text.contains(*k))
        .expect("a VisibilityShading pass");
    let set = format!("{}, light_loop: {kind})", &found[..found.len() - 1]);
    graph_text.replace(found, &set)
}

/// The graphs staging runs on, as text: one list per tile (Frustum and DepthMask, tiles of
/// 16 and 8 pixels, compact and fixed lists), and those that keep the per-pixel walk
/// with the range test first (HalfZ, Clustered, linked lists, all lights).
fn staging_graphs() -> Vec<(String, String)> {
    let file = |name: &str| std::fs::read_to_string(graph_path(name)).unwrap();
    let mut graphs: Vec<(String, String)> =
        GRAPHS.iter().map(|g| (g.to_string(), file(g))).collect();
    for (name, kind) in [
        (
            "tile 8 Frustum",
            "LightCulling(tile: 8, variant: Frustum, lists: Compact(max_indices: 16777216))",
        ),
        (
            "tile 8 DepthMask",
            "LightCulling(tile: 8, variant: DepthMask, lists: Compact(max_indices: 16777216))",
        ),
        (
            "fixed 512 Frustum",
            "LightCulling(tile: 16, variant: Frustum, capacity: 512)",
        ),
        // Four 16×16 workgroups (GroupList's) share each list.
        (
            "tile 32 Frustum",
            "LightCulling(tile: 32, variant: Frustum, lists: Compact(max_indices: 16777216))",
        ),
    ] {
        graphs.push((
            name.to_string(),
            with_culling(&file("visibility_buffer.ron"), kind),
        ));
    }
    graphs
}

/// Pixels whose RGBA differ in any bit, and the first of them.
fn bit_differences(a: &[[f32; 4]], b: &[[f32; 4]]) -> (usize, Option<usize>) {
    assert_eq!(a.len(), b.len(), "image sizes");
    assert!(!a.is_empty(), "empty image");
    let differs = |(x, y): (&[f32; 4], &[f32; 4])| x.map(f32::to_bits) != y.map(f32::to_bits);
    let n = a.iter().zip(b).filter(|&p| differs(p)).count();
    (n, a.iter().zip(b).position(differs))
}

/// An image and what it is called in a failure.
type NamedImage<'a> = (&'a str, &'a [[f32; 4]]);

/// Compares an image with its reference to the bit (the reference lit at over 1,000
/// pixels, so the comparison means something): prints the count of differing pixels and
/// adds a failure naming `what`, the first such pixel and both values.
fn compare_bits(
    what: &str,
    ((test_name, test), (reference_name, reference)): (NamedImage, NamedImage),
    failures: &mut Vec<String>,
) {
    let lit = reference
        .iter()
        .filter(|p| p[0] + p[1] + p[2] > 0.0)
        .count();
    assert!(lit > 1000, "{what}: only {lit} lit pixels");
    let (n, first) = bit_differences(test, reference);
    println!("{what:64} {n} pixels differ");
    if let Some(i) = first {
        failures.push(format!(
            "{what}: {n} pixels differ, first ({}, {}): {test_name} {:?}, {reference_name} {:?}",
            i as u32 % W,
            i as u32 / W,
            test[i],
            reference[i]
        ));
    }
}

/// Renders `scene` through every staging graph with each light loop (Staged, RangeFirst,
/// GroupList; the last with workgroups of 16 and 8) against forward shading's loop
/// (Forward); the failures where the images differ in any bit. Staging only reorders loads
/// and skips lights that add nothing, so the sums are the same floats in the same order.
fn check_staging_is_exact(r: &mut lightgraph::render::Renderer, scene: &Scene) -> Vec<String> {
    let mut failures = Vec::new();
    for (graph, text) in staging_graphs() {
        let plain = render_text(r, &with_loop(&text, "Forward"), scene, W, H);
        for kind in [
            // 8×8 workgroups (Staged's side), the others 16×16 by default.
            "Staged",
            "RangeFirst",
            "GroupList",
            // GroupList and RangeFirst on 8×8 too: GroupList falls back to RangeFirst on every
            // graph without one list per tile (HalfZ, Clustered, linked lists, all lights).
            "GroupList, workgroup: 8",
        ] {
            let name = format!("{graph} {kind}");
            let staged = render_text(r, &with_loop(&text, kind), scene, W, H);
            assert!(
                staged.culling.iter().all(|c| c.overflowed_lists == 0),
                "{name}: lists overflowed"
            );
            assert!(
                staged.links.iter().all(|l| l.links_dropped == 0),
                "{name}: link pool overflowed"
            );
            let pair = (
                ("staged", &staged.image[..]),
                ("per pixel", &plain.image[..]),
            );
            compare_bits(&format!("{} {name}", scene.name), pair, &mut failures);
        }
    }
    failures
}

/// harada (two materials, 3,072 point and spot lights), a third of its lights lighting
/// only the floor and a third only the boxes, so the material mask skips lights inside a
/// batch. Its lists run to several batches of 64 with a partial last one (asserted), and
/// 333×197 leaves partial tiles and workgroups at the right and bottom edges.
fn masked_harada() -> Scene {
    let mut s = scene::builtin::harada();
    let floor = s.materials[0].type_bit;
    let boxes = s.materials[1].type_bit;
    assert_ne!(floor, boxes, "harada's materials have distinct type bits");
    for (i, l) in s.lights.iter_mut().enumerate() {
        l.material_mask = [floor, u32::MAX, boxes][i % 3];
    }
    s
}

#[test]
fn staged_light_loop_equals_the_per_pixel_loop_to_the_bit() {
    let mut r = renderer();
    let harada = masked_harada();
    // Several full batches and a partial one in the same list, in some tile.
    let lists = render_file(&mut r, "visibility_buffer.ron", &harada, W, H);
    let counts = &lists.culling[0].counts;
    let longest = counts.iter().copied().max().unwrap();
    assert!(
        counts.iter().any(|&c| c > 2 * 64 && c % 64 != 0),
        "no list of 3+ batches with a partial last one (longest {longest})"
    );
    println!("harada: longest list {longest}");
    let mut failures = check_staging_is_exact(&mut r, &harada);
    failures.extend(check_staging_is_exact(&mut r, &textured_scene()));
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for path in [
        root.join("scenes/cornell_box/scene.gltf"),
        root.join("tests/assets/khronos/BoxTextured/BoxTextured.gltf"),
    ] {
        let mut s = scene::load(&path).unwrap().scene;
        s.add_headlight_if_unlit();
        failures.extend(check_staging_is_exact(&mut r, &s));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// GroupList, the default light loop, walks each tile list a subgroup of lights at a
/// time (SUBGROUP_LIST: an invocation loads a light, shuffles pass it round) on a device
/// with subgroup operations, lavapipe among them, so the exactness test above checks that
/// walk; RangeFirst, and lists that are not one per tile (HalfZ), keep the per-pixel walk,
/// as does GroupList on a device without subgroups, to the same image.
#[test]
fn group_list_walks_by_subgroup_where_the_device_has_subgroups() {
    let subgroups = renderer()
        .ctx
        .device
        .features()
        .contains(wgpu::Features::SUBGROUP);
    println!("device has subgroup operations: {subgroups}");
    let harada = masked_harada();
    let plain = graph_text("visibility_buffer.ron");
    let cases = [
        ("default loop", plain.clone(), subgroups),
        ("RangeFirst", with_loop(&plain, "RangeFirst"), false),
        ("HalfZ", graph_text("visibility_buffer_half_z.ron"), false),
    ];
    for (name, text, expected) in cases {
        let built = pipelines_built_from("visibility/visibility_shading.wgsl", &text, &harada);
        assert!(!built.is_empty(), "{name}: no shading pipeline");
        for key in &built {
            assert_eq!(key.contains("SUBGROUP_LIST"), expected, "{name}: {key}");
        }
    }
    // A device without them walks per pixel: the same image to the bit.
    let mut without =
        lightgraph::render::Renderer::headless_with(&lightgraph::gpu::ContextOptions {
            disabled_features: wgpu::Features::SUBGROUP,
            ..Default::default()
        })
        .expect("a wgpu adapter (lavapipe on CI)");
    let per_pixel = render_text(&mut without, &plain, &harada, W, H);
    let by_subgroup = render_text(&mut renderer(), &plain, &harada, W, H);
    assert_eq!(per_pixel.image.len(), (W * H) as usize);
    let mut failures = Vec::new();
    compare_bits(
        "harada GroupList",
        (
            ("by subgroup", &by_subgroup.image[..]),
            ("per pixel", &per_pixel.image[..]),
        ),
        &mut failures,
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The staged graphs (Frustum and DepthMask, tiles of 16 and 8, compact and fixed lists)
/// and those on the range-first per-pixel walk (HalfZ, Clustered, linked lists, all
/// lights) against forward brute force on the masked harada, within the Lambert bounds
/// (the same cause: a rebuilt point; harada's GGX lobes are broad, roughness 0.4-0.5).
/// Measured on lavapipe at 333x197 (2026-12-02), the same for all nine graphs: worst
/// 1.46e-3, 99.9% within 1.31e-4 (harada's glossy lobes turn the rebuilt point's error
/// into a little more than the Lambert scenes' 7.5e-5).
#[test]
fn staged_and_range_first_loops_match_brute_force_on_harada() {
    let failures = check_graph_texts(
        &masked_harada(),
        "brute_force.ron",
        BOUND_LAMBERT,
        &staging_graphs()
            .into_iter()
            .map(|(name, text)| (name, with_loop(&text, "Staged")))
            .collect::<Vec<_>>(),
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `graph_text` with its VisibilityShading pass's materials dispatched as `how`
/// (`PerShader`, `Classified` or `PerMaterial`).
fn with_materials(graph_text: &str, how: &str) -> String {
    assert!(
        graph_text.contains("VisibilityShading("),
        "a VisibilityShading pass"
    );
    graph_text.replace(
        "VisibilityShading(",
        &format!("VisibilityShading(materials: {how}, "),
    )
}

/// Grouping and classification only choose which dispatch and which workgroups shade a
/// pixel: every pixel is shaded by its material's code with its constants from the same
/// inputs, so the shared-code groups (the default), their classified dispatches and one
/// dispatch per material give the same image to the bit. Checked with harada (two
/// materials) through the hardware and compute visibility buffers with each light loop
/// and both workgroup sides, the textured scene (textured, normal-mapped, alpha-masked,
/// double-sided) through the hardware one with 16- and 8-pixel workgroups, and 98
/// materials (Khronos's MetalRoughSpheresNoTextures, 2,048 random lights, one group of
/// shared code) through the compute-first frame (98 pipelines per material, slow on
/// lavapipe); 333×197 leaves partial tiles at the right and bottom edges.
#[test]
fn grouped_and_classified_shading_equal_per_material_dispatches_to_the_bit() {
    let mut r = renderer();
    let spheres = khronos_model("MetalRoughSpheresNoTextures");
    assert!(
        spheres.materials.len() >= 98,
        "{} materials",
        spheres.materials.len()
    );
    let spheres = lightgraph::bench::sweep::with_light_count(&spheres, 2048);
    let every_loop = [
        "RangeFirst",
        "Staged",
        "GroupList",
        "RangeFirst, workgroup: 8",
    ];
    let both_graphs = ["visibility_buffer.ron", "visibility_compute_raster.ron"];
    let cases: [(Scene, &[&str], &[&str]); 3] = [
        (masked_harada(), &both_graphs, &every_loop),
        (textured_scene(), &both_graphs[..1], &every_loop[..2]),
        (spheres, &both_graphs[1..], &every_loop[..1]),
    ];
    let file = |name: &str| std::fs::read_to_string(graph_path(name)).unwrap();
    let mut failures = Vec::new();
    for (s, graphs, loops) in &cases {
        for graph in graphs.iter() {
            for kind in loops.iter() {
                let text = with_loop(&file(graph), kind);
                let grouped = render_text(&mut r, &with_materials(&text, "PerShader"), s, W, H);
                let classified = render_text(&mut r, &with_materials(&text, "Classified"), s, W, H);
                let whole = render_text(&mut r, &with_materials(&text, "PerMaterial"), s, W, H);
                let what = format!("{} {graph} {kind}", s.name);
                let pair = (
                    ("classified", &classified.image[..]),
                    ("grouped", &grouped.image[..]),
                );
                compare_bits(&what, pair, &mut failures);
                let pair = (
                    ("per material", &whole.image[..]),
                    ("grouped", &grouped.image[..]),
                );
                compare_bits(&what, pair, &mut failures);
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Materials that differ only in constants share one shading pipeline and dispatch: the
/// spheres' 98 untextured metallic-roughness materials and the default material build
/// one visibility-shading pipeline (a fresh renderer, so nothing comes from the cache);
/// each sphere still shades with its own
/// constants, as forward brute force (its constants written into its own code) shades it.
#[test]
fn materials_that_differ_only_in_constants_share_one_dispatch() {
    let spheres = khronos_model("MetalRoughSpheresNoTextures");
    let spheres = lightgraph::bench::sweep::with_light_count(&spheres, 64);
    let text = std::fs::read_to_string(graph_path("visibility_compute_raster.ron")).unwrap();
    // The spheres' 98 and the default material of their primitives without one (it is
    // single-sided, they are double-sided: shared code leaves sidedness out) in one
    // group.
    let shading = pipelines_built_from("visibility/visibility_shading.wgsl", &text, &spheres);
    assert_eq!(shading.len(), 1, "{shading:?}");
    assert!(shading[0].contains("MEMBERS_COUNT=99u"), "{shading:?}");
    let spheres = lightgraph::bench::sweep::with_light_count(&spheres, 512);
    let graphs = [("visibility_compute_raster.ron".to_string(), text)];
    let failures = check_graph_texts(&spheres, "brute_force.ron", BOUND_SPHERES, &graphs);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Textured glTF materials that read the same images through the same samplers share a
/// dispatch: AlphaBlendModeTest's opaque and three alpha-masked label materials read one
/// image with their own alpha modes and build one shading pipeline of four, beside the
/// bed's (its blended glass is not shaded here). BoxTextured beside it has the same code
/// but another image: a third pipeline (sharing the labels' would draw the labels on the
/// box). Grouped and per-material dispatches give the same bits, and the grouped frame
/// matches forward brute force, whose code has each material's constants written in.
#[test]
fn textured_materials_that_read_the_same_images_share_one_dispatch() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let khronos = root.join("tests/assets/khronos");
    let dir = tempfile::tempdir().unwrap();
    let scene_file = dir.path().join("labels_and_box.ron");
    std::fs::write(
        &scene_file,
        format!(
            r#"Scene(
    name: "labels_and_box",
    models: [
        (path: "{}"),
        (path: "{}", transform: (translation: (2.2, 0.5, 0.5), scale: (1.2, 1.2, 1.2))),
    ],
    camera: LookAt(eye: (0.6, 1.6, 5.5), target: (0.6, 0.6, 0), fov_y_deg: 50, near: 0.1, far: 30),
)"#,
            khronos
                .join("AlphaBlendModeTest/AlphaBlendModeTest.gltf")
                .display(),
            khronos.join("BoxTextured/BoxTextured.gltf").display()
        ),
    )
    .unwrap();
    let mut s = scene::load(&scene_file).unwrap().scene;
    // Trilinear, as in textured_gltf_matches_forward_plus: a nearest texel flips where
    // the two paths' uv differ by an ulp.
    for m in &mut s.materials {
        m.sampling = Default::default();
    }
    let s = lightgraph::bench::sweep::with_light_count(&s, 256);
    let text = std::fs::read_to_string(graph_path("visibility_compute_raster.ron")).unwrap();
    let shading = pipelines_built_from("visibility/visibility_shading.wgsl", &text, &s);
    assert_eq!(shading.len(), 3, "{shading:?}");
    assert!(
        shading
            .iter()
            .any(|l| l.contains("MEMBERS_COUNT=4u") && l.contains("SHARED_CODE")),
        "{shading:?}"
    );
    let mut r = renderer();
    let grouped = render_text(&mut r, &with_materials(&text, "PerShader"), &s, W, H);
    let whole = render_text(&mut r, &with_materials(&text, "PerMaterial"), &s, W, H);
    let mut failures = Vec::new();
    let pair = (
        ("per material", &whole.image[..]),
        ("grouped", &grouped.image[..]),
    );
    compare_bits("labels and box", pair, &mut failures);
    drop(r);
    let graphs = [("visibility_compute_raster.ron".to_string(), text)];
    failures.extend(check_graph_texts(
        &s,
        "brute_force.ron",
        BOUND_TEXTURED,
        &graphs,
    ));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
