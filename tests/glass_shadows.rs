//! Glass and shadows on the real adapter (lavapipe on CI), against CPU answers:
//! - a pane of glass between a casting light and a floor leaves the floor lit in every
//!   shadow graph (ray-cast and atlas): the image equals the scene without the pane;
//! - with `blended_cast_shadows` the pane casts again: the floor is black exactly where
//!   the segment to the light crosses the pane (edge pixels counted and left out);
//! - glass receives the shadow of an opaque box between a casting light and the pane: a
//!   pane pixel is black exactly where an f64 ray from it to the light hits the box, and
//!   elsewhere keeps the light of the scene without the box (glass tracing rays, and
//!   glass sampling the atlas beyond its blur; over Forward+, tiled deferred and the
//!   compute-first frame); a pane that casts too is unchanged;
//! - the BVH leaves a glTF model's blended meshes out unless its model opts in, and every
//!   triangle it keeps names its own scene triangle.

mod common;

use common::{graph_text, lambert, render_text_with, renderer};
use glam::{DMat4, DVec3, DVec4, Vec2, Vec3};
use lightgraph::render::{FrameResult, Renderer};
use lightgraph::scene::geometry::MeshBuilder;
use lightgraph::scene::{light_flags, AlphaMode, Camera, Light, Scene};
use lightgraph::shadow::atlas::GUARD_TEXELS;
use lightgraph::shadow::reference::near_edge;
use lightgraph::shadow::{occluded_reference, scene_triangles_f64, shadow_ray, ShadowBvh};
use std::path::Path;

const W: u32 = 96;
const H: u32 = 64;
/// Shaders' SHADOW_NORMAL_OFFSET default (ShadowRayCast's normal_offset).
const OFFSET: f32 = 1e-4;

/// Every graph that shadows opaque surfaces, each with its way of shadowing.
const RAY_GRAPHS: [&str; 4] = [
    "raycast_shadows.ron",
    "tiled_deferred_raycast_shadows.ron",
    "raycast_shadows_naive.ron",
    "transparent_raycast_shadows.ron",
];
const ATLAS_GRAPHS: [&str; 3] = [
    "shadow_atlas.ron",
    "tiled_deferred_shadow_atlas.ron",
    "transparent_shadow_atlas.ron",
];

fn render(r: &mut Renderer, graph: &str, scene: &Scene) -> Vec<[f32; 4]> {
    render_result(r, graph, scene).image
}

/// The frame, atlas graphs with their tiles 16× the size on screen (a 96×64 frame
/// would get a coarse 64-texel tile).
fn render_result(r: &mut Renderer, graph: &str, scene: &Scene) -> FrameResult {
    let text = graph_text(graph).replace("importance: 1.0", "importance: 16.0");
    let result = render_text_with(r, &text, scene, W, H, false);
    assert_eq!(result.image.len(), (W * H) as usize, "{graph}: image size");
    result
}

fn caster(position: Vec3) -> Light {
    let mut l = Light::point(position, 30.0, Vec3::ONE, 5.0);
    l.flags |= light_flags::CASTS_SHADOW;
    l
}

/// A horizontal square at height `y`, half-side `half`, facing up.
fn square(name: &str, material: usize, y: f32, half: f32) -> lightgraph::scene::Mesh {
    let mut m = MeshBuilder::new(name, material);
    m.quad(
        Vec3::new(-half, y, -half),
        Vec3::new(0.0, 0.0, 2.0 * half),
        Vec3::new(2.0 * half, 0.0, 0.0),
        Vec2::ONE,
    );
    m.build()
}

/// The camera ray through a pixel's centre, in f64: (origin on the near plane, direction).
fn pixel_ray(camera: &Camera, pixel: u32) -> (DVec3, DVec3) {
    let (px, py) = (pixel % W, pixel / W);
    let view_proj = camera.projection(W as f32 / H as f32).as_dmat4() * camera.view().as_dmat4();
    let inv: DMat4 = view_proj.inverse();
    let ndc = |z: f64| {
        DVec4::new(
            (px as f64 + 0.5) / W as f64 * 2.0 - 1.0,
            1.0 - (py as f64 + 0.5) / H as f64 * 2.0,
            z,
            1.0,
        )
    };
    let unproject = |v: DVec4| {
        let p = inv * v;
        p.truncate() / p.w
    };
    let near = unproject(ndc(0.0));
    (near, unproject(ndc(1.0)) - near)
}

/// Where a pixel's camera ray meets the plane y = `height`.
fn on_plane(camera: &Camera, pixel: u32, height: f64) -> Option<DVec3> {
    let (o, d) = pixel_ray(camera, pixel);
    let t = (height - o.y) / d.y;
    (t > 0.0 && t <= 1.0).then(|| o + d * t)
}

/// Whether a world point lies inside the camera's view.
fn in_view(camera: &Camera, p: Vec3) -> bool {
    let clip = camera.projection(W as f32 / H as f32) * camera.view() * p.extend(1.0);
    let n = clip.truncate() / clip.w;
    clip.w > 0.0 && n.x.abs() <= 1.0 && n.y.abs() <= 1.0
}

fn is_black(c: [f32; 4]) -> bool {
    c[..3] == [0.0; 3]
}

const PANE_Y: f32 = 2.0;
const PANE_HALF: f32 = 0.4;
const FLOOR_LIGHT: Vec3 = Vec3::new(0.3, 3.0, 0.2);

/// A floor under a glass pane under a casting light; the camera looks at the floor below
/// the pane, which stays above the view (so graphs that draw glass and graphs that do
/// not show the same floor). `pane: false` leaves the pane out.
fn pane_over_floor(pane: bool, pane_casts: bool) -> Scene {
    let mut meshes = vec![square("floor", 0, 0.0, 4.0)];
    if pane {
        let mut p = square("pane", 1, PANE_Y, PANE_HALF);
        p.blended_casts_shadow = pane_casts;
        meshes.push(p);
    }
    let scene = Scene {
        name: "pane over floor".into(),
        meshes,
        materials: vec![
            lambert("floor", Vec3::splat(0.8)),
            common::glass::pale_glass(),
        ],
        lights: vec![caster(FLOOR_LIGHT)],
        camera: Camera {
            eye: Vec3::new(0.0, 1.0, 3.0),
            target: Vec3::new(-0.5, 0.0, -0.4),
            fov_y: 40f32.to_radians(),
            ..Default::default()
        },
        ..Default::default()
    };
    for x in [-PANE_HALF, PANE_HALF] {
        for z in [-PANE_HALF, PANE_HALF] {
            let corner = Vec3::new(x, PANE_Y, z);
            assert!(
                !in_view(&scene.camera, corner),
                "pane corner {corner} in view"
            );
        }
    }
    scene
}

/// Where a floor pixel lies in the pane's shadow.
#[derive(Clone, Copy, Debug, PartialEq)]
enum PaneShadow {
    /// The segment from the floor point to the light crosses the pane, further than the
    /// margin (in the pane's plane) inside its edges.
    Inside,
    /// It passes as far outside.
    Outside,
    /// Within the margin of an edge.
    Edge,
}

/// A floor pixel's [`PaneShadow`]; None off the floor.
fn pane_shadow(camera: &Camera, pixel: u32, margin: f64) -> Option<PaneShadow> {
    let p = on_plane(camera, pixel, 0.0)?;
    if p.x.abs() > 4.0 || p.z.abs() > 4.0 {
        return None;
    }
    let l = FLOOR_LIGHT.as_dvec3();
    let q = p + (l - p) * ((PANE_Y as f64 - p.y) / (l.y - p.y));
    let half = PANE_HALF as f64;
    let edge = (half - q.x.abs()).abs().min((half - q.z.abs()).abs());
    Some(if edge < margin {
        PaneShadow::Edge
    } else if q.x.abs() < half && q.z.abs() < half {
        PaneShadow::Inside
    } else {
        PaneShadow::Outside
    })
}

#[test]
fn glass_leaves_the_floor_lit_in_every_shadow_graph() {
    let mut r = renderer();
    let with = pane_over_floor(true, false);
    let without = pane_over_floor(false, false);
    for graph in RAY_GRAPHS.iter().chain(&ATLAS_GRAPHS) {
        let a = render(&mut r, graph, &with);
        let b = render(&mut r, graph, &without);
        // Where an opaque pane would cast (well inside, 0.05 in its plane: past any
        // filter's reach), the floor keeps its light.
        let under: Vec<u32> = (0..W * H)
            .filter(|&i| pane_shadow(&with.camera, i, 0.05) == Some(PaneShadow::Inside))
            .collect();
        assert!(
            under.len() > 100,
            "{graph}: {} floor pixels under the pane",
            under.len()
        );
        let dark = under.iter().filter(|&&i| is_black(a[i as usize])).count();
        assert_eq!(
            dark,
            0,
            "{graph}: {dark} of {} floor pixels under the glass are black",
            under.len()
        );
        // Exactly the floor of the scene without the pane: glass blocks nothing.
        let differing = (0..a.len()).filter(|&i| a[i] != b[i]).count();
        assert_eq!(
            differing, 0,
            "{graph}: {differing} pixels differ from the scene without the pane"
        );
    }
}

#[test]
fn an_opted_in_pane_casts_again() {
    let mut r = renderer();
    let casting = pane_over_floor(true, true);
    let without = pane_over_floor(false, false);
    for graph in RAY_GRAPHS.iter().chain(&ATLAS_GRAPHS) {
        let shadowed_frame = render_result(&mut r, graph, &casting);
        let a = &shadowed_frame.image;
        let b = render(&mut r, graph, &without);
        // Ray-cast shadows are exact: 1e-3 in the pane's plane is far above the f32
        // error of a floor position (about 1e-6) carried up to the pane. The atlas
        // blurs: 5×5 taps (2.5 texels), each a 2×2 comparison (1 texel), the floor moved
        // 1.5 texels along its normal: 6 texels of the light's -Y face, which the pane
        // (1 below the light, in the face's plane) fills.
        let margin = match shadowed_frame.atlases.first() {
            None => 1e-3,
            Some(atlas) => {
                assert_eq!(atlas.shadowed.len(), 1, "{graph}: {atlas:?}");
                let inner = (atlas.shadowed[0].tile - 2 * GUARD_TEXELS) as f64;
                let texel = 2.0 * (FLOOR_LIGHT.y - PANE_Y) as f64 / inner;
                6.0 * texel
            }
        };
        let (mut shadowed, mut lit, mut edge) = (0, 0, 0);
        for i in 0..W * H {
            let (got, open) = (a[i as usize], b[i as usize]);
            match pane_shadow(&casting.camera, i, margin) {
                None => continue,
                Some(PaneShadow::Edge) => edge += 1,
                Some(PaneShadow::Inside) => {
                    shadowed += 1;
                    assert!(is_black(got), "{graph}: pixel {i} should be in the pane's shadow: {got:?} (open {open:?})");
                }
                Some(PaneShadow::Outside) => {
                    lit += 1;
                    // No ambient and one light: a lit pixel keeps all of it.
                    assert_eq!(got, open, "{graph}: pixel {i} outside the pane's shadow");
                    assert!(!is_black(got), "{graph}: pixel {i} unlit");
                }
            }
        }
        eprintln!("{graph}: {shadowed} shadowed, {lit} lit, {edge} near the shadow's edge");
        assert!(
            shadowed > 100 && lit > 1000,
            "{graph}: {shadowed} shadowed, {lit} lit"
        );
    }
}

const BOX_LIGHT: Vec3 = Vec3::new(-3.0, 2.0, 0.0);

/// A glass pane (y = 0, half-side 1) seen from above, lit from the side by a casting
/// light, with an opaque box between them outside the view; no floor, so behind the
/// glass is the cleared (black) frame. `occluder: false` leaves the box out.
fn box_over_pane(occluder: bool, pane_casts: bool) -> Scene {
    let mut pane = square("pane", 1, 0.0, 1.0);
    pane.blended_casts_shadow = pane_casts;
    let mut meshes = vec![pane];
    if occluder {
        let mut b = MeshBuilder::new("box", 0);
        b.cuboid(Vec3::new(-1.8, 0.9, -0.3), Vec3::new(-1.4, 1.4, 0.3));
        meshes.push(b.build());
    }
    Scene {
        name: "box over pane".into(),
        meshes,
        materials: vec![
            lambert("box", Vec3::splat(0.8)),
            common::glass::pale_glass(),
        ],
        lights: vec![caster(BOX_LIGHT)],
        camera: Camera {
            eye: Vec3::new(0.0, 4.0, 1.5),
            target: Vec3::ZERO,
            fov_y: 30f32.to_radians(),
            ..Default::default()
        },
        ..Default::default()
    }
}

#[test]
fn glass_shows_the_shadow_of_a_box() {
    let mut r = renderer();
    let scene = box_over_pane(true, false);
    let open_scene = box_over_pane(false, false);
    let casting = box_over_pane(true, true);
    let box_tris = scene_triangles_f64(&Scene {
        meshes: vec![scene.meshes[1].clone()],
        ..scene.clone()
    });
    assert_eq!(box_tris.len(), 12);
    let graphs = [
        "transparent_raycast_shadows.ron",
        "tiled_deferred_raycast_shadows.ron",
        "default.ron",
        "transparent_shadow_atlas.ron",
        "tiled_deferred_shadow_atlas.ron",
    ];
    for graph in graphs {
        let frame = render_result(&mut r, graph, &scene);
        let a = &frame.image;
        let open = render(&mut r, graph, &open_scene);
        // The atlas blurs over 6 texels (5×5 taps, each a 2×2 comparison, the pane
        // point moved 1.5 texels along its normal) of the light's +X face, whose texel
        // at the pane (at most 4 along the axis) is 2 × 4 / inner, doubled for the slant
        // off the axis: that far on the pane from the CPU shadow's border is undecided.
        let blur = frame.atlases.first().map(|atlas| {
            assert_eq!(atlas.shadowed.len(), 1, "{graph}: {atlas:?}");
            let inner = (atlas.shadowed[0].tile - 2 * GUARD_TEXELS) as f64;
            6.0 * 2.0 * (2.0 * 4.0 / inner)
        });
        let (mut shadowed, mut lit, mut edge) = (0, 0, 0);
        for i in 0..W * H {
            let Some(p) = on_plane(&scene.camera, i, 0.0) else {
                continue;
            };
            // Pixel centres within 1e-3 of the pane's border may fall either side of it.
            if (1.0 - p.x.abs()).abs().min((1.0 - p.z.abs()).abs()) < 1e-3 {
                continue;
            }
            if p.x.abs() > 1.0 || p.z.abs() > 1.0 {
                continue;
            }
            let (eye_o, eye_d) = pixel_ray(&scene.camera, i);
            let eye_t = (p - eye_o).length() / eye_d.length();
            assert!(
                !occluded_reference(&box_tris, eye_o, eye_d, eye_t),
                "the box hides pane pixel {i}"
            );
            // The ray every tracer casts from the glass (its face normal, +Y, faces the
            // eye).
            let ray = |p: DVec3| {
                let (o, d, t) = shadow_ray(p.as_vec3(), Vec3::Y, BOX_LIGHT, OFFSET);
                (o.as_dvec3(), d.as_dvec3(), t as f64)
            };
            let (o, d, t) = ray(p);
            let hidden = occluded_reference(&box_tris, o, d, t);
            let undecided = match blur {
                // Rays are exact: 1e-3 of a box edge is far above the f32 error of the
                // GPU's interpolated position (about 1e-6).
                None => near_edge(&box_tris, o, d, t, 1e-3),
                // The shadow is convex: p is `blur` inside or outside it when the eight
                // points around p at that distance on the pane agree with p.
                Some(m) => (-1..=1)
                    .flat_map(|x| (-1..=1).map(move |z| (x, z)))
                    .any(|(x, z)| {
                        let (o, d, t) = ray(p + DVec3::new(x as f64, 0.0, z as f64) * m);
                        occluded_reference(&box_tris, o, d, t) != hidden
                    }),
            };
            if undecided {
                edge += 1;
                continue;
            }
            let got = a[i as usize];
            if hidden {
                shadowed += 1;
                assert!(
                    is_black(got),
                    "{graph}: pane pixel {i} at {p} is in the box's shadow: {got:?}"
                );
            } else {
                lit += 1;
                assert_eq!(
                    got, open[i as usize],
                    "{graph}: pane pixel {i} at {p} sees the light"
                );
                assert!(!is_black(got), "{graph}: pane pixel {i} unlit");
            }
        }
        eprintln!("{graph}: pane {shadowed} shadowed, {lit} lit, {edge} on the shadow's edge");
        assert!(
            shadowed > 200 && lit > 200,
            "{graph}: {shadowed} shadowed, {lit} lit"
        );
        // The edge is a line across the pane: a thin band of its pixels (wider where the
        // atlas blurs it).
        let band = if frame.atlases.is_empty() { 10 } else { 2 };
        assert!(edge * band < shadowed + lit, "{graph}: {edge} edge pixels");
        // A pane that casts too does not shadow itself: its rays leave it on the eye's side.
        let self_casting = render(&mut r, graph, &casting);
        let differing = (0..a.len()).filter(|&i| a[i] != self_casting[i]).count();
        assert_eq!(
            differing, 0,
            "{graph}: a casting pane changes {differing} pixels"
        );
    }
}

/// A scene file placing the Khronos AlphaBlendModeTest model (opaque, masked and blended
/// meshes), with or without its glass casting.
fn alpha_modes(dir: &Path, casts: bool) -> Scene {
    let model = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/assets/khronos/AlphaBlendModeTest/AlphaBlendModeTest.gltf");
    let file = dir.join(format!("alpha_modes_{casts}.ron"));
    std::fs::write(
        &file,
        format!(
            "Scene(models: [(path: {:?}, blended_cast_shadows: {casts})])",
            model.display().to_string()
        ),
    )
    .unwrap();
    lightgraph::scene::load(&file).expect("scene loads").scene
}

#[test]
fn the_bvh_leaves_glass_out_unless_its_model_opts_in() {
    let dir = tempfile::tempdir().unwrap();
    for casts in [false, true] {
        let scene = alpha_modes(dir.path(), casts);
        let blended: usize = scene
            .meshes
            .iter()
            .filter(|m| scene.materials[m.material].alpha_mode == AlphaMode::Blend)
            .map(|m| m.indices.len() / 3)
            .sum();
        assert!(blended > 0 && blended < scene.triangle_count());
        let bvh = ShadowBvh::build(&scene).unwrap();
        let s = bvh.stats;
        assert_eq!(s.input_triangles, scene.triangle_count());
        assert_eq!(s.left_out_non_casting, if casts { 0 } else { blended });
        let skipped = s.skipped_degenerate + s.skipped_non_finite + s.skipped_bad_index;
        assert_eq!(
            s.triangles + skipped + s.left_out_non_casting,
            s.input_triangles
        );
        // Each kept triangle's id is its scene index: meshes in order, triangles in
        // index order, left-out meshes counted.
        let mut by_id = Vec::new();
        for (mesh, m) in scene.meshes.iter().enumerate() {
            for t in m.indices.chunks_exact(3) {
                by_id.push((mesh, [t[0], t[1], t[2]].map(|i| m.positions[i as usize])));
            }
        }
        let mut blended_kept = 0;
        for t in &bvh.triangles[..s.triangles] {
            let (mesh, [p0, p1, p2]) = by_id[t.id as usize];
            assert!(
                scene.casts_shadow(&scene.meshes[mesh]),
                "triangle {} of a mesh that casts none",
                t.id
            );
            assert_eq!(
                (t.v0, t.e1, t.e2),
                (p0.into(), (p1 - p0).into(), (p2 - p0).into()),
                "triangle {}",
                t.id
            );
            let m = &scene.meshes[mesh];
            blended_kept += (scene.materials[m.material].alpha_mode == AlphaMode::Blend) as usize;
        }
        assert_eq!(blended_kept, if casts { blended } else { 0 });
        assert!(scene.meshes.iter().all(|m| m.blended_casts_shadow == casts));
    }
}
