//! `lightgraph view` in a real X window (Xvfb) on the real adapter: its screenshot, taken
//! from the window's own swapchain image, shows the scene exactly as `lightgraph render`
//! draws it, with the overlay on top. scripts/test.sh installs Xvfb when it is missing.

use lightgraph::bench::image_io::read_exr;
use lightgraph::bench::Tonemap;
use std::path::Path;
use std::process::Command;

const WINDOW: [u32; 2] = [720, 400];
/// The window renders at a quarter of its size; the present pass scales it up (nearest).
const SCALE: f32 = 0.25;
const RENDER: [u32; 2] = [180, 100];

fn lightgraph() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_lightgraph"));
    c.env(
        "XDG_RUNTIME_DIR",
        std::env::var("XDG_RUNTIME_DIR").unwrap_or("/tmp".into()),
    );
    c
}

fn run(mut c: Command, what: &str) {
    let out = c.output().unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(
        out.status.success(),
        "{what} failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn window_shows_the_rendered_scene_and_the_overlay() {
    assert!(
        Command::new("xvfb-run").arg("--help").output().is_ok(),
        "xvfb-run is missing: install xvfb (scripts/test.sh does)"
    );
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = root.join("scenes/harada.ron");
    let graph = root.join("graphs/forward_plus.ron");
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("view.png");
    let reference = dir.path().join("render.exr");

    let mut view = Command::new("xvfb-run");
    view.args(["-a", "-s", "-screen 0 1024x768x24"])
        .arg(env!("CARGO_BIN_EXE_lightgraph"))
        .arg("view")
        .arg("--scene")
        .arg(&scene)
        .arg("--graph")
        .arg(&graph)
        .args(["--width", &WINDOW[0].to_string()])
        .args(["--height", &WINDOW[1].to_string()])
        .args(["--scale", &SCALE.to_string()])
        .args(["--frames", "3"])
        .arg("--screenshot")
        .arg(&shot);
    run(view, "lightgraph view under Xvfb");

    let mut render = lightgraph();
    render
        .arg("render")
        .arg("--scene")
        .arg(&scene)
        .arg("--graph")
        .arg(&graph)
        .args(["--width", &RENDER[0].to_string()])
        .args(["--height", &RENDER[1].to_string()])
        .arg("--out")
        .arg(&reference);
    run(render, "lightgraph render");

    let shot = image::open(&shot).unwrap().to_rgb8();
    assert_eq!(shot.dimensions(), (WINDOW[0], WINDOW[1]));
    let hdr = read_exr(&reference).unwrap();
    let expected = Tonemap::default().image_to_srgb8(&hdr.pixels);
    let expected_at = |x: u32, y: u32| {
        // The present shader's mapping from window pixel centre to render texel.
        let tx = ((x as f32 + 0.5) * RENDER[0] as f32 / WINDOW[0] as f32) as u32;
        let ty = ((y as f32 + 0.5) * RENDER[1] as f32 / WINDOW[1] as f32) as u32;
        let i = 3 * (ty * RENDER[0] + tx) as usize;
        [expected[i], expected[i + 1], expected[i + 2]]
    };
    let diff = |x: u32, y: u32| {
        let got = shot.get_pixel(x, y).0;
        let want = expected_at(x, y);
        (0..3).map(|c| got[c].abs_diff(want[c])).max().unwrap()
    };

    // Right of the overlay (egui's window starts at the top left, about 300 px wide):
    // the scene itself. The GPU's sRGB encode and the CPU's may round a code apart; a
    // silhouette pixel may flip where the viewer's camera (rebuilt from yaw, pitch and
    // distance) differs from the scene's by float rounding.
    let (mut compared, mut off_by_more, mut lit) = (0u32, 0u32, 0u32);
    for y in 0..WINDOW[1] {
        for x in 360..WINDOW[0] {
            compared += 1;
            off_by_more += (diff(x, y) > 2) as u32;
            lit += (shot.get_pixel(x, y).0.iter().any(|&c| c > 16)) as u32;
        }
    }
    assert!(lit > compared / 4, "the scene is lit: {lit} of {compared}");
    assert!(
        off_by_more * 200 <= compared,
        "{off_by_more} of {compared} window pixels differ from the render by more than 2 codes"
    );

    // The overlay covers part of the top left: many pixels there are not the scene.
    let overlay_pixels = (0..200)
        .flat_map(|y| (0..280).map(move |x| (x, y)))
        .filter(|&(x, y)| diff(x, y) > 24)
        .count();
    assert!(
        overlay_pixels > 5_000,
        "the overlay should cover the top left; only {overlay_pixels} pixels differ there"
    );
    // But no more than a quarter of the window (it covered 40% of this one once).
    let covered = (0..WINDOW[1])
        .flat_map(|y| (0..WINDOW[0]).map(move |x| (x, y)))
        .filter(|&(x, y)| diff(x, y) > 24)
        .count() as u32;
    assert!(
        covered * 4 <= WINDOW[0] * WINDOW[1],
        "the overlay covers {covered} of {} window pixels",
        WINDOW[0] * WINDOW[1]
    );
}
