//! Headless hot reload on the real adapter: edit a shader and the next frame changes;
//! break it and the error names the line while the frame stays; fix it and it recovers.
//! The same for a graph. Waits are bounded waits on the watcher's events.

mod common;
use common::*;
use lightgraph::reload::{ReloadSession, SceneSource};
use lightgraph::render::Renderer;
use lightgraph::shader::ShaderLibrary;
use std::path::{Path, PathBuf};
use std::time::Duration;

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

/// Waits (bounded) until a reload that touched `file` has happened.
fn reload_of(s: &mut ReloadSession, file: &Path) -> Result<Duration, String> {
    for _ in 0..20 {
        if let Some(r) = s.wait(Duration::from_secs(5)) {
            if r.changed
                .iter()
                .any(|c| c.ends_with(file.file_name().unwrap()))
            {
                return r.outcome;
            }
        }
    }
    panic!("no reload of {} within 100 s", file.display());
}

/// A reload session over a copy of the project's shaders and `forward_plus.ron` in
/// `dir` (a renderer of its own reading that copy), 48 random lights at 96×64: the
/// session, the shaders folder and the graph file, for the test to edit.
fn session_on_copy(dir: &Path) -> (ReloadSession, PathBuf, PathBuf) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let shaders = dir.join("shaders");
    copy_dir(&root.join("shaders"), &shaders);
    let graph: PathBuf = dir.join("forward_plus.ron");
    std::fs::copy(root.join("graphs/forward_plus.ron"), &graph).unwrap();
    let renderer = Renderer::new(
        lightgraph::gpu::GpuContext::new_headless().unwrap(),
        ShaderLibrary::new(&shaders),
    );
    let scene = random_scene(48, 3);
    let s = ReloadSession::new(
        renderer,
        &graph,
        SceneSource::Fixed(Box::new(scene)),
        96,
        64,
        &[],
    )
    .unwrap();
    (s, shaders, graph)
}

#[test]
fn shader_and_graph_edits_reload_and_errors_keep_the_last_frame() {
    let dir = tempfile::tempdir().unwrap();
    let (mut s, shaders, graph) = session_on_copy(dir.path());
    let first = s.frame.as_ref().unwrap().image.clone();
    assert_eq!(first.len(), 96 * 64);
    assert!(first.iter().any(|p| p[0] > 0.0), "the scene is lit");
    // Frustum culling's lists: a graph reload to DepthMask must change them.
    let frustum_counts = s.frame.as_ref().unwrap().culling[0].counts.clone();

    // 1. A shader constant: twice the range window doubles every light's contribution.
    let lighting = shaders.join("common/lighting.wgsl");
    let original = std::fs::read_to_string(&lighting).unwrap();
    let doubled = original.replace(
        "return clamp(1.0 - r * r, 0.0, 1.0);",
        "return 2.0 * clamp(1.0 - r * r, 0.0, 1.0);",
    );
    assert_ne!(doubled, original);
    std::fs::write(&lighting, &doubled).unwrap();
    let latency = reload_of(&mut s, &lighting).expect("the edited shader compiles");
    println!("shader edit to new frame: {latency:?} (lavapipe)");
    let second = s.frame.as_ref().unwrap().image.clone();
    assert_eq!(second.len(), first.len());
    for (a, b) in second.iter().zip(&first) {
        for c in 0..3 {
            // The window is at most 1, doubled exactly; the sum of doubled terms is the
            // doubled sum up to rounding.
            assert!(
                (a[c] - 2.0 * b[c]).abs() <= 1e-5 * a[c].abs().max(1e-3),
                "{a:?} vs 2x {b:?}"
            );
        }
    }

    // 2. A broken shader: the error names the file and line; the frame stays.
    let broken = doubled.replace("fn range_window(", "fn range_window(oops ");
    let line = broken.lines().position(|l| l.contains("oops")).unwrap() + 1;
    std::fs::write(&lighting, &broken).unwrap();
    let err = reload_of(&mut s, &lighting).expect_err("a broken shader must not load");
    assert!(err.contains(&format!("lighting.wgsl:{line}:")), "{err}");
    assert_eq!(
        s.frame.as_ref().unwrap().image,
        second,
        "the last good frame stays"
    );
    assert!(s.error.is_some());

    // 3. Fixing it recovers: back to the original constant gives the first frame.
    std::fs::write(&lighting, &original).unwrap();
    reload_of(&mut s, &lighting).expect("the fixed shader loads");
    assert_eq!(s.frame.as_ref().unwrap().image, first);
    assert!(s.error.is_none());

    // 4. A graph edit: another culling variant gives the same image.
    let text = std::fs::read_to_string(&graph).unwrap();
    std::fs::write(
        &graph,
        text.replace("variant: Frustum", "variant: DepthMask"),
    )
    .unwrap();
    reload_of(&mut s, &graph).expect("the edited graph compiles");
    let (d, _) = max_rel_diff(&s.frame.as_ref().unwrap().image, &first);
    assert!(d < 2e-6, "{d}");
    // The same image from other lists: the new graph ran (a no-op reload keeps Frustum's).
    let mask_counts = &s.frame.as_ref().unwrap().culling[0].counts;
    assert_eq!(mask_counts.len(), frustum_counts.len());
    assert!(
        mask_counts.iter().zip(&frustum_counts).all(|(m, f)| m <= f)
            && mask_counts.iter().sum::<u32>() < frustum_counts.iter().sum::<u32>(),
        "DepthMask lists are shorter than Frustum's"
    );

    // 5. A broken graph (an unknown resource) keeps the frame and names the line.
    let bad = text.replace("writes: [\"light_lists\"]", "writes: [\"light_list\"]");
    let line = bad
        .lines()
        .position(|l| l.contains("\"light_list\""))
        .unwrap()
        + 1;
    std::fs::write(&graph, &bad).unwrap();
    let err = reload_of(&mut s, &graph).expect_err("a broken graph must not load");
    assert!(err.contains(&format!("forward_plus.ron:{line}:")), "{err}");
    assert!(s.frame.is_some());

    // 6. And recovers.
    std::fs::write(&graph, &text).unwrap();
    reload_of(&mut s, &graph).expect("the fixed graph loads");
    assert_eq!(s.frame.as_ref().unwrap().image, first);
    assert_eq!(
        s.frame.as_ref().unwrap().culling[0].counts,
        frustum_counts,
        "back to Frustum's lists"
    );
}

/// The lobe library (`shaders/material/lobes.wgsl`) is a shader file like any other: the
/// generated material code includes it from the root, so an edit reloads every
/// material's pipelines, and a broken edit names the library's line.
#[test]
fn lobe_library_edits_reload_the_materials() {
    let dir = tempfile::tempdir().unwrap();
    let (mut s, shaders, _graph) = session_on_copy(dir.path());
    let first = s.frame.as_ref().unwrap().image.clone();
    assert!(first.iter().any(|p| p[0] > 0.0), "the scene is lit");

    // Twice the Lambert lobe: every lit pixel brightens, none darkens.
    let lobes = shaders.join("material/lobes.wgsl");
    let original = std::fs::read_to_string(&lobes).unwrap();
    let doubled = original.replace(
        "    return color * LG_INV_PI;",
        "    return 2.0 * color * LG_INV_PI;",
    );
    assert_ne!(doubled, original);
    std::fs::write(&lobes, &doubled).unwrap();
    reload_of(&mut s, &lobes).expect("the edited library compiles");
    let second = s.frame.as_ref().unwrap().image.clone();
    assert_eq!(second.len(), first.len());
    let brighter = second
        .iter()
        .zip(&first)
        .filter(|(a, b)| a[0] > b[0] * 1.01)
        .count();
    assert!(brighter > 100, "only {brighter} pixels brightened");
    assert!(second.iter().zip(&first).all(|(a, b)| a[0] >= b[0]));

    // Broken: the error names the library's file and line; the frame stays.
    let broken = doubled.replace("fn lg_lambert(", "fn lg_lambert(oops ");
    let line = broken.lines().position(|l| l.contains("oops")).unwrap() + 1;
    std::fs::write(&lobes, &broken).unwrap();
    let err = reload_of(&mut s, &lobes).expect_err("a broken library must not load");
    assert!(err.contains(&format!("lobes.wgsl:{line}:")), "{err}");
    assert_eq!(s.frame.as_ref().unwrap().image, second);

    // Back to the original: the first frame again.
    std::fs::write(&lobes, &original).unwrap();
    reload_of(&mut s, &lobes).expect("the restored library loads");
    assert_eq!(s.frame.as_ref().unwrap().image, first);
}

/// Reloads leave nothing behind on the GPU: over the reload benchmark's edits (a shader,
/// a material and a graph, each with a new value, every one rebuilding pipelines and the
/// graph edit re-planning resources), the number of live GPU memory allocations stays
/// what it was after the first round, and so do their bytes up to 4 KiB: a few buffers'
/// sizes follow the edited values (the light lists' capacity), tens of bytes on lavapipe
/// at this size. A reload that kept the replaced frame, its resources or a queue of
/// frames alive would add allocations every round.
#[test]
fn reloads_do_not_accumulate_gpu_memory() {
    use lightgraph::bench::reload_latency as rl;
    let gpu = lightgraph::gpu::GpuContext::new_headless().unwrap();
    let device = gpu.device.clone();
    if device.generate_allocator_report().is_none() {
        eprintln!("this adapter gives no allocator report: nothing to check");
        return;
    }
    let work = tempfile::tempdir().unwrap();
    let config = rl::ReloadBenchConfig {
        project: Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf(),
        work: work.path().join("w"),
        width: 32,
        height: 24,
        lights: 64,
        repeats: 5,
        salt: 0,
        frames_in_flight: 0,
        viewer_frames: 2,
        wait_for_idle_before_build: false,
        sequential_builds: false,
    };
    // (kind, edit index, allocations, bytes), after the edit's frame and the same frame
    // again (whose blocking poll lets wgpu free what the replaced frame held).
    let mut seen = Vec::new();
    rl::run(&config, gpu, |s| {
        let report = device
            .generate_allocator_report()
            .expect("a report as before");
        seen.push((
            s.kind,
            s.index,
            report.allocations.len(),
            report.total_allocated_bytes,
        ));
    })
    .unwrap();
    assert_eq!(seen.len(), 3 * config.repeats);
    for kind in rl::EditKind::ALL {
        let of: Vec<_> = seen.iter().filter(|s| s.0 == kind).collect();
        let (_, _, allocations, bytes) = *of[0];
        for &&(_, index, a, b) in &of[1..] {
            assert_eq!(a, allocations, "{kind} edit {index}: allocations {seen:?}");
            assert!(
                b.abs_diff(bytes) <= 4096,
                "{kind} edit {index}: bytes {seen:?}"
            );
        }
    }
}
