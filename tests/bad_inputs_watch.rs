//! A running hot-reload session (what `lightgraph watch` runs) survives every bad input
//! saved over the files it watches: every bad graph and hostile scene of tests/bad over its
//! graph and scene, every bad material over a material the scene uses, and every bad
//! shader over a shader its graph runs. Each save ends in the error the bad file expects
//! (its own name replaced by the saved file's); after each, the last good frame is still
//! there and still renders what it rendered; the texture wider than the device is scaled
//! down; and the good files saved again render again. Every file of those folders is
//! saved (about 90 saves at 64×36 on lavapipe, most refused before any GPU work).

use lightgraph::reload::{ReloadSession, SceneSource};
use lightgraph::render::Renderer;
use std::path::Path;
use std::time::Duration;
#[path = "common/watched_project.rs"]
mod watched_project;
use watched_project::{expected, ron_files, root, WatchedProject};

/// The outcome of the reload that touched `file` (bounded wait).
fn save(s: &mut ReloadSession, file: &Path, text: &[u8]) -> Result<Duration, String> {
    std::fs::write(file, text).unwrap();
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

/// The kept frame rendered again against the image it rendered when it was good. The
/// same prepared frame on the same device: equal but for the order in which atomics
/// append lights to tile lists, which reorders each pixel's sum (a few f32 ulps of HDR
/// values below 100, so 1e-4 absolute).
fn still_renders(s: &ReloadSession, good: &[[f32; 4]]) -> Result<(), String> {
    let prepared = s.prepared().ok_or("no kept frame")?;
    let again = prepared.render(&s.renderer).map_err(|e| e.to_string())?;
    if again.image.len() != good.len() {
        return Err(format!("{} pixels, was {}", again.image.len(), good.len()));
    }
    let worst = again
        .image
        .iter()
        .zip(good)
        .flat_map(|(a, b)| (0..4).map(move |c| (a[c] - b[c]).abs()))
        .fold(0.0f32, f32::max);
    if worst > 1e-4 {
        return Err(format!("the kept frame renders differently (by {worst})"));
    }
    Ok(())
}

/// The saved file's name in place of the bad file's, in a message that names the file.
fn renamed(want: &str, bad: &Path, saved: &Path) -> String {
    let name = |p: &Path| p.file_name().unwrap().to_string_lossy().into_owned();
    want.replace(&name(bad), &name(saved))
}

#[test]
fn watch_survives_every_bad_save() {
    let project = WatchedProject::new();
    let (graph, material, scene) = (&project.graph, &project.material, &project.scene);
    let hostile = root().join("tests/bad/hostile");

    let renderer = Renderer::headless().unwrap();
    let mut s = ReloadSession::new(
        renderer,
        graph,
        SceneSource::File(scene.clone()),
        64,
        36,
        &[],
    )
    .unwrap();
    let good = s.frame.as_ref().expect("the first frame").image.clone();
    assert_eq!(good.len(), 64 * 36);
    let mut failures = Vec::new();
    let mut saved = 0;
    let mut check = |s: &mut ReloadSession, file: &Path, bad: &Path| {
        let text = std::fs::read(bad).unwrap();
        let Some(want) = expected(&String::from_utf8_lossy(&text)).map(str::to_string) else {
            return;
        };
        let want = renamed(&want, bad, file);
        match save(s, file, &text) {
            Err(e) if e.contains(&want) => {}
            other => failures.push(format!("{}: want {want:?}, got {other:?}", bad.display())),
        }
        if let Err(e) = still_renders(s, &good) {
            failures.push(format!("{}: {e}", bad.display()));
        }
        saved += 1;
    };
    for bad in ron_files(&root().join("tests/bad/graphs")) {
        check(&mut s, graph, &bad);
    }
    save(&mut s, graph, &project.good_graph).expect("the good graph recovers");
    for bad in ron_files(&hostile) {
        check(&mut s, scene, &bad);
    }
    save(&mut s, scene, &project.good_scene).expect("the good scene recovers");

    // Materials: `// expect:` is the message, `// at:` its place in the saved file.
    for bad in ron_files(&root().join("tests/bad/materials")) {
        let text = std::fs::read_to_string(&bad).unwrap();
        let mut lines = text.lines();
        let want = lines.next().and_then(|l| l.strip_prefix("// expect: "));
        let at = lines.next().and_then(|l| l.strip_prefix("// at: "));
        let (Some(want), Some(at)) = (want, at) else {
            failures.push(format!("{}: no `// expect:` and `// at:`", bad.display()));
            continue;
        };
        let place = format!("mat.ron:{at}: ");
        match save(&mut s, material, text.as_bytes()) {
            Err(e) if e.contains(want) && e.contains(&place) => {}
            other => failures.push(format!(
                "{}: want {place}{want:?}, got {other:?}",
                bad.display()
            )),
        }
        if let Err(e) = still_renders(&s, &good) {
            failures.push(format!("{}: {e}", bad.display()));
        }
        saved += 1;
    }
    // A material saved with a texture wider than the device: scaled down, no panic.
    let wide = std::fs::read_to_string(hostile.join("wide_texture_material.ron")).unwrap();
    save(&mut s, material, wide.as_bytes()).expect("a too-wide texture is scaled down");
    save(&mut s, material, &project.good_material).expect("the good material recovers");
    let recovered = s.frame.as_ref().unwrap().image.clone();
    assert_eq!(recovered.len(), good.len());
    drop(s);

    // Shaders: a graph whose one pass runs pass.wgsl from a shader folder of the project
    // (watched; built-in shaders behind it), each bad shader saved over pass.wgsl.
    let shaders = project.dir.path().join("shaders");
    std::fs::create_dir_all(&shaders).unwrap();
    let pass = shaders.join("pass.wgsl");
    let good_shader = "@fragment\nfn fs_main(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {\n    return vec4<f32>(0.25, 0.5, 1.0, 1.0);\n}\n";
    std::fs::write(&pass, good_shader).unwrap();
    let fullscreen = project.dir.path().join("fullscreen.ron");
    std::fs::write(
        &fullscreen,
        r#"Graph(
    name: "fullscreen",
    resources: [Texture(name: "hdr", format: Rgba32Float)],
    passes: [Pass(name: "solid", kind: Fullscreen(shader: "pass.wgsl"), writes: ["hdr"])],
    output: "hdr",
)"#,
    )
    .unwrap();
    let mut renderer = Renderer::headless().unwrap();
    renderer.shaders = lightgraph::shader::ShaderLibrary::with_builtin(&shaders);
    let mut s = ReloadSession::new(
        renderer,
        &fullscreen,
        SceneSource::File(scene.clone()),
        64,
        36,
        &[],
    )
    .unwrap();
    let solid = s.frame.as_ref().unwrap().image.clone();
    assert!(solid.iter().all(|p| *p == [0.25, 0.5, 1.0, 1.0]));
    let mut shader_files: Vec<_> = std::fs::read_dir(root().join("tests/bad/shaders"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    shader_files.sort();
    for bad in &shader_files {
        let text = std::fs::read(bad).unwrap();
        let outcome = save(&mut s, &pass, &text);
        let name = bad.file_name().unwrap().to_string_lossy();
        // broken.wgsl's type error is the one every graph gets (broken_wgsl.ron expects
        // it); the others are made for their own graphs' bindings, so under this graph
        // they are refused naming the saved shader, or render where they are a
        // fullscreen shader too (the byte-order mark, the overflow).
        let ok = match (&*name, &outcome) {
            ("broken.wgsl", Err(e)) => e.contains("pass.wgsl:6:"),
            ("bom.wgsl" | "overflow.wgsl", Ok(_)) => true,
            (_, Err(e)) => e.contains("pass.wgsl"),
            _ => false,
        };
        if !ok {
            failures.push(format!("{}: got {outcome:?}", bad.display()));
        }
        if outcome.is_err() {
            if let Err(e) = still_renders(&s, &solid) {
                failures.push(format!("{}: {e}", bad.display()));
            }
        }
        saved += 1;
        // Back to the good shader, so the next one is judged from a good frame.
        save(&mut s, &pass, good_shader.as_bytes()).expect("the good shader recovers");
        assert_eq!(s.frame.as_ref().unwrap().image, solid);
    }
    // A test that saves nothing proves nothing: 27 graphs, 11 scenes, 15 materials and
    // 12 shaders when written.
    assert!(saved >= 60, "only {saved} bad files saved");
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}
