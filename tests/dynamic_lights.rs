//! Moving lights: scene-file motion is a pure function of time (`render --time` twice
//! gives the same image, another time a different one), and `PreparedFrame::update_lights`
//! moves lights between frames of one prepared graph: the culled image after a move
//! equals brute force with the lights placed there statically, the light count changes
//! up to the capacity set at upload, and past it the update is refused by name.

mod common;
use common::*;

use glam::Vec3;
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{LightUpdateError, PreparedFrame, RenderError, Renderer, SceneGpu};
use lightgraph::scene::motion::{Flicker, LightMotion, Motion, Orbit};
use lightgraph::scene::{Light, LightShape, Scene};
use lightgraph::shader::ShaderLibrary;
use std::path::Path;
use std::process::Command;

const W: u32 = 96;
const H: u32 = 54;

/// Same lights, same shading code: forward+ and brute force differ only in the order
/// lights are summed (the bound of tests/forward_plus.rs, relative to the peak here).
const SAME_LIGHTS: f32 = 2e-6;

/// `graph` prepared for `scene` with light buffers holding room for `capacity` lights.
fn prepare(
    r: &mut Renderer,
    graph_file: &str,
    scene: &Scene,
    capacity: u32,
) -> (PreparedFrame, SceneGpu) {
    prepare_file_with_gpu(r, graph_file, scene, W, H, capacity)
}

/// A still render of `scene` with `lights` placed in it from the start.
fn still(r: &mut Renderer, graph_file: &str, scene: &Scene, lights: &[Light]) -> Vec<[f32; 4]> {
    let mut s = scene.clone();
    s.lights = lights.to_vec();
    let image = render_text_with(
        r,
        &std::fs::read_to_string(graph_path(graph_file)).unwrap(),
        &s,
        W,
        H,
        false,
    )
    .image;
    assert_eq!(image.len(), (W * H) as usize);
    image
}

fn assert_same(a: &[[f32; 4]], b: &[[f32; 4]], what: &str) {
    let (d, at) = max_rel_diff(a, b);
    assert!(
        d <= SAME_LIGHTS,
        "{what}: relative error {d:e} at pixel {at}"
    );
}

fn assert_differs(a: &[[f32; 4]], b: &[[f32; 4]], what: &str) {
    let (d, at) = max_rel_diff(a, b);
    // Lights moved by metres: some pixel changes by a good part of the peak.
    assert!(d > 0.05, "{what}: only {d:e} apart (pixel {at})");
}

/// Every light of `scene` orbiting the room's centre, flickering.
fn orbiting(mut scene: Scene) -> Scene {
    scene.light_motion = vec![LightMotion {
        first: 0,
        count: scene.lights.len() as u32,
        motion: Motion {
            orbit: Some(Orbit {
                centre: Vec3::new(0.0, 0.0, -17.0),
                axis: Vec3::Y,
                speed_deg: 30.0,
            }),
            flicker: Some(Flicker {
                amplitude: 0.5,
                frequency: 3.0,
                seed: 9,
            }),
            path: None,
        },
    }];
    scene
}

#[test]
fn moved_lights_light_their_new_places_and_the_lists_follow() {
    let mut r = renderer();
    let scene = orbiting(random_scene(256, 5));
    let (mut at_0, mut at_2) = (Vec::new(), Vec::new());
    scene.lights_at(0.0, &mut at_0);
    scene.lights_at(2.0, &mut at_2);
    let mut start = scene.clone();
    start.lights = at_0.clone();
    let (prepared, gpu) = prepare(&mut r, "forward_plus.ron", &start, 0);
    let before = prepared.render(&r).unwrap().image;
    prepared.update_lights(&r, &gpu, &at_2).unwrap();
    let after = prepared.render(&r).unwrap().image;

    let brute_0 = still(&mut r, "brute_force.ron", &scene, &at_0);
    let brute_2 = still(&mut r, "brute_force.ron", &scene, &at_2);
    assert_same(
        &before,
        &brute_0,
        "culled frame before the move vs brute force at t=0",
    );
    assert_same(
        &after,
        &brute_2,
        "culled frame after the move vs brute force at t=2",
    );
    assert_differs(&after, &brute_0, "after the move vs the old places");
}

#[test]
fn one_moved_light_lights_the_new_place_not_the_old() {
    let mut r = renderer();
    let scene = random_scene(0, 2);
    let a = Light::point(Vec3::new(-6.0, 1.0, -10.0), 6.0, Vec3::ONE, 8.0);
    let b = Light::point(Vec3::new(6.0, 1.0, -10.0), 6.0, Vec3::ONE, 8.0);
    let mut start = scene.clone();
    start.lights = vec![a];
    let (prepared, gpu) = prepare(&mut r, "forward_plus.ron", &start, 0);
    prepared.update_lights(&r, &gpu, &[b]).unwrap();
    let moved = prepared.render(&r).unwrap().image;
    let at_a = still(&mut r, "brute_force.ron", &scene, &[a]);
    assert_same(
        &moved,
        &still(&mut r, "brute_force.ron", &scene, &[b]),
        "at B",
    );
    assert_differs(&moved, &at_a, "vs A");
    // The left quarter of the frame: A lights it, B (6 m range, 12 m to the right) not.
    let left_lit = |image: &[[f32; 4]]| {
        image
            .iter()
            .enumerate()
            .filter(|(i, p)| (*i as u32 % W) < W / 4 && p[0] > 0.0)
            .count()
    };
    assert!(left_lit(&at_a) > 50, "A lights the left quarter");
    assert_eq!(left_lit(&moved), 0, "the old place is still lit");
}

#[test]
fn the_light_count_changes_up_to_the_capacity_and_no_further() {
    let mut r = renderer();
    let scene = random_scene(12, 8);
    // Starts with one point and one spot light (what the graph is compiled for), room
    // for twelve.
    let spot = |l: &&Light| matches!(l.shape, lightgraph::scene::LightShape::Spot { .. });
    let mut start = scene.clone();
    start.lights = vec![
        *scene.lights.iter().find(|l| !spot(l)).unwrap(),
        *scene.lights.iter().find(spot).unwrap(),
    ];
    let (prepared, gpu) = prepare(&mut r, "forward_plus.ron", &start, 12);
    assert_eq!((prepared.light_count(), prepared.light_capacity()), (2, 12));
    for n in [12, 5, 1] {
        prepared
            .update_lights(&r, &gpu, &scene.lights[..n])
            .unwrap();
        assert_eq!(prepared.light_count(), n as u32);
        let image = prepared.render(&r).unwrap().image;
        let brute = still(&mut r, "brute_force.ron", &scene, &scene.lights[..n]);
        assert_same(&image, &brute, &format!("{n} lights"));
    }
    prepared.update_lights(&r, &gpu, &[]).unwrap();
    let dark = prepared.render(&r).unwrap().image;
    assert_eq!(dark.len(), (W * H) as usize);
    assert!(
        dark.iter().all(|p| p[..3] == [0.0; 3]),
        "no lights, no light"
    );
    let mut more = scene.lights.clone();
    more.push(scene.lights[0]);
    let e = prepared.update_lights(&r, &gpu, &more).unwrap_err();
    assert!(
        matches!(
            e,
            LightUpdateError::OverCapacity {
                count: 13,
                capacity: 12
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("over the capacity of 12"), "{e}");
    // Refused means untouched: the last update's count stays.
    assert_eq!(prepared.light_count(), 0);
}

#[test]
fn updates_that_the_prepared_graph_cannot_show_are_refused() {
    let mut r = renderer();
    let scene = random_scene(0, 3);
    let point = Light::point(Vec3::new(0.0, 1.0, -5.0), 4.0, Vec3::ONE, 2.0);
    let mut start = scene.clone();
    start.lights = vec![point];
    let (prepared, gpu) = prepare(&mut r, "forward_plus.ron", &start, 4);
    // Spots were compiled away: the scene had none.
    let mut spot = point;
    spot.shape = lightgraph::scene::LightShape::Spot {
        direction: Vec3::NEG_Y,
        inner_angle: 0.2,
        outer_angle: 0.4,
    };
    let e = prepared
        .update_lights(&r, &gpu, &[point, spot])
        .unwrap_err();
    assert!(e.to_string().contains("light 1 adds a spot light"), "{e}");
    let mut bad = point;
    bad.range = f32::NAN;
    let e = prepared.update_lights(&r, &gpu, &[bad]).unwrap_err();
    assert!(e.to_string().contains("light 0: range NaN"), "{e}");

    // A plan sized for fewer lights than the upload holds is refused at prepare.
    let text = std::fs::read_to_string(graph_path("forward_plus.ron")).unwrap();
    let checked = graph::check_text(Path::new("fp"), &text, &ShaderLibrary::builtin()).unwrap();
    let size = FrameSize {
        width: W,
        height: H,
        lights: 1,
    };
    let compiled = graph::compile(checked, &start.features(), size);
    let err = r
        .prepare(compiled, &start, &gpu, size, false)
        .err()
        .unwrap();
    assert!(
        matches!(
            err,
            RenderError::LightCapacity {
                compiled: 1,
                capacity: 4
            }
        ),
        "{err}"
    );
}

/// A scene file whose lights move: an explicit light on a path and a random set orbiting.
const MOVING_SCENE: &str = r#"Scene(
    builtin: "harada",
    keep_model_lights: false,
    lights: [
        (position: (0, 1, 0), range: 8, intensity: 20,
         motion: (path: (points: [(-8, 0, 0), (8, 0, 0), (0, 0, 8)], period: 3,
                         interpolation: CatmullRom))),
    ],
    light_sets: [
        Random(count: 48, placement: SceneBounds(margin: 0), range: (2, 5), intensity: (1, 4),
               seed: 3, motion: (orbit: (centre: (0, 0, 0), speed_deg: 40),
                                 flicker: (amplitude: 0.8, frequency: 4, seed: 1))),
    ],
)"#;

fn render_at(dir: &Path, scene: &Path, time: &str, out: &str) -> Vec<u8> {
    let o = Command::new(env!("CARGO_BIN_EXE_lightgraph"))
        .current_dir(dir)
        .args(["render", "--scene", scene.to_str().unwrap()])
        .args([
            "--width", "64", "--height", "36", "--time", time, "--out", out,
        ])
        .env_remove("LIGHTGRAPH_ROOT")
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .expect("the binary runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::read(dir.join(out)).unwrap()
}

#[test]
fn render_time_is_reproducible_and_moves_the_lights() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("moving.ron");
    std::fs::write(&scene, MOVING_SCENE).unwrap();
    let first = render_at(dir.path(), &scene, "1.25", "a.exr");
    let again = render_at(dir.path(), &scene, "1.25", "b.exr");
    let later = render_at(dir.path(), &scene, "2.5", "c.exr");
    assert!(first.len() > 64 * 36 * 4, "an EXR of 64x36 pixels");
    assert!(first == again, "the same --time gave different images");
    assert!(first != later, "another --time gave the same image");
}

/// `watch --time` until its first frame is written; then stopped.
fn watch_at(dir: &Path, scene: &Path, time: &str, out: &str) -> Vec<u8> {
    use std::io::{BufRead, BufReader};
    let mut child = Command::new(env!("CARGO_BIN_EXE_lightgraph"))
        .current_dir(dir)
        .args(["watch", "--scene", scene.to_str().unwrap()])
        .args([
            "--width", "64", "--height", "36", "--time", time, "--out", out,
        ])
        .env_remove("LIGHTGRAPH_ROOT")
        .env_remove("XDG_RUNTIME_DIR")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the binary runs");
    let stdout = BufReader::new(child.stdout.take().unwrap());
    let mut seen = String::new();
    for line in stdout.lines().map_while(Result::ok) {
        seen.push_str(&line);
        seen.push('\n');
        if line.starts_with("watching; wrote") {
            break;
        }
    }
    child.kill().unwrap();
    let status = child.wait().unwrap();
    assert!(
        seen.contains("watching; wrote"),
        "watch ended ({status}) before its first frame:\n{seen}\n{}",
        std::io::read_to_string(child.stderr.take().unwrap()).unwrap_or_default()
    );
    std::fs::read(dir.join(out)).unwrap()
}

#[test]
fn watch_time_renders_what_render_time_renders() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("moving.ron");
    std::fs::write(&scene, MOVING_SCENE).unwrap();
    let watched = watch_at(dir.path(), &scene, "1.25", "w.exr");
    assert!(watched.len() > 64 * 36 * 4, "an EXR of 64x36 pixels");
    assert!(
        watched == render_at(dir.path(), &scene, "1.25", "r.exr"),
        "watch --time 1.25 and render --time 1.25 differ"
    );
    // Without --time both place the lights at 0 (the path light starts a whole offset
    // away from where it is written, so unplaced lights would differ).
    let watched_0 = watch_at(dir.path(), &scene, "0", "w0.exr");
    assert!(watched_0 != watched, "another --time gave the same image");
    let o = Command::new(env!("CARGO_BIN_EXE_lightgraph"))
        .current_dir(dir.path())
        .args(["render", "--scene", scene.to_str().unwrap()])
        .args(["--width", "64", "--height", "36", "--out", "r0.exr"])
        .env_remove("LIGHTGRAPH_ROOT")
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        watched_0 == std::fs::read(dir.path().join("r0.exr")).unwrap(),
        "watch --time 0 differs from render without --time"
    );
    let o = Command::new(env!("CARGO_BIN_EXE_lightgraph"))
        .current_dir(dir.path())
        .args(["watch", "--scene", scene.to_str().unwrap()])
        .args(["--time", "inf", "--out", "x.exr"])
        .env_remove("LIGHTGRAPH_ROOT")
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("--time must be a finite number"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
fn scene_file_motion_is_a_pure_function_of_time() {
    let loaded = lightgraph::scene::scene_file::build_scene(
        &lightgraph::scene::scene_file::parse_scene_file(MOVING_SCENE, Path::new("m.ron")).unwrap(),
        Path::new("m.ron"),
    )
    .unwrap();
    let scene = loaded.scene;
    assert_eq!(scene.lights.len(), 49);
    assert_eq!(scene.light_motion.len(), 2);
    let (mut a, mut b, mut c) = (Vec::new(), Vec::new(), Vec::new());
    scene.lights_at(1.25, &mut a);
    scene.lights_at(1.25, &mut b);
    scene.lights_at(2.5, &mut c);
    assert_eq!(a, b);
    // The path light is at its second point a third of the way round (t = 1 of 3 s).
    scene.lights_at(1.0, &mut c);
    assert!((c[0].position - Vec3::new(8.0, 1.0, 0.0)).length() < 1e-4);
    // Orbits keep each light's distance from the axis and its height.
    for (l0, l1) in scene.lights[1..].iter().zip(&a[1..]) {
        let radius = |p: Vec3| Vec3::new(p.x, 0.0, p.z).length();
        assert!((radius(l0.position) - radius(l1.position)).abs() < 1e-3);
        assert!((l0.position.y - l1.position.y).abs() < 1e-4);
        assert!(l1.intensity <= l0.intensity * 1.8 + 1e-4);
    }
    assert!(scene.lights[1..]
        .iter()
        .zip(&a[1..])
        .all(|(l0, l1)| (l0.position - l1.position).length() > 1e-3));
}

#[test]
fn bad_motion_is_named_with_its_light() {
    let refusal = |text: &str| {
        let spec =
            lightgraph::scene::scene_file::parse_scene_file(text, Path::new("m.ron")).unwrap();
        lightgraph::scene::scene_file::build_scene(&spec, Path::new("m.ron"))
            .err()
            .unwrap()
            .to_string()
    };
    let e = refusal(&MOVING_SCENE.replace("period: 3", "period: 0"));
    assert!(
        e.contains("lights[0]") && e.contains("path period 0"),
        "{e}"
    );
    let e = refusal(&MOVING_SCENE.replace("amplitude: 0.8", "amplitude: 1.5"));
    assert!(
        e.contains("light_sets[0]") && e.contains("flicker amplitude"),
        "{e}"
    );
}

#[test]
fn the_shadow_atlas_follows_moved_casters() {
    let mut r = renderer();
    let scene = random_scene(0, 4);
    let caster = |p: Vec3| {
        let mut l = Light::point(p, 10.0, Vec3::ONE, 20.0);
        l.flags = lightgraph::scene::light_flags::CASTS_SHADOW;
        l
    };
    let a = [
        caster(Vec3::new(-4.0, 2.0, -8.0)),
        caster(Vec3::new(3.0, 5.0, -20.0)),
    ];
    let b = [
        caster(Vec3::new(4.0, 1.5, -12.0)),
        caster(Vec3::new(-3.0, 3.0, -16.0)),
    ];
    let mut start = scene.clone();
    start.lights = a.to_vec();
    let (prepared, gpu) = prepare(&mut r, "shadow_atlas.ron", &start, 0);
    let allocations = |f: &lightgraph::render::FrameResult| f.atlases[0].allocations;
    assert_eq!(allocations(&prepared.render(&r).unwrap()), 1, "at prepare");
    // A viewer's frame: the lights move, then the camera is set (to where it was):
    // one allocation for both, made when the frame is recorded.
    prepared.update_lights(&r, &gpu, &b).unwrap();
    prepared.set_camera(&r, &start);
    let moved = prepared.render(&r).unwrap();
    assert_eq!(
        allocations(&moved),
        2,
        "one more for the moved lights and camera"
    );
    assert_eq!(
        allocations(&prepared.render(&r).unwrap()),
        2,
        "none for a frame where nothing moved"
    );
    let moved = moved.image;
    // The same graph prepared with the casters at B from the start: the same atlas
    // allocation and views, so the same image.
    assert_same(
        &moved,
        &still(&mut r, "shadow_atlas.ron", &scene, &b),
        "atlas at B",
    );
    assert_differs(
        &moved,
        &still(&mut r, "shadow_atlas.ron", &scene, &a),
        "vs A",
    );
}

const ANIMATED_SWEEP: &str = r#"Sweep(
    scenes: ["builtin:glass"],
    graphs: ["forward_plus.ron"],
    lights: [64],
    resolutions: [(48, 27)],
    warmup: 2,
    warmup_seconds: 0,
    frames: 3,
    rounds: 1,
    light_stats: false,
    animate: 0.25,
)"#;

#[test]
fn an_animated_sweep_moves_the_lights_and_compares_them_where_they_started() {
    use lightgraph::bench::sweep::{self, Sweep};
    let plan = Sweep::parse(ANIMATED_SWEEP, Path::new("animated.ron")).unwrap();
    let rows = {
        let mut r = renderer();
        sweep::run(&plan, Path::new("."), &mut r, |_| {}).expect("sweep")
    };
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0].params, "animate=0.25s");
    // The error columns render after the sweep gives every frame the scene's lights
    // back: the same lights as the reference, so only summation order differs (lights
    // left where the last timed frame moved them are off by the whole signal).
    let max_rel = rows[0].max_rel.expect("an error column");
    assert!(max_rel <= 1e-3, "max_rel {max_rel}");
    // The CPU's share of a moving frame: evaluating 64 orbits and writing them. Well
    // under a millisecond on any machine; not zero, and written to the CSV.
    let update_ms = rows[0].light_update_cpu_ms.expect("a light update column");
    eprintln!("light update: {update_ms} ms CPU a frame (64 lights)");
    assert!(update_ms > 0.0 && update_ms < 50.0, "{update_ms} ms");
    let csv = lightgraph::bench::report::to_csv(&rows);
    let mut reader = csv::Reader::from_reader(csv.as_bytes());
    let column = reader
        .headers()
        .unwrap()
        .iter()
        .position(|c| c == "light_update_cpu_ms")
        .expect("the CSV column");
    let record = reader.records().next().unwrap().unwrap();
    assert_eq!(record[column].parse::<f64>().unwrap(), update_ms);

    let bad = ANIMATED_SWEEP.replace("animate: 0.25", "animate: 0");
    let e = Sweep::parse(&bad, Path::new("animated.ron"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("11: animate 0 must be"), "{e}");
}

/// The Cornell box of scenes/cornell_indirect.ron with its one indirect light, n = 4.
fn cornell_indirect() -> Scene {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut s = lightgraph::scene::load(&root.join("scenes/cornell_indirect.ron"))
        .expect("cornell_indirect loads")
        .scene;
    for c in s.vpl_controls.values_mut() {
        c.n = 4;
    }
    s
}

/// The flux-weighted mean x of the VPLs the last frame appended after `scene_lights`.
fn vpl_centre_x(r: &Renderer, prepared: &PreparedFrame, scene_lights: usize) -> f32 {
    let vpls = prepared.render(r).unwrap().vpls[0].spawned as usize;
    assert!(vpls > 20, "{vpls} VPLs");
    let geometry = prepared.read_buffer(r, "light_geometry").unwrap();
    let properties = prepared.read_buffer(r, "light_properties").unwrap();
    let (g, p): (&[f32], &[f32]) = (
        bytemuck::cast_slice(&geometry),
        bytemuck::cast_slice(&properties),
    );
    let (mut sum, mut weight) = (0.0, 0.0);
    for i in scene_lights..scene_lights + vpls {
        let flux = p[8 * i] + p[8 * i + 1] + p[8 * i + 2];
        sum += flux * g[8 * i];
        weight += flux;
    }
    sum / weight
}

#[test]
fn a_moved_indirect_light_moves_its_maps_and_vpls_as_a_fresh_prepare_would() {
    let mut r = renderer();
    let scene = cornell_indirect();
    // Left (red wall) and right (green wall) of the box, off the floor.
    let at = |x: f32| {
        let mut l = scene.lights[0];
        l.position = Vec3::new(x, 0.6, 0.1);
        l
    };
    let (a, b) = (at(-0.55), at(0.55));
    let mut start = scene.clone();
    start.lights = vec![a];
    // Room for a second light, added below.
    let (prepared, gpu) = prepare(&mut r, "indirect_vpl.ron", &start, 2);
    let before = prepared.render(&r).unwrap().image;
    let centre_a = vpl_centre_x(&r, &prepared, 1);
    prepared.update_lights(&r, &gpu, &[b]).unwrap();
    let moved = prepared.render(&r).unwrap();
    let mut at_b = scene.clone();
    at_b.lights = vec![b];
    let (fresh, _) = prepare(&mut r, "indirect_vpl.ron", &at_b, 0);
    let fresh_image = fresh.render(&r).unwrap().image;
    assert_eq!(moved.image.len(), (W * H) as usize);
    // The same VPLs from the same maps, appended in whatever order the atomic slots
    // were taken: only the order lights are summed in may differ, over at most 97
    // lights (96 candidates and the light): 97 × 2^-24 ≈ 5.8e-6 of the peak (lavapipe
    // measured 0).
    let (d, px) = max_rel_diff(&moved.image, &fresh_image);
    assert!(d <= 6e-6, "moved vs fresh prepare: {d:e} at pixel {px}");
    assert_eq!(
        moved.vpls[0].spawned,
        fresh.render(&r).unwrap().vpls[0].spawned
    );
    // The VPLs followed the light across the box: their flux sat on the left (red
    // wall) side, now on the right.
    let centre_b = vpl_centre_x(&r, &prepared, 1);
    assert!(
        centre_a < -0.2 && centre_b > 0.2,
        "VPL centre x {centre_a} at A, {centre_b} after the move to B"
    );
    // And the old place went dark: the left half of the frame loses most of its light
    // (measured: 39% of it stays).
    let left = |image: &[[f32; 4]]| -> f32 {
        image
            .iter()
            .enumerate()
            .filter(|(i, _)| (*i as u32 % W) < W / 2)
            .map(|(_, p)| p[0] + p[1] + p[2])
            .sum()
    };
    assert!(
        left(&moved.image) < 0.5 * left(&before),
        "left half {} after the move, {} before",
        left(&moved.image),
        left(&before)
    );
    // A second, plain light: the VPLs now go after two scene lights.
    let plain = Light::point(Vec3::new(0.0, 1.5, 0.5), 3.0, Vec3::ONE, 0.5);
    prepared.update_lights(&r, &gpu, &[b, plain]).unwrap();
    let two = prepared.render(&r).unwrap();
    let mut with_plain = scene.clone();
    with_plain.lights = vec![b, plain];
    let (fresh, _) = prepare(&mut r, "indirect_vpl.ron", &with_plain, 0);
    let (d, px) = max_rel_diff(&two.image, &fresh.render(&r).unwrap().image);
    assert!(
        d <= 6e-6,
        "two lights vs fresh prepare: {d:e} at pixel {px}"
    );
    assert_eq!(two.vpls[0].scene_lights, 2);
    // VPL controls go by light index: as light 1 the indirect light gets the default
    // n = 8, four times the candidates the frame was prepared for. Refused, by pass.
    let e = prepared
        .update_lights(&r, &gpu, &[plain, b])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("'vpl_spawn'")
            && e.contains("make 384 VPL candidates")
            && e.contains("prepared for 96"),
        "{e}"
    );
}

/// A motion written as in a scene file (paths can only be made so).
fn motion(ron_text: &str) -> Motion {
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(ron_text)
        .expect("a motion")
}

/// `scene`'s 160 lights in four runs: orbiting (tilted axis) and flickering, on a
/// Catmull–Rom path while orbiting, on a straight path while flickering, and still.
fn four_motions(mut scene: Scene) -> Scene {
    let run = |first: u32, motion: Motion| LightMotion {
        first,
        count: 40,
        motion,
    };
    scene.light_motion = vec![
        run(
            0,
            motion(
                "(orbit: (centre: (1, 2, -17), axis: (0.3, 1, -0.2), speed_deg: 47),
                  flicker: (amplitude: 0.9, frequency: 5, seed: 12345678901))",
            ),
        ),
        run(
            40,
            motion(
                "(orbit: (centre: (-2, 0, -12), speed_deg: -30),
                  path: (points: [(-3, 0, 0), (3, 1, 0), (0, 2, 4), (1, -1, 1)], period: 2.7,
                         interpolation: CatmullRom))",
            ),
        ),
        run(
            80,
            motion(
                "(path: (points: [(0, 0, 0), (4, 0, -3), (-2, 3, 1)], period: 1.3),
                  flicker: (amplitude: 0.5, frequency: 11, seed: 3))",
            ),
        ),
    ];
    scene
}

/// `lights` as the GPU should hold them.
fn gpu_lights(
    lights: &[Light],
) -> (
    Vec<lightgraph::gpu::structs::GpuLightGeometry>,
    Vec<lightgraph::gpu::structs::GpuLightProperties>,
) {
    lights
        .iter()
        .map(lightgraph::gpu::structs::gpu_light)
        .unzip()
}

/// The light buffers as the GPU holds them: (geometry, properties) as f32 words, 8 a light.
fn light_buffers_on_gpu(r: &Renderer, gpu: &SceneGpu) -> (Vec<f32>, Vec<f32>) {
    let read = |b| {
        let bytes = lightgraph::gpu::readback::read_buffer(&r.ctx.device, &r.ctx.queue, b).unwrap();
        bytemuck::cast_slice::<u8, f32>(&bytes).to_vec()
    };
    (read(&gpu.light_geometry), read(&gpu.light_properties))
}

#[test]
fn gpu_motion_writes_what_the_cpu_motion_evaluates() {
    let mut r = renderer();
    let scene = four_motions(random_scene(160, 8));
    let (prepared, gpu) = prepare(&mut r, "forward_plus.ron", &scene, 0);
    prepared
        .set_light_motion(&r, &gpu, &scene.lights, &scene.light_motion)
        .unwrap();
    let placed = gpu_lights(&scene.lights);
    let mut cpu = Vec::new();
    // A long run too: the phases are taken in f64, so it stays as tight as time 0.
    for t in [0.0, 0.37, 2.5, 7.9, 1234.5] {
        prepared.move_lights_to(&r, t).unwrap();
        prepared.execute(&r).unwrap();
        let (g, p) = light_buffers_on_gpu(&r, &gpu);
        assert!(g.len() >= 8 * 160 && p.len() >= 8 * 160);
        scene.lights_at(t, &mut cpu);
        let (want_g, want_p) = gpu_lights(&cpu);
        let mut moved = 0;
        for i in 0..160 {
            let (wg, wp) = (want_g[i], want_p[i]);
            let at = |k: usize| -> &[f32] { &g[8 * i + k..8 * i + k + 3] };
            let position = Vec3::from_slice(at(0));
            let direction = Vec3::from_slice(at(4));
            let color = Vec3::from_slice(&p[8 * i..8 * i + 3]);
            // The same f32 operations on both sides (phases from the CPU, no sines on the
            // GPU), but the GPU may fuse a multiply and add or sum a dot product in
            // another order: each a rounding of at most 2^-24 of the magnitude, and about
            // ten of them stand between a light's place and its coordinates (tens of
            // metres). 16 roundings of it bound that (lavapipe: 0; the spot directions,
            // normalised again on the CPU, 4).
            let scale = Vec3::from(wg.position).abs().max_element().max(20.0);
            let d = (position - Vec3::from(wg.position)).abs().max_element();
            assert!(
                d <= scale * 2f32.powi(-20),
                "t {t} light {i}: position {position} vs {:?}",
                wg.position
            );
            // Unit vectors: the same bound at magnitude 1.
            let d = (direction - Vec3::from(wg.direction)).abs().max_element();
            assert!(
                d <= 2f32.powi(-20),
                "t {t} light {i}: direction {direction} vs {:?}",
                wg.direction
            );
            // Colour × intensity × (1 + amplitude × noise): the noise's lattice values are
            // exact integers on both sides; three roundings of the product, at most 2×
            // the placed colour (amplitude ≤ 1).
            let peak = Vec3::from(placed.1[i].color).max_element() * 2.0;
            let d = (color - Vec3::from(wp.color)).abs().max_element();
            assert!(
                d <= peak * 2f32.powi(-21),
                "t {t} light {i}: colour {color} vs {:?}",
                wp.color
            );
            // The rest is copied: bit for bit.
            assert_eq!(g[8 * i + 3].to_bits(), wg.range.to_bits());
            assert_eq!(g[8 * i + 7].to_bits(), wg.cos_outer.to_bits());
            assert_eq!(p[8 * i + 3].to_bits(), wp.cos_inner.to_bits());
            assert_eq!(
                [p[8 * i + 4].to_bits(), p[8 * i + 5].to_bits()],
                [wp.flags, wp.material_mask]
            );
            if i >= 120 {
                assert_eq!(
                    position.to_array(),
                    placed.0[i].position,
                    "light {i} stands still"
                );
                assert_eq!(
                    color.to_array(),
                    placed.1[i].color,
                    "light {i} stands still"
                );
            } else if (position - Vec3::from(placed.0[i].position)).length() > 0.1 {
                moved += 1;
            }
        }
        assert!(
            t == 0.0 || moved > 100,
            "t {t}: only {moved} of 120 lights moved"
        );
    }
    // The caller takes over again: what it writes is what the buffers hold (its spot
    // directions normalised on the way).
    prepared.update_lights(&r, &gpu, &scene.lights).unwrap();
    assert!(!prepared.has_light_motion());
    prepared.execute(&r).unwrap();
    let (g, _) = light_buffers_on_gpu(&r, &gpu);
    let unit: Vec<Light> = scene
        .lights
        .iter()
        .map(|l| {
            let mut l = *l;
            if let lightgraph::scene::LightShape::Spot { direction, .. } = &mut l.shape {
                *direction = direction.normalize();
            }
            l
        })
        .collect();
    let (written, _) = gpu_lights(&unit);
    let written: &[f32] = bytemuck::cast_slice(&written);
    assert!(
        g[..8 * 160] == *written,
        "the caller's lights are not what the buffer holds"
    );
}

#[test]
fn gpu_motion_moves_shadow_casters_the_atlas_follows() {
    let mut r = renderer();
    let mut scene = random_scene(0, 4);
    let caster = |p: Vec3| {
        let mut l = Light::point(p, 10.0, Vec3::ONE, 20.0);
        l.flags = lightgraph::scene::light_flags::CASTS_SHADOW;
        l
    };
    scene.lights = vec![
        caster(Vec3::new(-4.0, 2.0, -8.0)),
        caster(Vec3::new(3.0, 5.0, -20.0)),
    ];
    scene.light_motion = vec![LightMotion {
        first: 0,
        count: 2,
        motion: motion(
            "(orbit: (centre: (0, 0, -14), speed_deg: 20),
              path: (points: [(0, 0, 0), (1, 0.5, 0)], period: 4))",
        ),
    }];
    let (prepared, gpu) = prepare(&mut r, "shadow_atlas.ron", &scene, 0);
    prepared
        .set_light_motion(&r, &gpu, &scene.lights, &scene.light_motion)
        .unwrap();
    let t = 3.0;
    prepared.move_lights_to(&r, t).unwrap();
    let moved = prepared.render(&r).unwrap().image;
    // The casters at t placed from the start: the same atlas allocation and views (the
    // CPU evaluated the casters), the same places on the GPU, so the same image.
    let mut at_t = Vec::new();
    scene.lights_at(t, &mut at_t);
    let mut still_scene = scene.clone();
    still_scene.light_motion.clear();
    assert_same(
        &moved,
        &still(&mut r, "shadow_atlas.ron", &still_scene, &at_t),
        "atlas at t",
    );
    assert_differs(
        &moved,
        &still(&mut r, "shadow_atlas.ron", &still_scene, &scene.lights),
        "vs placed",
    );
}

#[test]
fn gpu_motion_moves_an_indirect_light_its_maps_and_vpls_follow() {
    let mut r = renderer();
    let mut scene = cornell_indirect();
    // From the left of the box (red wall) to the right (green wall) and back.
    scene.lights[0].position = Vec3::new(-0.55, 0.6, 0.1);
    scene.light_motion = vec![LightMotion {
        first: 0,
        count: 1,
        motion: motion("(path: (points: [(0, 0, 0), (1.1, 0, 0)], period: 2))"),
    }];
    let (prepared, gpu) = prepare(&mut r, "indirect_vpl.ron", &scene, 0);
    prepared
        .set_light_motion(&r, &gpu, &scene.lights, &scene.light_motion)
        .unwrap();
    let centre_placed = vpl_centre_x(&r, &prepared, 1);
    prepared.move_lights_to(&r, 1.0).unwrap();
    let moved = prepared.render(&r).unwrap();
    let mut fresh_scene = scene.clone();
    scene.lights_at(1.0, &mut fresh_scene.lights);
    fresh_scene.light_motion.clear();
    assert!((fresh_scene.lights[0].position.x - 0.55).abs() < 1e-6);
    let (fresh, _) = prepare(&mut r, "indirect_vpl.ron", &fresh_scene, 0);
    let fresh = fresh.render(&r).unwrap();
    assert_eq!(moved.image.len(), (W * H) as usize);
    // The bound of the update_lights test above: the same VPLs, summed in another order.
    let (d, px) = max_rel_diff(&moved.image, &fresh.image);
    assert!(
        d <= 6e-6,
        "moved on the GPU vs fresh prepare: {d:e} at pixel {px}"
    );
    assert_eq!(moved.vpls[0].spawned, fresh.vpls[0].spawned);
    let centre_moved = vpl_centre_x(&r, &prepared, 1);
    assert!(
        centre_placed < -0.2 && centre_moved > 0.2,
        "VPL centre x {centre_placed} placed, {centre_moved} moved"
    );
}

/// An update writes the light buffers as a fresh upload of the same lights does, to the
/// bit: the same image through the brute-force graph (every light in the same order, so
/// any difference is the lights' bytes). The spots' directions come normalised, as
/// scene loading leaves them; normalising them a second time on update only (what the
/// update used to do) moves a last bit of about a third of them.
#[test]
fn an_update_writes_the_lights_a_fresh_upload_writes() {
    let mut r = renderer();
    let scene = random_scene(96, 9);
    let mut moved = scene.lights.clone();
    for (i, l) in moved.iter_mut().enumerate() {
        l.position.x += 0.5 * ((i % 7) as f32 - 3.0);
        if let LightShape::Spot { direction, .. } = &mut l.shape {
            *direction = (*direction + Vec3::new(0.3, 0.1 * (i % 3) as f32, -0.2)).normalize();
        }
    }
    assert!(moved
        .iter()
        .any(|l| matches!(l.shape, LightShape::Spot { .. })));
    let (prepared, gpu) = prepare(&mut r, "brute_force.ron", &scene, 0);
    prepared.update_lights(&r, &gpu, &moved).unwrap();
    let updated = prepared.render(&r).unwrap().image;
    let fresh = still(&mut r, "brute_force.ron", &scene, &moved);
    assert_eq!(updated.len(), (W * H) as usize);
    let differing = updated.iter().zip(&fresh).filter(|(a, b)| a != b).count();
    assert_eq!(
        differing, 0,
        "{differing} pixels differ from a fresh upload"
    );
}
