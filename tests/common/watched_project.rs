//! The project that the hot-reload survival tests save bad files into (a library
//! `ReloadSession` in bad_inputs_watch.rs, a `lightgraph watch` process in
//! watch_process.rs): a graph, a scene of tests/bad/hostile/models' triangle and a material
//! override, each with its good text to save back.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

pub struct WatchedProject {
    pub dir: tempfile::TempDir,
    pub graph: PathBuf,
    pub material: PathBuf,
    pub scene: PathBuf,
    pub good_graph: Vec<u8>,
    pub good_material: Vec<u8>,
    pub good_scene: Vec<u8>,
}

impl WatchedProject {
    pub fn new() -> Self {
        let dir = tempfile::tempdir().unwrap();
        let t = dir.path();
        let models = root().join("tests/bad/hostile/models");
        std::fs::create_dir_all(t.join("models")).unwrap();
        for e in std::fs::read_dir(models).unwrap() {
            let p = e.unwrap().path();
            std::fs::copy(&p, t.join("models").join(p.file_name().unwrap())).unwrap();
        }
        let good_graph = std::fs::read(root().join("graphs/forward_plus.ron")).unwrap();
        let good_material =
            b"(name: \"plain\", layers: [(lobes: [Lambert(color: (0.5, 0.5, 0.5))])])".to_vec();
        let good_scene = br#"Scene(
    models: [(path: "models/tri.gltf")],
    material_overrides: { "tri_mat": "mat.ron" },
    camera: LookAt(eye: (0.3, 0.3, 3), target: (0.3, 0.3, 0), fov_y_deg: 50, near: 0.1, far: 100),
)"#
        .to_vec();
        let (graph, material, scene) =
            (t.join("graph.ron"), t.join("mat.ron"), t.join("scene.ron"));
        std::fs::write(&graph, &good_graph).unwrap();
        std::fs::write(&material, &good_material).unwrap();
        std::fs::write(&scene, &good_scene).unwrap();
        WatchedProject {
            dir,
            graph,
            material,
            scene,
            good_graph,
            good_material,
            good_scene,
        }
    }
}

/// The `// expect: ` message of a bad file, if it has one.
pub fn expected(text: &str) -> Option<&str> {
    text.trim_start_matches('\u{feff}')
        .lines()
        .next()?
        .strip_prefix("// expect: ")
}

/// The .ron files of `dir`, sorted.
pub fn ron_files(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    v.sort();
    v
}
