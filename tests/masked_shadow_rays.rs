//! Ray-cast shadows of alpha-masked casters, on the real adapter (lavapipe on CI): a quad
//! textured with alpha stripes (255 and 20, cut at 0.5) over a floor under one casting
//! point light. Every floor pixel's shadow, in every graph that traces rays (jobs from
//! the G-buffer, from the visibility buffer, rays in the light loop, Forward+, tiled
//! deferred, the compute-first frame and stochastic light sampling), equals the stripes projected from the light
//! (computed here from the texture's stripe layout, not by the shaders' code), except
//! pixels whose projection lies within a texel and a half of a stripe's or the quad's
//! edge (counted). The CPU twin (`ShadowBvh::occluded`) agrees on the same pixels.

mod common;

use common::textured::push_striped_quad;
use common::{graph_text, lambert, prepare_text, renderer};
use glam::{DVec3, Vec3};
use lightgraph::scene::geometry::MeshBuilder;
use lightgraph::scene::{light_flags, Camera, Light, Scene};
use lightgraph::shadow::{shadow_ray, ShadowBvh};

const W: u32 = 128;
const H: u32 = 96;
/// Shaders' SHADOW_NORMAL_OFFSET default (ShadowRayCast's normal_offset).
const OFFSET: f32 = 1e-4;
const LIGHT: Vec3 = Vec3::new(0.3, 3.0, 0.2);
/// The striped quad: centre, half extents along x and along −z (uv over [0, 2]²).
const QUAD_Y: f64 = 1.0;
const HALF: f64 = 0.8;
/// The stripes texture's width in texels (`common::textured::checker`, 64 a side).
const TEXELS: f64 = 64.0;

fn scene(masked: bool) -> Scene {
    let mut floor = MeshBuilder::new("floor", 0);
    floor.quad(
        Vec3::new(-4.0, 0.0, 4.0),
        Vec3::new(8.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -8.0),
        glam::Vec2::ONE,
    );
    let mut light = Light::point(LIGHT, 30.0, Vec3::ONE, 5.0);
    light.flags |= light_flags::CASTS_SHADOW;
    let mut s = Scene {
        name: "striped quad over a floor".into(),
        meshes: vec![floor.build()],
        materials: vec![lambert("floor", Vec3::splat(0.8))],
        lights: vec![light],
        camera: Camera {
            eye: Vec3::new(0.0, 5.0, 2.5),
            target: Vec3::new(0.0, 0.0, 0.0),
            ..Default::default()
        },
        ..Default::default()
    };
    push_striped_quad(
        &mut s,
        "stripes",
        Vec3::new(0.0, QUAD_Y as f32, 0.0),
        Vec3::new(HALF as f32, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -HALF as f32),
        !masked,
    );
    s
}

/// Where the floor point `p` sees the light through the quad's plane: Some(shadowed) or
/// None within 1.5 texels of a stripe's edge or 1e-3 m of the quad's. The stripes are
/// `checker`'s alpha: texel column x is opaque where ⌊4x / 64⌋ is even.
fn expected(p: DVec3) -> Option<bool> {
    let l = LIGHT.as_dvec3();
    let q = p + (l - p) * ((QUAD_Y - p.y) / (l.y - p.y));
    let (a, b) = (q.x / HALF, -q.z / HALF);
    let edge = (1.0 - a.abs()).abs().min((1.0 - b.abs()).abs()) * HALF;
    if edge < 1e-3 {
        return None;
    }
    if a.abs() > 1.0 || b.abs() > 1.0 {
        return Some(false);
    }
    let x = (a + 1.0).fract() * TEXELS;
    let stripe = TEXELS / 4.0;
    let from_edge = (x / stripe - (x / stripe).round()).abs() * stripe;
    if from_edge < 1.5 {
        return None;
    }
    Some(((x / stripe).floor() as u32).is_multiple_of(2))
}

/// The floor's world positions per pixel (None off the floor), from the G-buffer of
/// raycast_shadows.ron made the output (its shading pass left out: the frame's colour
/// texture reuses the G-buffer's).
fn floor_positions(r: &mut lightgraph::render::Renderer, s: &Scene) -> Vec<Option<DVec3>> {
    let full = graph_text("raycast_shadows.ron");
    let start = full
        .find("        Pass(\n            name: \"forward_shading\"")
        .expect("shading pass");
    let end = start + full[start..].find("        ),\n").unwrap() + "        ),\n".len();
    let text = format!("{}{}", &full[..start], &full[end..]).replace(
        "output: \"hdr\",",
        "output: \"g_position\",\n    side_effects: [\"shadow_ray_cast\"],",
    );
    let prepared = prepare_text(r, &text, s, W, H, false).expect("prepare");
    prepared.render(r).expect("render");
    let g = prepared.read_texture(r, "g_position").unwrap();
    g.iter()
        .map(|g| {
            (g[3] >= 0.0 && g[1].abs() < 1e-3)
                .then(|| DVec3::new(g[0] as f64, g[1] as f64, g[2] as f64))
        })
        .collect()
}

#[test]
fn masked_casters_shadow_only_where_their_alpha_is_kept_in_every_tracer() {
    let mut r = renderer();
    let s = scene(true);
    let floor = floor_positions(&mut r, &s);
    // The CPU twin on the floor's rays.
    let bvh = ShadowBvh::build(&s).unwrap();
    assert!(
        bvh.alpha.records() == 2,
        "the quad's two triangles alpha-test"
    );
    let (mut shadowed, mut lit, mut ambiguous) = (0, 0, 0);
    for (pixel, p) in floor.iter().enumerate() {
        let Some(p) = p else { continue };
        let Some(hidden) = expected(*p) else {
            ambiguous += 1;
            continue;
        };
        let (o, dir, t_max) = shadow_ray(p.as_vec3(), Vec3::Y, LIGHT, OFFSET);
        assert_eq!(
            bvh.occluded(o, dir, t_max),
            hidden,
            "CPU twin at pixel {pixel}"
        );
        if hidden {
            shadowed += 1;
        } else {
            lit += 1;
        }
    }
    eprintln!("floor: {shadowed} shadowed, {lit} lit, {ambiguous} by an edge");
    assert!(
        shadowed > 150 && lit > 2000,
        "{shadowed} shadowed, {lit} lit"
    );
    for graph in [
        "raycast_shadows.ron",
        "raycast_shadows_naive.ron",
        "tiled_deferred_raycast_shadows.ron",
        "transparent_raycast_shadows.ron",
        "visibility_raycast_shadows.ron",
        "visibility_raycast_shadows_naive.ron",
        "default.ron",
        "visibility_stochastic_shadows.ron",
    ] {
        let prepared = prepare_text(&mut r, &graph_text(graph), &s, W, H, false)
            .unwrap_or_else(|e| panic!("{graph}: {e}"));
        let image = prepared.render(&r).expect("render").image;
        assert_eq!(image.len(), (W * H) as usize, "{graph}: image size");
        let mut wrong = Vec::new();
        for (pixel, p) in floor.iter().enumerate() {
            let Some(hidden) = p.and_then(expected) else {
                continue;
            };
            // No ambient light: a shadowed floor pixel is black, a lit one is not.
            if (image[pixel][0] == 0.0) != hidden {
                wrong.push(pixel);
            }
        }
        assert!(
            wrong.is_empty(),
            "{graph}: {} floor pixels shadowed against the stripes, first {:?}",
            wrong.len(),
            &wrong[..wrong.len().min(8)]
        );
    }
}

#[test]
fn the_same_quad_opaque_shadows_its_whole_square() {
    // What the stripes are cut from: without the mask every ray through the square is
    // blocked, so the test above can tell a mask from none.
    let mut r = renderer();
    let s = scene(false);
    let floor = floor_positions(&mut r, &s);
    let bvh = ShadowBvh::build(&s).unwrap();
    assert_eq!(bvh.alpha.records(), 0);
    let prepared = prepare_text(&mut r, &graph_text("default.ron"), &s, W, H, false).unwrap();
    let image = prepared.render(&r).expect("render").image;
    let mut through_cut_outs = 0;
    for (pixel, p) in floor.iter().enumerate() {
        if let (Some(p), Some(false)) = (p, p.and_then(expected)) {
            let l = LIGHT.as_dvec3();
            let q = *p + (l - *p) * ((QUAD_Y - p.y) / (l.y - p.y));
            if q.x.abs() < HALF && q.z.abs() < HALF {
                assert_eq!(image[pixel][0], 0.0, "pixel {pixel} under the solid quad");
                through_cut_outs += 1;
            }
        }
    }
    assert!(
        through_cut_outs > 150,
        "{through_cut_outs} pixels under cut-outs"
    );
}
