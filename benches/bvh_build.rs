//! Building the shadow BVH over the built-in `chairs` scene (289,018 triangles) on one
//! core: gathering the triangles, the obvhs PLOC build, SAH leaf collapse and flattening.
//! obvhs is built without its `parallel` feature (Cargo.toml: no rayon is compiled), so
//! the build is single-threaded; divan runs the bench on one thread (`threads = 1`).
//! Aim: ≤ 50 ms with the default options (`BuildQuality::Fastest`, leaves of ≤ 4).

use lightgraph::scene::builtin;
use lightgraph::shadow::bvh::{BuildOptions, BuildQuality, ShadowBvh};

fn main() {
    divan::main();
}

const QUALITIES: [BuildQuality; 4] = [
    BuildQuality::Fastest,
    BuildQuality::VeryFast,
    BuildQuality::Fast,
    BuildQuality::Medium,
];

#[divan::bench(args = QUALITIES, threads = 1, sample_count = 20)]
fn chairs(bencher: divan::Bencher, quality: BuildQuality) {
    let scene = builtin::by_name("chairs").expect("chairs scene");
    assert!(scene.triangle_count() >= 250_000);
    let options = BuildOptions {
        quality,
        ..Default::default()
    };
    bencher.bench(|| ShadowBvh::build_with(divan::black_box(&scene), &options).unwrap());
}
