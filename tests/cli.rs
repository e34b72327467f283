//! The command line's manners, run as a new user would: the README's first command writes
//! a picture, usage errors and bad flags are reported before anything renders, `compare`
//! leads with a summary line, `bench` without --sweep says which sweep it picked.

use std::path::Path;
use std::process::{Command, Output};

/// The built binary in `dir`, with no root and no runtime dir from the environment.
fn lightgraph(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lightgraph"))
        .current_dir(dir)
        .args(args)
        .env_remove("LIGHTGRAPH_ROOT")
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .expect("the binary runs")
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn no_arguments_writes_lightgraph_png_sized_for_the_adapter() {
    let dir = tempfile::tempdir().unwrap();
    let o = lightgraph(dir.path(), &[]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let png = dir.path().join("lightgraph.png");
    let shown = std::path::absolute(&png).unwrap();
    assert!(out.contains(&format!("wrote {}", shown.display())), "{out}");
    let image = image::open(&png).expect("a PNG").to_rgb8();
    // The progress line says how the size was picked; a software adapter gets 640x360.
    assert!(err.contains("rendering atrium (1024 lights) at "), "{err}");
    if err.contains("software adapter: small size") {
        assert_eq!(image.dimensions(), (640, 360));
    } else {
        assert!(err.contains("GPU adapter: the scene's full size"), "{err}");
        assert_eq!(image.dimensions(), (1920, 1080));
    }
    assert!(!err.contains("XDG_RUNTIME_DIR"), "{err}");
    let lit = image
        .pixels()
        .filter(|p| p.0.iter().any(|&c| c > 8))
        .count();
    assert!(lit * 2 > image.pixels().len(), "{lit} lit pixels");
}

/// In a checkout (the root has scenes/gallery.ron) no arguments render the gallery, its
/// glTF models, 1,027 lights (three casting shadows) and glass, through the default graph,
/// and say where the picture went.
#[test]
fn no_arguments_in_a_checkout_render_the_gallery() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let o = lightgraph(dir.path(), &["--root", root.to_str().unwrap()]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(err.contains("rendering gallery (1027 lights) at "), "{err}");
    assert!(out.contains("shadow_ray_cast"), "{out}");
    // AlphaBlendModeTest's masked strips: six triangles whose cut-outs rays pass through.
    assert!(
        out.contains("shadow rays alpha-test 6 triangles of alpha-masked casters"),
        "{out}"
    );
    assert!(out.contains("graphs/default.ron, "), "{out}");
    assert!(out.contains("transparent_shading"), "{out}");
    assert!(!err.contains("TransparentShading"), "{err}");
    let png = dir.path().join("lightgraph.png");
    let shown = std::path::absolute(&png).unwrap();
    assert!(out.contains(&format!("wrote {}", shown.display())), "{out}");
    let image = image::open(&png).expect("a PNG").to_rgb8();
    if err.contains("software adapter: small size") {
        assert_eq!(image.dimensions(), (640, 360));
    }
}

#[test]
fn validate_without_files_is_a_usage_error() {
    let dir = tempfile::tempdir().unwrap();
    let o = lightgraph(dir.path(), &["validate"]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("<FILE>"), "{err}");
}

#[test]
fn bad_flags_are_reported_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    for (args, says) in [
        (
            &["render", "--out", "x.jpg"][..],
            "must end in .png or .exr",
        ),
        (&["render", "--heatmap", "h.jpg"][..], "must end in .png"),
        (
            &[
                "render",
                "--graph",
                "<built-in>/graphs/brute_force.ron",
                "--heatmap",
                "h.png",
            ][..],
            "--heatmap needs a graph with a LightCulling pass",
        ),
    ] {
        let o = lightgraph(dir.path(), args);
        let (out, err) = text(&o);
        assert!(!o.status.success(), "{args:?}: {out}");
        assert!(err.contains(says), "{args:?}: {err}");
        // The progress line comes just before the GPU work: none was started.
        assert!(!err.contains("rendering"), "{args:?}: {err}");
        assert!(!out.contains("adapter:"), "{args:?}: {out}");
    }
    assert!(!dir.path().join("h.png").exists());
}

#[test]
fn compare_prints_a_summary_line_then_a_table() {
    let dir = tempfile::tempdir().unwrap();
    let a: Vec<[f32; 4]> = (0..64).map(|i| [i as f32 / 64.0, 0.5, 0.25, 1.0]).collect();
    let mut b = a.clone();
    b[10][0] += 0.5;
    lightgraph::bench::write_exr(dir.path().join("a.exr"), &a, 8, 8).unwrap();
    lightgraph::bench::write_exr(dir.path().join("b.exr"), &b, 8, 8).unwrap();
    let o = lightgraph(dir.path(), &["compare", "a.exr", "a.exr"]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert_eq!(out.lines().next(), Some("identical (8x8)"), "{out}");
    let o = lightgraph(dir.path(), &["compare", "a.exr", "b.exr"]);
    let (out, _) = text(&o);
    let mut lines = out.lines();
    let summary = lines.next().unwrap();
    assert!(
        summary.starts_with("differ: RMSE 3.608e-2, max abs 5.000e-1, 1 of 64 pixels over"),
        "{out}"
    );
    let table: Vec<&str> = lines.collect();
    for row in [
        "size        8x8",
        "RMSE        3.608",
        "max abs     5.0",
        "bad pixels  1",
    ] {
        assert!(
            table.iter().any(|l| l.starts_with(row)),
            "no row {row:?} in {out}"
        );
    }
    assert!(!out.contains("ImageMetrics {"), "{out}");
}

/// Images of different shapes but the same pixel count (64×36, 36×64, 48×48) are refused
/// naming both files and sizes, not compared as if one were the other; so is a 1×1 image
/// against a larger one (refused before without naming either file), while two 1×1
/// images compare.
#[test]
fn compare_refuses_different_sizes_and_one_pixel_images() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, w: u32, h: u32| {
        let px: Vec<[f32; 4]> = (0..w * h)
            .map(|i| [i as f32 / 2304.0, 0.5, 0.25, 1.0])
            .collect();
        lightgraph::bench::write_exr(dir.path().join(name), &px, w, h).unwrap();
    };
    write("wide.exr", 64, 36);
    write("tall.exr", 36, 64);
    write("square.exr", 48, 48);
    write("dot.exr", 1, 1);
    for (a, b, says) in [
        (
            "wide.exr",
            "tall.exr",
            "wide.exr is 64x36 but tall.exr is 36x64",
        ),
        (
            "wide.exr",
            "square.exr",
            "wide.exr is 64x36 but square.exr is 48x48",
        ),
        (
            "wide.exr",
            "dot.exr",
            "wide.exr is 64x36 but dot.exr is 1x1",
        ),
        (
            "dot.exr",
            "square.exr",
            "dot.exr is 1x1 but square.exr is 48x48",
        ),
    ] {
        let o = lightgraph(dir.path(), &["compare", a, b]);
        let (out, err) = text(&o);
        assert_eq!(o.status.code(), Some(1), "compare {a} {b}: {out}{err}");
        assert!(err.contains(says), "compare {a} {b}: {err}");
    }
    let o = lightgraph(dir.path(), &["compare", "dot.exr", "dot.exr"]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert_eq!(out.lines().next(), Some("identical (1x1)"), "{out}");
}

#[test]
fn bench_without_sweep_says_which_it_runs() {
    let dir = tempfile::tempdir().unwrap();
    let probe = lightgraph(dir.path(), &["render", "--width", "8", "--height", "8"]);
    let software = text(&probe).1.contains("llvmpipe") || text(&probe).0.contains("llvmpipe");
    if !software {
        return; // the headline sweep takes minutes even on a GPU: not run here
    }
    let o = lightgraph(dir.path(), &["bench", "--out", "report"]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let all = format!("{out}{err}");
    assert!(
        all.contains("no --sweep: running benches/sweeps/smoke.ron (3 points; software adapter"),
        "{all}"
    );
    assert!(dir.path().join("report/results.md").exists());
    // The smoke sweep lights most of its frame (it lit 76 of 14,400 pixels once).
    let csv = std::fs::read_to_string(dir.path().join("report/results.csv")).unwrap();
    let mut lines = csv.lines().map(csv_fields);
    let header = lines.next().unwrap();
    let lit = header.iter().position(|h| h == "lit_pixels").unwrap();
    let rows: Vec<Vec<String>> = lines.collect();
    assert_eq!(rows.len(), 3);
    for row in rows {
        let n: u64 = row[lit].parse().unwrap();
        assert!(n * 2 > 160 * 90, "{n} of 14,400 pixels lit: {row:?}");
    }
}

/// One CSV line's fields (quoted fields may hold commas; no escaped quotes here).
fn csv_fields(line: &str) -> Vec<String> {
    let (mut fields, mut field, mut quoted) = (Vec::new(), String::new(), false);
    for ch in line.chars() {
        match ch {
            '"' => quoted = !quoted,
            ',' if !quoted => fields.push(std::mem::take(&mut field)),
            c => field.push(c),
        }
    }
    fields.push(field);
    fields
}

/// `render --graph GRAPH --width 64 --height 36 EXTRA...` in `dir`, which must succeed:
/// its standard output.
fn render_64x36(dir: &Path, graph: &Path, extra: &[&str]) -> String {
    let mut args = vec!["render", "--graph", graph.to_str().unwrap()];
    args.extend(["--width", "64", "--height", "36"]);
    args.extend(extra);
    let o = lightgraph(dir, &args);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    out
}

#[test]
fn render_reports_the_link_pool_and_its_overflow() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let graph = root.join("graphs/light_linked_list_deferred.ron");
    let small = dir.path().join("small_pool.ron");
    std::fs::write(
        &small,
        std::fs::read_to_string(&graph).unwrap().replace(
            "LightLinkedList(scale: 1, links_per_pixel: 32)",
            "LightLinkedList(scale: 4, links_per_pixel: 1)",
        ),
    )
    .unwrap();
    for (g, overflow) in [(graph, false), (small, true)] {
        let out = render_64x36(dir.path(), &g, &[]);
        let scale = if overflow { 4 } else { 1 };
        let line = format!(
            "linked_list_build: {}x{} list pixels (1/{scale} per side)",
            64 / scale,
            36 / scale
        );
        assert!(out.contains(&line) && out.contains(" MiB ("), "{out}");
        assert_eq!(
            out.contains("WARNING: the link pool of 144 overflowed"),
            overflow,
            "{out}"
        );
    }
}

/// `lightgraph compare A B | head -1`: the reader closes the pipe after one line; the
/// command must end quietly (SIGPIPE), not panic on the next print.
#[test]
fn output_into_a_closed_pipe_ends_quietly() {
    use std::io::Read;
    use std::process::Stdio;
    let dir = tempfile::tempdir().unwrap();
    let a: Vec<[f32; 4]> = (0..64).map(|i| [i as f32 / 64.0, 0.5, 0.25, 1.0]).collect();
    let mut b = a.clone();
    b[3][1] = 2.0;
    lightgraph::bench::write_exr(dir.path().join("a.exr"), &a, 8, 8).unwrap();
    lightgraph::bench::write_exr(dir.path().join("b.exr"), &b, 8, 8).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_lightgraph"))
        .current_dir(dir.path())
        .args(["compare", "a.exr", "b.exr"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary runs");
    // Closed before the command writes anything: its first print hits a closed pipe.
    drop(child.stdout.take());
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    child.wait().unwrap();
    assert!(!err.contains("panicked"), "{err}");
    assert!(!err.contains("Broken pipe"), "{err}");
}

/// A graph whose only writer of the output is skipped by `when:` for this scene: a clear
/// error naming the graph line and the pass, not a panic (it was an `expect` in render).
#[test]
fn output_without_a_running_writer_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let graph = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("graphs/forward_plus.ron"),
    )
    .unwrap()
    .replace(
        "            writes: [\"hdr\"],\n",
        "            writes: [\"hdr\"],\n            when: Some(Transparent),\n",
    );
    assert!(graph.contains("when: Some(Transparent)"));
    // The error points at the output in the skipped pass's writes.
    let line = 1 + graph
        .lines()
        .position(|l| l.contains("writes: [\"hdr\"]"))
        .unwrap();
    std::fs::write(dir.path().join("g.ron"), graph).unwrap();
    let o = lightgraph(
        dir.path(),
        &[
            "render", "--graph", "g.ron", "--width", "32", "--height", "18", "--out", "x.png",
        ],
    );
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains(&format!("g.ron:{line}:"))
            && err.contains("pass 'forward_shading': output 'hdr' has no writer in this scene")
            && err.contains("when: Transparent is false"),
        "{err}"
    );
}

#[test]
fn render_reports_compact_lists_and_their_bound() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let graph = root.join("graphs/forward_plus.ron");
    let scene = root.join("scenes/harada.ron");
    let small = dir.path().join("small_bound.ron");
    let source = std::fs::read_to_string(&graph).unwrap();
    let shipped = "lists: Compact(max_indices: 16777216)";
    assert_eq!(source.matches(shipped).count(), 1);
    std::fs::write(
        &small,
        source.replace(shipped, "lists: Compact(max_indices: 1000)"),
    )
    .unwrap();
    for (g, bound) in [(graph, 16_777_216), (small, 1000)] {
        let out = render_64x36(dir.path(), &g, &["--scene", scene.to_str().unwrap()]);
        // Harada's 3,072 lights at 64x36 want 4,375 indices: fixed lists of 256 overflow
        // in six tiles, compact lists hold them all under the shipped bound (681 in the
        // scratch slots of the six lists of at most 256). Under 1,000 the slots are
        // lowered to 41 (they take at most half the bound: 1000 / (2 · 12)), no list is
        // that short, and the pool after the slots holds 508 of the 4,375.
        assert!(out.contains("light_culling: 12 tiles x 1 lists"), "{out}");
        let (held, slots) = if bound == 1000 {
            (508, "0 in scratch slots of 41")
        } else {
            (4375, "681 in scratch slots of 256")
        };
        assert!(
            out.contains(&format!("(compact, {held} of max_indices {bound}; ")),
            "{out}"
        );
        assert!(out.contains(&format!(" MiB; {slots})")), "{out}");
        let warning = "WARNING: light_culling: the lists wanted 4375 light indices, 4375 of them in lists longer than their scratch slot of 41, over the 508 the pool holds (max_indices 1000 less 492 in scratch slots): ";
        assert_eq!(out.contains(warning), bound == 1000, "{out}");
        if bound == 1000 {
            // Slots of the whole 256 and a pool for every pooled list: 12 · 256 + 4,375.
            assert!(out.contains("(max_indices: 7447 fits this frame)"), "{out}");
        }
    }
}

/// Glass through a graph without transparency passes is rendered without it, and `render`
/// says so once; a graph with them (the default one too) says nothing.
#[test]
fn render_warns_when_the_graph_draws_no_blended_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = root.join("scenes/glass.ron");
    let run = |graph: &str| {
        let g = root.join("graphs").join(graph);
        let out = dir.path().join("x.png");
        let o = lightgraph(
            dir.path(),
            &[
                "render",
                "--scene",
                scene.to_str().unwrap(),
                "--graph",
                g.to_str().unwrap(),
                "--width",
                "64",
                "--height",
                "36",
                "--out",
                out.to_str().unwrap(),
            ],
        );
        let (stdout, err) = text(&o);
        assert!(o.status.success(), "{graph}: {stdout}\n{err}");
        err
    };
    for graph in ["forward_plus.ron", "visibility_compute_raster.ron"] {
        let err = run(graph);
        // Once for the render, though it draws a warm-up frame and the reported one.
        assert_eq!(
            err.matches("has no TransparentShading pass: the scene's blended")
                .count(),
            1,
            "{graph}: {err}"
        );
    }
    for graph in ["transparent.ron", "default.ron"] {
        let err = run(graph);
        assert!(!err.contains("TransparentShading"), "{graph}: {err}");
    }
}
