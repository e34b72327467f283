//! Ray-cast shadows on the real adapter (lavapipe on CI), against references:
//! - every job's mask bit equals an f64 brute-force ray over every triangle from the same
//!   origin, except rays within 1e-4 of a triangle edge (counted);
//! - each pixel gets exactly the jobs its reaching, facing casters ask for (point and spot);
//! - a quad over a floor: every floor pixel's shadow equals the quad projected from the light;
//! - no self-shadowing at grazing light on flat and curved surfaces, and acne without the
//!   normal offset (so the test can fail);
//! - jobs, deferred and naive tracing give one image, equal to brute force with tracing;
//! - lights lying on surfaces or at their vertices cast no shadow in any tracer;
//! - a scene without casters runs no shadow pass and renders as Forward+ does;
//! - a full job buffer and pixels over 128 casters are counted.

mod common;

use common::shadow_jobs::raycast_inspection_graph;
use common::{graph_text, lambert, renderer, shadow_room, Rng};
use glam::{DVec3, Vec3};
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{FrameResult, PreparedFrame, Renderer, SceneGpu};
use lightgraph::scene::geometry::MeshBuilder;
use lightgraph::scene::{light_flags, Camera, Light, LightShape, Scene};
use lightgraph::shader::ShaderLibrary;
use lightgraph::shadow::reference::near_edge;
use lightgraph::shadow::{scene_triangles_f64, shadow_ray, ShadowBvh, Triangle64};
use std::path::Path;

const W: u32 = 96;
const H: u32 = 64;
/// Shaders' SHADOW_NORMAL_OFFSET default (ShadowRayCast's normal_offset).
const OFFSET: f32 = 1e-4;

fn caster(position: Vec3, range: f32, intensity: f32) -> Light {
    let mut l = Light::point(position, range, Vec3::ONE, intensity);
    l.flags |= light_flags::CASTS_SHADOW;
    l
}

/// Prepares and runs one frame, keeping the prepared frame to read buffers from.
fn run(r: &mut Renderer, text: &str, scene: &Scene) -> (PreparedFrame, FrameResult) {
    let checked =
        graph::check_text(Path::new("<test>"), text, &ShaderLibrary::builtin()).expect("valid");
    let size = FrameSize {
        width: W,
        height: H,
        lights: scene.lights.len() as u32,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, scene).expect("materials");
    let prepared = r
        .prepare(compiled, scene, &gpu, size, false)
        .expect("prepare");
    let result = prepared.render(r).expect("render");
    (prepared, result)
}

/// Floor, boxes, a floating slab and a standing cylinder under shadow-casting lights.
fn shadow_scene(lights: usize, seed: u64) -> Scene {
    let mut rng = Rng(seed);
    let meshes = shadow_room(&mut rng);
    // Every third light a spot pointing down and about, so the reach test covers cones.
    let lights = (0..lights)
        .map(|i| {
            let p = rng.vec3(Vec3::new(-6.0, 0.5, -10.0), Vec3::new(6.0, 5.0, 2.0));
            let mut l = caster(p, rng.range(4.0, 12.0), rng.range(2.0, 10.0));
            if i % 3 == 2 {
                let direction =
                    (rng.vec3(Vec3::splat(-0.6), Vec3::splat(0.6)) - Vec3::Y).normalize();
                l.shape = LightShape::Spot {
                    direction,
                    inner_angle: 0.3,
                    outer_angle: rng.range(0.5, 0.9),
                };
            }
            l
        })
        .collect();
    Scene {
        name: "shadow test".into(),
        meshes,
        materials: vec![
            lambert("floor", Vec3::splat(0.7)),
            lambert("boxes", Vec3::new(0.8, 0.5, 0.3)),
        ],
        lights,
        camera: Camera {
            eye: Vec3::new(0.0, 6.0, 7.0),
            target: Vec3::new(0.0, 0.0, -4.0),
            ..Default::default()
        },
        ..Default::default()
    }
}

struct Frame {
    positions: Vec<[f32; 4]>,
    geometric: Vec<[f32; 4]>,
    mask: Vec<u32>,
    /// (pixel, light, caster number)
    jobs: Vec<(u32, u32, u32)>,
}

fn read_frame(r: &Renderer, prepared: &PreparedFrame) -> Frame {
    let words = |name: &str| -> Vec<u32> {
        bytemuck::cast_slice(&prepared.read_buffer(r, name).unwrap()).to_vec()
    };
    let job_words = words("shadow_jobs");
    let count = job_words[0].min(((job_words.len() - 8) / 2) as u32) as usize;
    let jobs = (0..count)
        .map(|j| {
            let (a, b) = (job_words[8 + 2 * j], job_words[8 + 2 * j + 1]);
            (a, b & 0xff_ffff, b >> 24)
        })
        .collect();
    Frame {
        positions: prepared.read_texture(r, "g_position").unwrap(),
        geometric: prepared.read_texture(r, "g_geometric").unwrap(),
        mask: words("shadow_mask"),
        jobs,
    }
}

fn hidden(mask: &[u32], pixel: u32, caster: u32) -> bool {
    mask[(pixel * 4 + caster / 32) as usize] & (1 << (caster % 32)) != 0
}

/// Mask bits against f64 rays over every triangle: (agreeing, ambiguous, disagreeing).
fn compare_with_reference(
    f: &Frame,
    tris: &[Triangle64],
    lights: &[Light],
    offset: f32,
) -> (usize, usize, usize) {
    let (mut agree, mut ambiguous, mut disagree) = (0, 0, 0);
    for &(pixel, light, c) in &f.jobs {
        let g = f.positions[pixel as usize];
        let n = f.geometric[pixel as usize];
        // The shaders' ray (its CPU twin), traced in f64 over every triangle.
        let (o, _, t_max) = shadow_ray(
            Vec3::new(g[0], g[1], g[2]),
            Vec3::new(n[0], n[1], n[2]),
            lights[light as usize].position,
            offset,
        );
        let (o64, l64) = (o.as_dvec3(), lights[light as usize].position.as_dvec3());
        let (dir, t_max) = (l64 - o64, t_max as f64);
        // Only rays passing within 1e-4 of a triangle edge may go either way in f32.
        if near_edge(tris, o64, dir, t_max, 1e-4) {
            ambiguous += 1;
            continue;
        }
        let reference = lightgraph::shadow::occluded_reference(tris, o64, dir, t_max);
        if reference == hidden(&f.mask, pixel, c) {
            agree += 1;
        } else {
            disagree += 1;
        }
    }
    (agree, ambiguous, disagree)
}

#[test]
fn masks_equal_the_f64_reference_and_jobs_are_complete() {
    let mut r = renderer();
    let scene = shadow_scene(24, 7);
    let (prepared, result) = run(&mut r, &raycast_inspection_graph(), &scene);
    let f = read_frame(&r, &prepared);
    let tris = scene_triangles_f64(&scene);
    let (agree, ambiguous, disagree) = compare_with_reference(&f, &tris, &scene.lights, OFFSET);
    eprintln!("rays: {agree} agree, {ambiguous} within 1e-4 of an edge, {disagree} disagree");
    assert_eq!(disagree, 0);
    assert!(agree > 5_000, "too few rays to mean anything: {agree}");
    assert!(ambiguous * 100 < agree, "{ambiguous} ambiguous of {agree}");
    let hidden_count = f
        .jobs
        .iter()
        .filter(|&&(p, _, c)| hidden(&f.mask, p, c))
        .count();
    assert!(
        hidden_count > 500 && hidden_count < agree,
        "{hidden_count} of {agree} hidden"
    );
    let report = &result.shadows[0];
    assert_eq!(report.jobs_wanted as usize, f.jobs.len());
    assert_eq!((report.jobs_dropped, report.overflow_pixels), (0, 0));

    // Each pixel's jobs are exactly its facing casters in reach (in range and cone).
    let mut jobs_at = vec![Vec::new(); (W * H) as usize];
    for &(p, l, c) in &f.jobs {
        jobs_at[p as usize].push((l, c));
    }
    let mut checked = 0;
    for (pixel, jobs) in jobs_at.iter_mut().enumerate() {
        let g = f.positions[pixel];
        if g[3] < 0.0 {
            assert!(jobs.is_empty());
            continue;
        }
        let p = Vec3::new(g[0], g[1], g[2]);
        let n = f.geometric[pixel];
        let ng = Vec3::new(n[0], n[1], n[2]);
        // Reach is decided in f32 by the shader; skip pixels on a light's range or cone
        // boundary.
        let cone = |l: &Light| match l.shape {
            LightShape::Point => None,
            LightShape::Spot {
                direction,
                outer_angle,
                ..
            } => Some(direction.dot((p - l.position).normalize()) - outer_angle.cos()),
        };
        if scene.lights.iter().any(|l| {
            (l.position.distance(p) - l.range).abs() < 1e-3 * l.range
                || cone(l).is_some_and(|c| c.abs() < 1e-3)
        }) {
            continue;
        }
        let mut want: Vec<u32> = (0..scene.lights.len() as u32)
            .filter(|&i| {
                let l = &scene.lights[i as usize];
                l.position.distance(p) < l.range
                    && cone(l).is_none_or(|c| c > 0.0)
                    && ng.dot(l.position - p) > 0.0
            })
            .collect();
        let mut got: Vec<u32> = jobs.iter().map(|j| j.0).collect();
        want.sort();
        got.sort();
        if got != want {
            for &i in want.iter().filter(|i| !got.contains(i)) {
                let l = &scene.lights[i as usize];
                eprintln!(
                    "missing light {i}: {:?} dist {} range {} cone {:?} facing {}",
                    l.shape,
                    l.position.distance(p),
                    l.range,
                    cone(l),
                    ng.dot(l.position - p)
                );
            }
        }
        assert_eq!(got, want, "pixel {pixel}");
        // Caster numbers are distinct and below 128.
        let mut cs: Vec<u32> = jobs.iter().map(|j| j.1).collect();
        cs.sort();
        cs.dedup();
        assert_eq!(cs.len(), jobs.len());
        checked += 1;
    }
    assert!(checked > (W * H / 2) as usize, "{checked} pixels checked");
}

#[test]
fn a_quad_over_a_floor_casts_its_projection() {
    let mut r = renderer();
    let light = Vec3::new(0.3, 3.0, 0.2);
    let mut quad = MeshBuilder::new("quad", 1);
    quad.quad(
        Vec3::new(-0.5, 1.0, 0.5),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -1.0),
        glam::Vec2::ONE,
    );
    let mut floor = MeshBuilder::new("floor", 0);
    floor.quad(
        Vec3::new(-4.0, 0.0, 4.0),
        Vec3::new(8.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -8.0),
        glam::Vec2::ONE,
    );
    let scene = Scene {
        name: "quad over floor".into(),
        meshes: vec![floor.build(), quad.build()],
        materials: vec![
            lambert("floor", Vec3::splat(0.8)),
            lambert("quad", Vec3::ONE),
        ],
        lights: vec![caster(light, 30.0, 5.0)],
        camera: Camera {
            eye: Vec3::new(0.0, 5.0, 2.5),
            target: Vec3::new(0.0, 0.0, 0.0),
            ..Default::default()
        },
        ..Default::default()
    };
    let (prepared, _) = run(&mut r, &raycast_inspection_graph(), &scene);
    let f = read_frame(&r, &prepared);
    let (_, result) = run(&mut r, &graph_text("raycast_shadows.ron"), &scene);
    let (mut shadowed, mut lit, mut near_edge) = (0, 0, 0);
    for pixel in 0..(W * H) {
        let g = f.positions[pixel as usize];
        if g[3] < 0.0 || g[1].abs() > 1e-3 {
            continue; // not the floor
        }
        let p = DVec3::new(g[0] as f64, g[1] as f64, g[2] as f64);
        let l = light.as_dvec3();
        // Where the segment to the light crosses the quad's plane y = 1.
        let t = (1.0 - p.y) / (l.y - p.y);
        let q = p + (l - p) * t;
        let inside = q.x.abs() <= 0.5 && q.z.abs() <= 0.5;
        let edge_distance = (0.5 - q.x.abs()).abs().min((0.5 - q.z.abs()).abs());
        if edge_distance < 1e-3 {
            near_edge += 1;
            continue;
        }
        assert_eq!(
            hidden(&f.mask, pixel, 0),
            inside,
            "floor pixel {pixel} at {p}"
        );
        if inside {
            shadowed += 1;
        } else {
            lit += 1;
        }
        // The image agrees: a shadowed floor pixel gets no light at all (no ambient here).
        let c = result.image[pixel as usize];
        assert_eq!(c[0] == 0.0, inside, "pixel {pixel} colour {c:?}");
    }
    eprintln!("floor: {shadowed} shadowed, {lit} lit, {near_edge} on the shadow's edge");
    assert!(
        shadowed > 100 && lit > 1000,
        "{shadowed} shadowed, {lit} lit"
    );
}

/// A floor strip and a standing cylinder lit from 1.5° above the floor, with nothing
/// that can shadow them: every hidden bit is acne.
fn grazing_scene() -> Scene {
    let mut floor = MeshBuilder::new("floor", 0);
    floor.quad(
        Vec3::new(0.8, 0.0, 3.0),
        Vec3::new(9.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -6.0),
        glam::Vec2::ONE,
    );
    let mut cyl = MeshBuilder::new("column", 1);
    cyl.cylinder(Vec3::new(0.0, 0.0, 0.0), 0.5, 2.0, 32, 2);
    Scene {
        name: "grazing".into(),
        meshes: vec![floor.build(), cyl.build()],
        materials: vec![
            lambert("floor", Vec3::splat(0.8)),
            lambert("column", Vec3::ONE),
        ],
        lights: vec![caster(Vec3::new(40.0, 40.0 * 0.026, 0.5), 100.0, 200.0)],
        camera: Camera {
            eye: Vec3::new(9.0, 3.0, 6.0),
            target: Vec3::new(2.0, 0.5, 0.0),
            ..Default::default()
        },
        ..Default::default()
    }
}

fn with_offset(text: &str, offset: f32) -> String {
    text.replace(
        "ShadowRayCast()",
        &format!("ShadowRayCast(normal_offset: {offset:?})"),
    )
}

#[test]
fn no_acne_at_grazing_light_and_acne_without_the_offset() {
    let mut r = renderer();
    let scene = grazing_scene();
    let text = raycast_inspection_graph();
    let acne = |r: &mut Renderer, offset: f32| {
        let (prepared, _) = run(r, &with_offset(&text, offset), &scene);
        let f = read_frame(r, &prepared);
        let hidden_count = f
            .jobs
            .iter()
            .filter(|&&(p, _, c)| hidden(&f.mask, p, c))
            .count();
        (hidden_count, f.jobs.len())
    };
    let (with, rays) = acne(&mut r, OFFSET);
    let (without, rays0) = acne(&mut r, 0.0);
    eprintln!("self-shadowed rays: {with} of {rays} with the offset, {without} of {rays0} without");
    assert!(rays > 1000, "{rays} rays");
    assert_eq!(with, 0, "acne with the normal offset");
    assert!(
        without > 0,
        "no acne without the offset: the test cannot fail"
    );
}

/// A floor and a wall meeting at an edge, with shadow-casting lights lying exactly on
/// them, on their shared edge and at their shared vertex: nothing stands between any
/// point and any light, so every tracer must leave the image unshadowed (a ray reaching
/// the light's own triangle at t ≈ 1 drew black streaks).
fn lights_on_surfaces_scene() -> Scene {
    let mut floor = MeshBuilder::new("floor", 0);
    floor.quad(
        Vec3::new(-4.0, 0.0, 2.0),
        Vec3::new(8.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -5.0),
        glam::Vec2::ONE,
    );
    let mut wall = MeshBuilder::new("wall", 0);
    wall.quad(
        Vec3::new(-4.0, 0.0, -3.0),
        Vec3::new(8.0, 0.0, 0.0),
        Vec3::new(0.0, 3.0, 0.0),
        glam::Vec2::ONE,
    );
    let lights = [
        Vec3::new(-1.5, 0.0, -0.5), // on the floor
        Vec3::new(1.2, 0.0, 0.7),
        Vec3::new(0.5, 1.5, -3.0), // on the wall
        Vec3::new(-2.0, 0.7, -3.0),
        Vec3::new(0.3, 0.0, -3.0), // on the edge they share
        Vec3::new(4.0, 0.0, -3.0), // at a vertex of both
    ]
    .map(|p| caster(p, 8.0, 3.0))
    .to_vec();
    Scene {
        name: "lights on surfaces".into(),
        meshes: vec![floor.build(), wall.build()],
        materials: vec![lambert("plaster", Vec3::splat(0.8))],
        lights,
        camera: Camera {
            eye: Vec3::new(0.0, 2.5, 5.0),
            target: Vec3::new(0.0, 0.8, -1.5),
            ..Default::default()
        },
        ..Default::default()
    }
}

#[test]
fn a_light_on_a_surface_casts_no_shadow_in_any_tracer() {
    let scene = lights_on_surfaces_scene();
    // The CPU twin: rays from a grid of floor and wall points to every light they face.
    let bvh = ShadowBvh::build(&scene).unwrap();
    let mut rays = 0;
    for i in 0..=64 {
        for j in 0..=64 {
            let (a, b) = (i as f32 / 64.0, j as f32 / 64.0);
            for (p, ng) in [
                (Vec3::new(-4.0 + 8.0 * a, 0.0, 2.0 - 5.0 * b), Vec3::Y),
                (Vec3::new(-4.0 + 8.0 * a, 3.0 * b, -3.0), Vec3::Z),
            ] {
                for l in &scene.lights {
                    if ng.dot(l.position - p) <= 0.0 {
                        continue;
                    }
                    let (origin, dir, t_max) = shadow_ray(p, ng, l.position, OFFSET);
                    rays += 1;
                    assert!(
                        !bvh.occluded(origin, dir, t_max),
                        "CPU twin: {p} hidden from the light at {}",
                        l.position
                    );
                }
            }
        }
    }
    assert!(rays > 10_000, "{rays} rays");
    let mut r = renderer();
    let (_, unshadowed) = run(&mut r, &graph_text("forward_plus.ron"), &scene);
    let lit = unshadowed.image.iter().filter(|c| c[0] > 0.0).count();
    assert!(lit > (W * H / 2) as usize, "{lit} lit pixels");
    for graph in [
        "raycast_shadows.ron",
        "raycast_shadows_naive.ron",
        "tiled_deferred_raycast_shadows.ron",
    ] {
        let (_, shadowed) = run(&mut r, &graph_text(graph), &scene);
        // Shading is the same but for the shadow factor: a darker pixel is a false shadow.
        // The lights in a receiving surface's own plane reach it only through the rounding
        // of its position (an N·L of f32 rounding's order), which may go either way:
        // they move a pixel by up to 1e-4 of its value (seen: 1.4e-4 on 7 pixels where the
        // floor meets the wall), a false black streak by all of that light.
        let darker = shadowed
            .image
            .iter()
            .zip(&unshadowed.image)
            .filter(|(s, u)| s[0] < u[0] * (1.0 - 1e-3))
            .count();
        assert_eq!(darker, 0, "{graph}: {darker} pixels falsely shadowed");
    }
}

#[test]
fn jobs_deferred_naive_and_brute_force_give_one_image() {
    let mut r = renderer();
    let scene = shadow_scene(24, 11);
    let (_, jobs) = run(&mut r, &graph_text("raycast_shadows.ron"), &scene);
    let (_, deferred) = run(
        &mut r,
        &graph_text("tiled_deferred_raycast_shadows.ron"),
        &scene,
    );
    let (_, naive) = run(&mut r, &graph_text("raycast_shadows_naive.ron"), &scene);
    // Brute force (every light at every pixel) tracing in the loop: the image reference.
    let brute = graph_text("raycast_shadows_naive.ron")
        .replace(
            "ForwardShading(lights: Culled)",
            "ForwardShading(lights: AllLights)",
        )
        .replace("\"light_lists\", \"bvh_nodes\"", "\"bvh_nodes\"");
    let (_, brute) = run(&mut r, &brute, &scene);
    let (_, unshadowed) = run(&mut r, &graph_text("forward_plus.ron"), &scene);
    for (name, other) in [
        ("deferred", &deferred),
        ("naive", &naive),
        ("brute force", &brute),
    ] {
        assert_eq!((other.width, other.height), (jobs.width, jobs.height));
        let differ = jobs
            .image
            .iter()
            .zip(&other.image)
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(
            differ, 0,
            "{name}: {differ} pixels differ from the job graph"
        );
    }
    let darker = jobs
        .image
        .iter()
        .zip(&unshadowed.image)
        .filter(|(a, b)| a[0] < b[0])
        .count();
    assert!(darker > 500, "shadows darkened only {darker} pixels");
}

#[test]
fn without_casters_no_shadow_pass_runs_and_the_image_is_forward_plus() {
    let mut r = renderer();
    let mut scene = shadow_scene(24, 3);
    for l in &mut scene.lights {
        l.flags &= !light_flags::CASTS_SHADOW;
    }
    let text = graph_text("raycast_shadows.ron");
    let checked = graph::check_text(Path::new("<test>"), &text, &ShaderLibrary::builtin()).unwrap();
    let size = FrameSize {
        width: W,
        height: H,
        lights: 24,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    for pass in ["shadow_gbuffer", "shadow_ray_jobs", "shadow_ray_cast"] {
        assert!(compiled.culled_reason(pass).is_some(), "{pass} ran");
    }
    let (_, shadowed) = run(&mut r, &text, &scene);
    let (_, plain) = run(&mut r, &graph_text("forward_plus.ron"), &scene);
    assert!(shadowed.shadows.is_empty());
    assert_eq!(shadowed.image, plain.image);
}

#[test]
fn a_full_job_buffer_and_pixels_over_128_casters_are_counted() {
    let mut r = renderer();
    let scene = shadow_scene(24, 7);
    let small =
        graph_text("raycast_shadows.ron").replace("jobs_per_pixel: 16.0", "jobs_per_pixel: 0.5");
    let (_, result) = run(&mut r, &small, &scene);
    let s = &result.shadows[0];
    assert_eq!(s.capacity, (W * H / 2) as u64);
    assert!(
        s.jobs_dropped > 0 && s.jobs_wanted == s.rays() + s.jobs_dropped,
        "{s:?}"
    );

    // 140 casters around the origin, every one reaching the floor there.
    let mut crowd = shadow_scene(0, 1);
    let mut rng = Rng(5);
    crowd.lights = (0..140)
        .map(|_| {
            caster(
                rng.vec3(Vec3::new(-1.0, 3.0, -4.0), Vec3::new(1.0, 4.0, -2.0)),
                40.0,
                0.05,
            )
        })
        .collect();
    let big =
        graph_text("raycast_shadows.ron").replace("jobs_per_pixel: 16.0", "jobs_per_pixel: 128.0");
    let (_, result) = run(&mut r, &big, &crowd);
    let s = &result.shadows[0];
    assert!(s.overflow_pixels > (W * H / 4) as u64, "{s:?}");
    assert_eq!(s.jobs_dropped, 0, "{s:?}");
}
