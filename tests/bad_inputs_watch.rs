//! A running hot-reload session (what `lightgraph watch` runs) survives every bad input
//! saved over its graph, its scene and a material it uses: each save ends in the error
//! tests/bad_inputs.rs expects (the last good frame stays), the texture wider than the
//! device is scaled down, and the good files saved again recover.

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
    let mut failures = Vec::new();
    let mut check = |s: &mut ReloadSession, file: &Path, bad: &Path| {
        let text = std::fs::read(bad).unwrap();
        let Some(want) = expected(&String::from_utf8_lossy(&text)).map(str::to_string) else {
            return;
        };
        // Saved under another name: a message that names the file names the saved one.
        let name = |p: &Path| p.file_name().unwrap().to_string_lossy().into_owned();
        let want = want.replace(&name(bad), &name(file));
        match save(s, file, &text) {
            Err(e) if e.contains(&want) => {}
            other => failures.push(format!("{}: want {want:?}, got {other:?}", bad.display())),
        }
        assert!(s.frame.is_some(), "the last good frame stays");
    };
    for bad in ron_files(&root().join("tests/bad/graphs")) {
        check(&mut s, graph, &bad);
    }
    save(&mut s, graph, &project.good_graph).expect("the good graph recovers");
    for bad in ron_files(&hostile) {
        check(&mut s, scene, &bad);
    }
    save(&mut s, scene, &project.good_scene).expect("the good scene recovers");
    // A material saved with a texture wider than the device: scaled down, no panic.
    let wide = std::fs::read_to_string(hostile.join("wide_texture_material.ron")).unwrap();
    save(&mut s, material, wide.as_bytes()).expect("a too-wide texture is scaled down");
    save(&mut s, material, &project.good_material).expect("the good material recovers");
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}
