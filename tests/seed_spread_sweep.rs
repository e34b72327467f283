//! A sweep's `seeds:` columns through the code the `bench` command runs, on the real
//! adapter (lavapipe on CI): harada's geometry with 1,024 lights, every one casting, at
//! 64×36, against the exact ray-cast reference (the light loop traces every caster).

use lightgraph::bench::sweep::{self, Sweep};
use lightgraph::render::Renderer;

const SWEEP: &str = r#"Sweep(
    scenes: ["../scenes/harada_all_casting.ron"],
    graphs: [
        "visibility_raycast_shadows_naive.ron",
        "../benches/graphs/stochastic_k1_off.ron",
        "../benches/graphs/stochastic_k1_temporal.ron",
    ],
    lights: [1024],
    resolutions: [(64, 36)],
    warmup: 1,
    warmup_seconds: 0.0,
    frames: 1,
    rounds: 1,
    reference: "visibility_raycast_shadows_naive.ron",
    light_stats: false,
    seeds: 8,
)"#;

/// The exact graph takes no seed: its frame rendered again is the same, no variance and
/// no bias against itself. The stochastic graphs, reseeded, spread: variance > 0. Both
/// are unbiased (docs/stochastic_lighting.md, tested to 5σ by tests/stochastic_lighting.rs),
/// so their bias² estimate stays below their variance: its own noise is about
/// √2·variance/S per channel, averaged over thousands of channels.
#[test]
fn stochastic_graphs_spread_over_seeds_and_the_exact_graph_does_not() {
    let dir = lightgraph::project_root().join("benches/sweeps");
    let plan = Sweep::parse(SWEEP, &dir.join("seeds.ron")).expect("the sweep parses");
    let mut renderer = Renderer::headless().expect("a wgpu adapter (lavapipe on CI)");
    let rows = sweep::run(&plan, &dir, &mut renderer, |_| {}).expect("sweep");
    assert_eq!(rows.len(), 3);
    for r in &rows {
        eprintln!(
            "{}: rel_mse {:?}, seeds {:?}, variance {:?}, bias² {:?}",
            r.technique, r.rel_mse, r.seeds, r.seed_rel_variance, r.seed_rel_bias2
        );
        assert_eq!(r.seeds, Some(plan.seeds), "{}", r.technique);
    }
    let exact = &rows[0];
    assert_eq!(
        (exact.seed_rel_variance, exact.seed_rel_bias2),
        (Some(0.0), Some(0.0))
    );
    for r in &rows[1..] {
        let variance = r.seed_rel_variance.expect("measured");
        let bias2 = r.seed_rel_bias2.expect("measured");
        assert!(variance > 0.0, "{}: no spread over seeds", r.technique);
        assert!(
            bias2.abs() < variance,
            "{}: bias² {bias2} against variance {variance}",
            r.technique
        );
    }
}

#[test]
fn seeds_are_refused_below_two_and_with_moving_lights() {
    let path = std::path::Path::new("seeds.ron");
    let e = Sweep::parse(&SWEEP.replace("seeds: 8", "seeds: 1"), path)
        .unwrap_err()
        .to_string();
    assert!(e.contains("seeds.ron: 16: seeds 1 must be 0 (off)"), "{e}");
    let moving = SWEEP.replace("seeds: 8", "seeds: 3,\n    animate: Some(0.1)");
    let e = Sweep::parse(&moving, path).unwrap_err().to_string();
    assert!(
        e.contains("16: seeds cannot be combined with animate"),
        "{e}"
    );
    assert!(Sweep::parse(&SWEEP.replace("seeds: 8", "seeds: 0"), path).is_ok());
}

/// The stochastic sweeps with seeds parse, ask for 8 seeds and name graphs that validate.
#[test]
fn the_stochastic_seed_sweeps_parse_and_their_graphs_validate() {
    let root = lightgraph::project_root();
    let shaders = lightgraph::shader::ShaderLibrary::builtin();
    for name in ["harada", "gallery", "chairs", "harada_65536"] {
        let path = root.join(format!("benches/sweeps/stochastic_seeds_{name}.ron"));
        let plan = Sweep::load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(plan.seeds, 8, "{name}");
        for g in &plan.graphs {
            lightgraph::graph::check_file(&root.join("graphs").join(g), &shaders)
                .unwrap_or_else(|e| panic!("{name}: {g}: {e}"));
        }
    }
}
