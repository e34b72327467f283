//! Import time: the shared Cornell box, and a generated glTF (.glb) of a million triangles
//! written to a temporary folder when the benchmark starts.
//!
//! `cargo bench --bench scene_import`

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

fn main() {
    divan::main();
}

const CORNELL: &str = "/work/shared/assets/cornell_box/scene.gltf";

fn million_triangles() -> &'static Path {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("lightgraph_bench_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("grid_1m.glb");
        lightgraph::scene::gltf_writer::write_grid_glb(&path, 1_000_000).unwrap();
        path
    })
}

#[divan::bench(sample_count = 50)]
fn cornell_box(b: divan::Bencher) {
    let path = Path::new(CORNELL);
    if !path.exists() {
        eprintln!("skipped: {CORNELL} not present");
        return;
    }
    b.bench(|| lightgraph::scene::load(divan::black_box(path)).unwrap());
}

#[divan::bench(sample_count = 10)]
fn generated_1m_triangles(b: divan::Bencher) {
    let path = million_triangles();
    b.bench(|| {
        let l = lightgraph::scene::load(divan::black_box(path)).unwrap();
        assert!(l.scene.triangle_count() >= 1_000_000);
        l
    });
}

#[divan::bench(sample_count = 20)]
fn builtin_atrium() -> lightgraph::scene::Scene {
    lightgraph::scene::builtin::atrium()
}
