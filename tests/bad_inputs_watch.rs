//! A running hot-reload session (what `lightgraph watch` runs) survives every bad input
//! saved over its graph, its scene and a material it uses: each save ends in the error
//! tests/bad_inputs.rs expects (the last good frame stays), the texture wider than the
//! device is scaled down, and the good files saved again recover.

use lightgraph::reload::{ReloadSession, SceneSource};
use lightgraph::render::Renderer;
use std::path::{Path, PathBuf};
use std::time::Duration;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

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

/// The `// expect: ` message of a bad file, if it has one.
fn expected(text: &str) -> Option<&str> {
    text.trim_start_matches('\u{feff}')
        .lines()
        .next()?
        .strip_prefix("// expect: ")
}

fn ron_files(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    v.sort();
    v
}

#[test]
fn watch_survives_every_bad_save() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let hostile = root().join("tests/bad/hostile");
    std::fs::create_dir_all(t.join("models")).unwrap();
    for e in std::fs::read_dir(hostile.join("models")).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, t.join("models").join(p.file_name().unwrap())).unwrap();
    }
    let good_graph = std::fs::read(root().join("graphs/forward_plus.ron")).unwrap();
    let graph = t.join("graph.ron");
    std::fs::write(&graph, &good_graph).unwrap();
    let material = t.join("mat.ron");
    let good_material = b"(name: \"plain\", layers: [(lobes: [Lambert(color: (0.5, 0.5, 0.5))])])";
    std::fs::write(&material, good_material).unwrap();
    let good_scene = br#"Scene(
    models: [(path: "models/tri.gltf")],
    material_overrides: { "tri_mat": "mat.ron" },
    camera: LookAt(eye: (0.3, 0.3, 3), target: (0.3, 0.3, 0), fov_y_deg: 50, near: 0.1, far: 100),
)"#;
    let scene = t.join("scene.ron");
    std::fs::write(&scene, good_scene).unwrap();

    let renderer = Renderer::headless().unwrap();
    let mut s = ReloadSession::new(
        renderer,
        &graph,
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
        check(&mut s, &graph, &bad);
    }
    save(&mut s, &graph, &good_graph).expect("the good graph recovers");
    for bad in ron_files(&hostile) {
        check(&mut s, &scene, &bad);
    }
    save(&mut s, &scene, good_scene).expect("the good scene recovers");
    // A material saved with a texture wider than the device: scaled down, no panic.
    let wide = std::fs::read_to_string(hostile.join("wide_texture_material.ron")).unwrap();
    save(&mut s, &material, wide.as_bytes()).expect("a too-wide texture is scaled down");
    save(&mut s, &material, good_material).expect("the good material recovers");
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}
