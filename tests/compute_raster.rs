//! The compute rasterizer (`ComputeRaster`) against the hardware depth prepass on the
//! same device: coverage equal but for a counted few edge pixels, depth equal within a
//! tiny tolerance where both cover; near-plane clipping, the shared-workgroup path for
//! large triangles, and depth ties (the later triangle wins, as LessEqual keeps it).

mod common;
use common::compute_raster::*;
use common::textured::*;
use common::*;
use glam::{Vec2, Vec3};
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::SceneGpu;
use lightgraph::scene::{AlphaMode, Mesh, Scene};
use lightgraph::shader::ShaderLibrary;
use std::path::Path;

#[test]
fn lavapipe_has_the_64_bit_atomics() {
    let r = renderer();
    let have = r.ctx.device.features();
    let needed = wgpu::Features::SHADER_INT64 | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX;
    eprintln!(
        "compute raster: adapter {} offers SHADER_INT64 {}, SHADER_INT64_ATOMIC_MIN_MAX {}, TEXTURE_INT64_ATOMIC {}",
        r.ctx.adapter_name(),
        r.ctx.adapter.features().contains(wgpu::Features::SHADER_INT64),
        r.ctx
            .adapter
            .features()
            .contains(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX),
        r.ctx
            .adapter
            .features()
            .contains(wgpu::Features::TEXTURE_INT64_ATOMIC),
    );
    if !have.contains(needed) {
        eprintln!(
            "!!!!! THIS ADAPTER LACKS 64-BIT ATOMICS: the compute rasterizer cannot run; only its hardware fallback is tested (tests/compute_raster_fallback.rs) !!!!!"
        );
        drop(r);
        let frame = render_text(&mut renderer(), COMPARE, &random_scene(4, 1), 64, 36);
        assert_eq!(frame.fallbacks.len(), 1, "the fallback says so");
    }
}

#[test]
fn shipped_scenes_match_the_depth_prepass() {
    if !has_atomics() {
        return;
    }
    for rel in [
        "scenes/harada.ron",
        "scenes/atrium_amd.ron",
        "scenes/chairs.ron",
        "scenes/depth_discontinuity.ron",
        "scenes/cornell_box/scene.gltf",
    ] {
        let scene = load(rel);
        let (px, report) = rasterize_limited(&scene, 333, 197, "");
        let d = diff(&scene, &px);
        eprintln!("{rel}: {d:?}, {report:?}");
        assert_eq!(report.serial(), 0, "{rel}: the lists hold the scene");
        assert!(d.covered > d.pixels / 4, "{rel}: {d:?}");
        assert_matches(rel, &d);
    }
}

/// The screen split along its diagonal into two triangles at different depths whose
/// corners project onto the frame's corners: the diagonal passes exactly through the
/// centres of pixels (i, i). The top-left rule gives them to the upper-right triangle
/// (the diagonal is its left edge; the lower-left one's right edge), the far one here.
#[test]
fn top_left_rule_on_a_diagonal_through_pixel_centres() {
    if !has_atomics() {
        return;
    }
    let (near, far) = (2.0, 4.0);
    let s = scene(
        vec![
            // Lower left on screen, near.
            triangle(
                "near",
                [
                    Vec3::new(-near, near, -near),
                    Vec3::new(-near, -near, -near),
                    Vec3::new(near, -near, -near),
                ],
                0,
            ),
            // Upper right, far.
            triangle(
                "far",
                [
                    Vec3::new(-far, far, -far),
                    Vec3::new(far, -far, -far),
                    Vec3::new(far, far, -far),
                ],
                0,
            ),
        ],
        vec![double_sided("grey", Vec3::splat(0.5))],
        camera(0.1),
    );
    let n = 64;
    let px = rasterize(&s, n, n);
    let d = diff(&s, &px);
    eprintln!("diagonal: {d:?}");
    // Every diagonal centre shows the far triangle (id 1) in both rasterizers.
    for i in 0..n as usize {
        let p = &px[i * n as usize + i];
        assert_eq!(
            p.id, 1,
            "pixel ({i}, {i}): id {} depth {} vs {}",
            p.id, p.cr, p.hw
        );
        assert!(
            (p.cr - p.hw).abs() <= DEPTH_TOLERANCE,
            "pixel ({i}, {i}): {} vs {}",
            p.cr,
            p.hw
        );
    }
    assert_eq!(d.covered, d.pixels, "{d:?}");
    assert_matches("diagonal", &d);
}

/// A floor and a wall running from in front of the camera to behind it: their triangles
/// cross the near plane (some vertices behind the camera) and are clipped into up to two
/// each.
#[test]
fn near_plane_crossing_triangles() {
    if !has_atomics() {
        return;
    }
    let mut floor = cuboid(
        "floor",
        Vec3::new(-6.0, -1.5, -30.0),
        Vec3::new(6.0, -1.0, 8.0),
        0,
        false,
    );
    let wall = cuboid(
        "wall",
        Vec3::new(1.0, -1.0, -20.0),
        Vec3::new(1.2, 3.0, 5.0),
        1,
        false,
    );
    floor.name = "floor".into();
    // A far near plane: the viewport's sides alone clip away w < 0, so only geometry
    // between the eye and the near plane shows whether near clipping happens.
    let mut cam = camera(1.5);
    cam.eye = Vec3::new(0.0, 0.2, 0.0);
    cam.target = Vec3::new(0.3, -0.1, -1.0);
    let s = scene(
        vec![floor, wall],
        vec![
            lambert("grey", Vec3::splat(0.5)),
            lambert("orange", Vec3::new(0.9, 0.5, 0.2)),
        ],
        cam,
    );
    // Some vertex lies behind the camera: the case is really exercised.
    let vp = s.camera.projection(333.0 / 197.0) * s.camera.view();
    let behind = s
        .meshes
        .iter()
        .flat_map(|m| &m.positions)
        .filter(|p| (vp * p.extend(1.0)).w < 0.0)
        .count();
    assert!(behind > 0);
    let px = rasterize(&s, 333, 197);
    let d = diff(&s, &px);
    eprintln!("near plane: {d:?}, {behind} vertices behind the camera");
    assert!(d.covered > d.pixels / 3, "{d:?}");
    assert_matches("near plane", &d);
}

/// One triangle far larger than the frame (every pixel, clipped at the viewport's sides,
/// bounding box over BIG_PIXELS: the shared-workgroup dispatch), small boxes in front.
#[test]
fn screen_filling_triangle() {
    if !has_atomics() {
        return;
    }
    let s = scene(
        vec![
            triangle(
                "huge",
                [
                    Vec3::new(-100.0, -100.0, -10.0),
                    Vec3::new(100.0, -100.0, -10.0),
                    Vec3::new(0.0, 200.0, -10.0),
                ],
                0,
            ),
            cuboid(
                "box",
                Vec3::new(-1.0, -1.0, -6.0),
                Vec3::new(0.5, 0.5, -5.0),
                1,
                false,
            ),
        ],
        vec![
            lambert("grey", Vec3::splat(0.5)),
            lambert("orange", Vec3::new(0.9, 0.5, 0.2)),
        ],
        camera(0.1),
    );
    let px = rasterize(&s, 333, 197);
    let d = diff(&s, &px);
    eprintln!("screen filling: {d:?}");
    assert_eq!(d.covered, d.pixels, "{d:?}");
    assert_eq!(px[0].id, 0, "the corner shows the large triangle");
    assert!(px.iter().any(|p| p.id > 0), "the box is in front somewhere");
    assert_matches("screen filling", &d);
}

/// A 4 m square in the plane z = `z` facing +Z or away (-Z).
fn square(name: &str, z: f32, material: usize, facing_camera: bool) -> Mesh {
    let n = if facing_camera { Vec3::Z } else { Vec3::NEG_Z };
    let mut m = Mesh {
        name: name.into(),
        material,
        ..Default::default()
    };
    for (x, y) in [(-2.0, -2.0), (2.0, -2.0), (2.0, 2.0), (-2.0, 2.0)] {
        m.positions.push(Vec3::new(x, y, z));
        m.normals.push(n);
        m.uvs.push(Vec2::ZERO);
        m.tangents.push(Vec3::X.extend(1.0));
    }
    m.indices = if facing_camera {
        vec![0, 1, 2, 0, 2, 3]
    } else {
        vec![0, 2, 1, 0, 3, 2]
    };
    m
}

/// Two double-sided squares in the same place: the one drawn later (larger ids) wins,
/// as LessEqual keeps it (tests/depth_ties.rs). A single-sided square facing away in
/// front of them is culled, as the hardware culls it.
#[test]
fn coincident_triangles_keep_the_later() {
    if !has_atomics() {
        return;
    }
    for second_faces_camera in [true, false] {
        let s = scene(
            vec![
                cuboid(
                    "wall",
                    Vec3::new(-10.0, -10.0, -11.0),
                    Vec3::new(10.0, 10.0, -10.0),
                    0,
                    false,
                ),
                square("red", -5.0, 1, true),
                square("green", -5.0, 2, second_faces_camera),
                square("away", -3.0, 3, false),
            ],
            vec![
                lambert("grey", Vec3::splat(0.5)),
                double_sided("red", Vec3::X),
                double_sided("green", Vec3::Y),
                lambert("single-sided", Vec3::Z),
            ],
            camera(0.1),
        );
        let (w, h) = (64, 36);
        let px = rasterize(&s, w, h);
        let d = diff(&s, &px);
        eprintln!("coincident (second faces the camera: {second_faces_camera}): {d:?}");
        // Ids: the wall 0..12, red 12..14, green 14..16, the away square 16..18.
        let centre = &px[(h / 2 * w + w / 2) as usize];
        assert!(
            (14..16).contains(&centre.id),
            "the centre shows triangle {}, not the green square's",
            centre.id
        );
        let squares = px.iter().filter(|p| (12..16).contains(&p.id)).count();
        assert!(
            squares > 0
                && px
                    .iter()
                    .all(|p| p.id < 12 || (14..16).contains(&p.id) || p.id == NO_TRIANGLE),
            "the red square or the culled one shows"
        );
        assert_matches("coincident", &d);
    }
}

/// The shipped compute-first frame (graphs/visibility_compute_raster.ron): light culling
/// on the compute depth builds the same tile lists as on the hardware prepass
/// (forward_plus.ron), and shading its ids gives the hardware visibility buffer's image
/// (visibility_buffer.ron: same ids, same shading code).
#[test]
fn shipped_graph_matches_the_hardware_visibility_buffer() {
    if !has_atomics() {
        return;
    }
    let s = load("scenes/harada.ron");
    let mut r = renderer();
    let forward = render_file(&mut r, "forward_plus.ron", &s, 333, 197);
    let hardware = render_file(&mut r, "visibility_buffer.ron", &s, 333, 197);
    let frame = render_file(&mut r, "visibility_compute_raster.ron", &s, 333, 197);
    // The same tile lists: each tile's depth range from the compute depth bounds the
    // same lights (all-ones depth, say, would keep more).
    let (lists, reference_lists) = (&frame.culling[0].counts, &forward.culling[0].counts);
    assert_eq!(lists.len(), reference_lists.len());
    let differ = lists
        .iter()
        .zip(reference_lists)
        .filter(|(a, b)| a != b)
        .count();
    eprintln!("{differ} of {} tile lists differ", lists.len());
    assert_eq!(differ, 0);
    assert!(lists.iter().any(|&c| c > 0));
    let (image, reference) = (frame.image, hardware.image);
    assert_eq!(image.len(), reference.len());
    assert_eq!(image.len(), 333 * 197);
    let (worst, at) = max_rel_diff(&image, &reference);
    let lit = reference
        .iter()
        .filter(|p| p[0] + p[1] + p[2] > 0.0)
        .count();
    eprintln!(
        "visibility_compute_raster vs visibility_buffer: worst {worst:e} at {at}, {lit} lit pixels"
    );
    assert!(
        lit > 10_000,
        "only {lit} lit pixels: the comparison tests nothing"
    );
    // Coverage is equal on lavapipe (shipped_scenes_match_the_depth_prepass), so every
    // pixel shades the same triangle with the same code: equal up to the compiler
    // contracting a multiply-add differently (the two pipelines are built alike, so 0
    // is expected; 2e-6 relative is one f32 rounding per light term, as culling_exact.rs).
    assert!(
        worst <= 2e-6,
        "pixel {at}: {:?} vs {:?} ({worst:e})",
        image[at],
        reference[at]
    );
}

/// Alpha-masked materials against the prepass's alpha test (DepthPrepass discards below
/// the cutoff): the textured scene's striped panels (the alpha of a mip-mapped texture,
/// a front face and a double-sided back face) and a panel whose alpha is under the cutoff
/// everywhere, in front of the camera. Coverage as for opaque scenes (`assert_matches`:
/// both rebuild the uv at the pixel centre and pick the mip level from the quad's coarse
/// derivatives, so a cut edge moves only where the filtered alpha is within rounding of
/// the cutoff); the list-full paths (setup's and bin's serial walks) alpha-test alike,
/// bit for bit.
#[test]
fn masked_materials_match_the_prepass_alpha_test() {
    if !has_atomics() {
        return;
    }
    let mut s = textured_scene();
    let striped = s.materials.len() - 1;
    let mut faint = lightgraph::scene::SurfaceMaterial {
        name: "faint".into(),
        alpha_mode: AlphaMode::Mask(0.5),
        ..Default::default()
    };
    faint.base_color.w = 0.2;
    s.materials.push(faint);
    s.meshes.push(quad(
        "faint_panel",
        Vec3::new(0.0, 2.0, -5.0),
        Vec3::X * 1.5,
        Vec3::Y * 1.0,
        s.materials.len() - 1,
    ));
    let (w, h) = (333, 197);
    let (px, report) = rasterize_limited(&s, w, h, "");
    let d = diff(&s, &px);
    eprintln!("masked: {d:?}, {report:?}");
    assert_eq!(report.serial(), 0);
    assert_matches("masked", &d);
    // What the alpha test decides: the panels opaque cover these pixels more.
    let mut solid = s.clone();
    for m in [striped, s.materials.len() - 1] {
        solid.materials[m].alpha_mode = AlphaMode::Opaque;
    }
    let opaque = rasterize(&solid, w, h);
    let cut = bit_differences(&px, &opaque);
    let faint_first = triangles(&s) - 2;
    let kept_faint = px
        .iter()
        .filter(|p| p.id >= faint_first && p.id != NO_TRIANGLE)
        .count();
    let solid_faint = opaque
        .iter()
        .filter(|p| p.id >= faint_first && p.id != NO_TRIANGLE)
        .count();
    let kept_striped = px
        .iter()
        .filter(|p| p.id >= faint_first - 4 && p.id < faint_first)
        .count();
    eprintln!("{cut} pixels cut out; faint panel {kept_faint} of {solid_faint}, striped panels {kept_striped}");
    assert!(
        solid_faint > 1000 && kept_faint == 0,
        "the faint panel is cut out whole"
    );
    assert!(
        cut > solid_faint + 500,
        "the stripes cut pixels out too: {cut}"
    );
    assert!(
        kept_striped > 500,
        "the stripes keep pixels: {kept_striped}"
    );
    for limits in ["records=0", "blocks=40"] {
        let (serial, r) = rasterize_limited(&s, w, h, limits);
        assert!(r.serial() > 0, "{limits}: {r:?}");
        assert_eq!(bit_differences(&serial, &px), 0, "{limits}");
    }
}

/// The triangle ids of material `m`'s meshes: the merged triangles are sorted by
/// material, so one material's form one range.
fn material_triangles(s: &Scene, m: usize) -> std::ops::Range<u32> {
    let count = |keep: &dyn Fn(usize) -> bool| -> u32 {
        s.meshes
            .iter()
            .filter(|mesh| s.materials[mesh.material].alpha_mode != AlphaMode::Blend)
            .filter(|mesh| keep(mesh.material))
            .map(|mesh| mesh.indices.len() as u32 / 3)
            .sum()
    };
    let first = count(&|k| k < m);
    first..first + count(&|k| k == m)
}

/// The textured scene with masked materials that share their code: the striped panels
/// at 70% alpha, the front one cut at 0.5 (stripes kept), the back one at 0.75 (cut out
/// whole); with `flat`, three untextured panels too (alpha 0.2 cut at 0.5, 0.6 at 0.75,
/// 0.6 at 0.5: cut, cut, kept), an opaque material's triangles between the first two.
/// Returns the scene and the masked materials with the pixels each must keep: Some(n),
/// n of the solid panel's; None, some but not all (stripes).
fn shared_masked_scene(flat: bool) -> (Scene, Vec<(usize, Option<bool>)>) {
    let mut s = textured_scene();
    let striped = s.materials.len() - 1;
    s.materials[striped].base_color.w = 0.7;
    let mut striped_high = s.materials[striped].clone();
    striped_high.name = "striped_high".into();
    striped_high.alpha_mode = AlphaMode::Mask(0.75);
    s.materials.push(striped_high);
    let striped_high = s.materials.len() - 1;
    let back = s
        .meshes
        .iter()
        .position(|m| m.name == "panel_back")
        .unwrap();
    s.meshes[back].material = striped_high;
    let mut expected = vec![(striped, None), (striped_high, Some(false))];
    let flats = if flat {
        &[(0.2, 0.5), (0.6, 0.75), (0.6, 0.5)][..]
    } else {
        &[]
    };
    for (i, &(alpha, cutoff)) in flats.iter().enumerate() {
        let mut m = lightgraph::scene::SurfaceMaterial {
            name: format!("flat_{i}"),
            alpha_mode: AlphaMode::Mask(cutoff),
            ..Default::default()
        };
        m.base_color.w = alpha;
        s.materials.push(m);
        expected.push((s.materials.len() - 1, Some(alpha >= cutoff)));
        s.meshes.push(quad(
            &format!("flat_panel_{i}"),
            Vec3::new(-3.0 + 3.0 * i as f32, -0.5, -5.0),
            Vec3::X * 1.2,
            Vec3::Y * 0.8,
            s.materials.len() - 1,
        ));
        if i == 0 {
            // An opaque material between members: the run's triangles are not one range.
            s.materials.push(Default::default());
            s.meshes.push(quad(
                "opaque_between",
                Vec3::new(0.0, -2.0, -7.0),
                Vec3::X * 2.0,
                Vec3::Y * 0.5,
                s.materials.len() - 1,
            ));
        }
    }
    (s, expected)
}

/// Masked materials that differ only in their constants and cutoffs share one run of
/// the rasterizer (one pipeline, their constants read from a buffer), and a scene whose
/// masked materials form one such group has it folded into the opaque run (its triangles
/// flagged for the alpha test there): either way each material must test its own alpha
/// against its own cutoff. Coverage as the prepass's alpha test, which draws each
/// material with its own code; the list-full paths (the flag carried in the records)
/// bit for bit.
#[test]
fn masked_materials_sharing_code_keep_their_own_alpha_and_cutoff() {
    if !has_atomics() {
        return;
    }
    for flat in [true, false] {
        let (s, expected) = shared_masked_scene(flat);
        let what = if flat {
            "two groups"
        } else {
            "one group, folded"
        };
        let (w, h) = (333, 197);
        let (px, report) = rasterize_limited(&s, w, h, "");
        let d = diff(&s, &px);
        eprintln!("{what}: {d:?}, {report:?}");
        assert_eq!(report.serial(), 0);
        assert_matches(what, &d);
        let mut solid = s.clone();
        for m in solid.materials.iter_mut() {
            if m.alpha_mode.is_masked() {
                m.alpha_mode = AlphaMode::Opaque;
            }
        }
        let opaque = rasterize(&solid, w, h);
        let shown = |px: &[Pixel], m: usize| {
            let ids = material_triangles(&s, m);
            px.iter().filter(|p| ids.contains(&p.id)).count()
        };
        for (m, whole) in expected {
            let (kept, of) = (shown(&px, m), shown(&opaque, m));
            let name = &s.materials[m].name;
            eprintln!("{what}: {name} keeps {kept} of {of}");
            assert!(of > 100, "{what}: {name} shows {of} pixels solid");
            match whole {
                Some(true) => assert_eq!(kept, of, "{what}: {name} kept whole"),
                Some(false) => assert_eq!(kept, 0, "{what}: {name} cut out"),
                None => assert!(
                    kept > 500 && kept + 500 < of,
                    "{what}: {name}'s stripes: {kept} of {of}"
                ),
            }
        }
        for limits in ["records=0", "blocks=40"] {
            let (serial, r) = rasterize_limited(&s, w, h, limits);
            assert!(r.serial() > 0, "{what}, {limits}: {r:?}");
            assert_eq!(bit_differences(&serial, &px), 0, "{what}, {limits}");
        }
    }
}

/// A triangle covering the whole viewport behind a field of small triangles (some under
/// a pixel, some single-sided and facing away, many across tile and block borders): the
/// rasterizer (setup's direct paths, tiles, bin, raster) against the hardware prepass,
/// and bit for bit against every triangle rasterized serially by its setup thread
/// (records=0 with the direct paths off: the list-full path, which walks each triangle's
/// box as the one-thread-per-triangle rasterizer did).
#[test]
fn screen_filling_triangle_among_many_small_ones_is_exact() {
    if !has_atomics() {
        return;
    }
    let mut rng = Rng(7);
    let mut small = |name: &str, material: usize| {
        let mut m = Mesh {
            name: name.into(),
            material,
            ..Default::default()
        };
        for i in 0..300u32 {
            let z = rng.range(-9.0, -2.0);
            let centre = rng.vec3(
                Vec3::new(-0.9 * -z, -0.9 * -z, z),
                Vec3::new(0.9 * -z, 0.9 * -z, z),
            );
            // Sizes from a fraction of a pixel to a sixth of the frame.
            let size = -z * 0.3 * rng.f32().powi(3);
            for _ in 0..3 {
                let offset = rng.vec3(Vec3::splat(-size), Vec3::splat(size));
                m.positions.push(centre + offset);
                m.normals.push(Vec3::Z);
                m.uvs.push(Vec2::ZERO);
                m.tangents.push(Vec3::X.extend(1.0));
            }
            m.indices.extend([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        m
    };
    let (two_sided, one_sided) = (small("double-sided", 1), small("single-sided", 2));
    let s = scene(
        vec![
            triangle(
                "huge",
                [
                    Vec3::new(-100.0, -100.0, -10.0),
                    Vec3::new(100.0, -100.0, -10.0),
                    Vec3::new(0.0, 200.0, -10.0),
                ],
                0,
            ),
            two_sided,
            one_sided,
        ],
        vec![
            lambert("grey", Vec3::splat(0.5)),
            double_sided("red", Vec3::X),
            lambert("green", Vec3::Y),
        ],
        camera(0.1),
    );
    for (w, h) in [(333, 197), (480, 270)] {
        let (px, report) = rasterize_limited(&s, w, h, "");
        let d = diff(&s, &px);
        eprintln!("{w}x{h}: {d:?}, {report:?}");
        assert_eq!(d.covered, d.pixels, "{d:?}");
        assert_matches("screen filling among small", &d);
        assert_eq!(report.serial(), 0, "{report:?}");
        // The huge triangle alone lists every tile and block of the frame.
        assert!(
            report.tiles >= w.div_ceil(64) * h.div_ceil(64),
            "{report:?}"
        );
        assert!(report.blocks >= w.div_ceil(8) * h.div_ceil(8), "{report:?}");
        let shown = |lo: u32, hi: u32| px.iter().filter(|p| (lo..hi).contains(&p.id)).count();
        assert!(
            shown(1, 301) > 1000 && shown(301, 601) > 1000,
            "both fields show"
        );
        let (serial, serial_report) = rasterize_limited(&s, w, h, "records=0,direct=0");
        assert!(serial_report.serial_triangles > 300, "{serial_report:?}");
        assert_eq!(bit_differences(&px, &serial), 0);
        // The huge triangle's fan triangles reserve their many tiles with a
        // compare-exchange that stops at the capacity; here it runs out mid-box.
        let (part, part_report) = rasterize_limited(&s, w, h, "tiles=30");
        assert!(part_report.serial_tiles > 0, "{part_report:?}");
        assert_eq!(bit_differences(&px, &part), 0);
    }
}

/// Every list full in turn, and dispatches folded into y: the image is bit for bit the
/// one with room everywhere, and the serial work is counted where it happened.
#[test]
fn full_lists_fall_back_exactly_and_are_counted() {
    if !has_atomics() {
        return;
    }
    let s = load("scenes/harada.ron");
    let (w, h) = (333, 197);
    let (reference, room) = rasterize_limited(&s, w, h, "");
    eprintln!("room everywhere: {room:?}");
    assert_eq!(room.serial(), 0);
    assert!(
        room.records > 100 && room.tiles > 100 && room.blocks > 1000,
        "{room:?}"
    );
    // Bin and raster fold thousands of workgroups into rows of 3 under "groups=3";
    // clear and setup too.
    for limits in [
        "records=0",
        "records=100",
        "tiles=40",
        "blocks=300",
        "groups=3",
    ] {
        let (px, r) = rasterize_limited(&s, w, h, limits);
        eprintln!("{limits}: {r:?}");
        let counted = match limits {
            // Every fan triangle that had a record with room is drawn by its setup thread.
            "records=0" => r.serial_triangles == room.records && r.records == 0,
            "records=100" => r.serial_triangles == room.records - 100 && r.records == 100,
            "tiles=40" => r.serial_triangles == 0 && r.serial_tiles > 0 && r.tiles == 40,
            "blocks=300" => {
                r.serial_triangles + r.serial_tiles == 0 && r.serial_blocks > 0 && r.blocks == 300
            }
            _ => r.serial() == 0 && r.blocks == room.blocks,
        };
        assert!(counted, "{limits}: {r:?}");
        assert_eq!(bit_differences(&px, &reference), 0, "{limits}");
    }
}

/// One frame of `graph` (text) for `scene` at `width`×`height`: the result, and the bits
/// of each texture in `read` (depths and ids, compared exactly).
fn render_reading(
    graph: &str,
    scene: &Scene,
    (width, height): (u32, u32),
    read: &[&str],
) -> (lightgraph::render::FrameResult, Vec<Vec<u32>>) {
    let mut r = renderer();
    let checked = graph::check_text(Path::new("<test>"), graph, &ShaderLibrary::builtin())
        .expect("valid graph");
    let size = FrameSize {
        width,
        height,
        lights: scene.lights.len() as u32,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, scene).expect("materials");
    let prepared = r
        .prepare(compiled, scene, &gpu, size, false)
        .expect("prepare");
    let result = prepared.render(&r).expect("render");
    let bits = read
        .iter()
        .map(|name| prepared.read_texture_bits(&r, name).expect("readback"))
        .collect();
    (result, bits)
}

/// The shipped compute-only graph (R32Float depth, compute resolve) and the same graph
/// with a Depth32Float depth (the full-screen draw resolve).
fn shipped_graph_both_resolves() -> (String, String) {
    let compute = std::fs::read_to_string(graph_path("visibility_compute_raster.ron")).unwrap();
    let float = r#"Texture(name: "depth", format: R32Float, size: Output)"#;
    assert!(
        compute.contains(float),
        "the shipped graph's depth is R32Float"
    );
    let draw = compute.replace(
        float,
        r#"Texture(name: "depth", format: Depth32Float, size: Output)"#,
    );
    (compute, draw)
}

/// The compute resolve writes exactly what the draw resolve writes: every depth's bits
/// and every id, covered pixels and empty ones (1.0 and NO_TRIANGLE) alike; so culling and
/// shading on either agree exactly too.
#[test]
fn compute_resolve_equals_the_draw_resolve_bit_for_bit() {
    if !has_atomics() {
        return;
    }
    let (compute, draw) = shipped_graph_both_resolves();
    // harada from its camera, and looking up past its walls: pixels nothing covers.
    let mut sky = load("scenes/harada.ron");
    sky.camera.target += Vec3::new(0.0, 6.0, 0.0);
    for (what, scene) in [("harada", load("scenes/harada.ron")), ("harada, sky", sky)] {
        let (a, a_bits) = render_reading(&compute, &scene, (333, 197), &["depth", "visibility"]);
        let (b, b_bits) = render_reading(&draw, &scene, (333, 197), &["depth", "visibility"]);
        let (depth, ids) = (&a_bits[0], &a_bits[1]);
        assert_eq!(depth.len(), 333 * 197);
        assert_eq!(ids.len(), 333 * 197);
        let empty: Vec<u32> = ids
            .iter()
            .zip(depth)
            .filter(|(&id, _)| id == NO_TRIANGLE)
            .map(|(_, &d)| d)
            .collect();
        eprintln!("{what}: {} of {} pixels empty", empty.len(), ids.len());
        assert!(ids.len() - empty.len() > 1000, "{what}: few pixels covered");
        if what.ends_with("sky") {
            assert!(
                empty.len() > 1000,
                "{what}: no sky: the empty case is untested"
            );
        }
        assert!(
            empty.iter().all(|&d| d == 1f32.to_bits()),
            "{what}: an empty pixel's depth is not 1.0"
        );
        let differ = |x: &[u32], y: &[u32]| x.iter().zip(y).filter(|(p, q)| p != q).count();
        assert_eq!(differ(depth, &b_bits[0]), 0, "{what}: depth bits differ");
        assert_eq!(differ(ids, &b_bits[1]), 0, "{what}: ids differ");
        assert_eq!(
            a.culling[0].counts, b.culling[0].counts,
            "{what}: tile lists"
        );
        assert_eq!(a.image.len(), b.image.len());
        assert!(a.image == b.image, "{what}: images differ");
    }
}

/// Every culling variant and list layout the shaded graphs use builds the same lists on
/// the R32Float depth (`FLOAT_DEPTH`) as on the Depth32Float one: the depths are the same
/// bits, so any difference is the variant reading the float texture wrongly.
#[test]
fn culling_variants_read_the_r32float_depth_alike() {
    if !has_atomics() {
        return;
    }
    let (compute, draw) = shipped_graph_both_resolves();
    let scene = pillar_scene(64);
    for kind in [
        "LightCulling(tile: 16, variant: Frustum, lists: Compact(max_indices: 16777216))",
        "LightCulling(tile: 16, variant: HalfZ, lists: Compact(max_indices: 16777216), coarse: 0)",
        "LightCulling(tile: 8, variant: DepthMask, capacity: 256, coarse: 4)",
        "LightCulling(tile: 16, variant: Clustered(slices: 16), capacity: 128, coarse: 0)",
        "LightCulling(tile: 16, variant: Frustum, capacity: 256, coarse: 4)",
    ] {
        let (a, _) = render_reading(&with_culling(&compute, kind), &scene, (200, 120), &[]);
        let (b, _) = render_reading(&with_culling(&draw, kind), &scene, (200, 120), &[]);
        let (la, lb) = (&a.culling[0], &b.culling[0]);
        eprintln!("{kind}: {} lights listed", la.listed());
        assert!(
            la.listed() > 0,
            "{kind}: no lights listed: nothing compared"
        );
        assert_eq!(la.counts, lb.counts, "{kind}: lists differ");
        assert_eq!(la.overflowed_lists, lb.overflowed_lists, "{kind}");
        assert!(a.image == b.image, "{kind}: images differ");
    }
}

/// A light linked list built on the R32Float depth equals one built on the Depth32Float.
#[test]
fn light_linked_list_reads_the_r32float_depth_alike() {
    if !has_atomics() {
        return;
    }
    let (compute, draw) = shipped_graph_both_resolves();
    let linked = |graph: &str| {
        graph
            .replace(
                r#"Buffer(name: "light_lists", size: Auto),"#,
                r#"Buffer(name: "light_lists", size: Auto), Buffer(name: "light_links", size: Auto),"#,
            )
            .replace(
                r#"reads: ["visibility", "vertices", "triangles", "material_triangles", "light_geometry", "light_properties", "light_lists"],"#,
                r#"reads: ["visibility", "vertices", "triangles", "material_triangles", "light_geometry", "light_properties", "light_links"],"#,
            )
            .replace(
                r#"Pass(
            name: "visibility_shading","#,
                r#"Pass(name: "links", kind: LightLinkedList(scale: 2, links_per_pixel: 32), reads: ["depth", "light_geometry", "light_lists"], writes: ["light_links"]),
        Pass(
            name: "visibility_shading","#,
            )
    };
    let (compute, draw) = (linked(&compute), linked(&draw));
    assert!(compute.contains("LightLinkedList") && compute.contains(r#""light_links"],"#));
    let scene = pillar_scene(64);
    let (a, _) = render_reading(&compute, &scene, (200, 120), &[]);
    let (b, _) = render_reading(&draw, &scene, (200, 120), &[]);
    let (la, lb) = (&a.links[0], &b.links[0]);
    eprintln!("linked list: {} links", la.links());
    assert!(la.links() > 0, "no links: nothing compared");
    assert_eq!(la, lb);
    assert!(a.image == b.image, "images differ");
}
