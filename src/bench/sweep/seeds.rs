//! The seed columns of a sweep row (`seeds: S`): the graph's frame rendered with S other
//! seeds, and the spread of those images around their mean and the reference
//! ([`crate::bench::seed_spread`]).

use super::SweepError;
use crate::bench::report::BenchRow;
use crate::bench::SeedSpreadAccumulator;
use crate::graph::{CompiledGraph, FrameSize, PassKind};
use crate::render::{PreparedFrame, Renderer, SceneGpu};
use crate::scene::Scene;

/// Frames a reseeded graph with temporal reuse runs before the one it is measured by, per
/// frame of `history`: its reservoirs' candidate count reaches the cap after `history`
/// frames, and from then on the first frames' share falls by history/(history + 1) a
/// frame, to about e⁻³ after 3 × history more.
pub(crate) const HISTORY_WARMUP: u32 = 4;

/// What the seeded frames of one graph are rendered with.
pub(super) struct SeedRun<'a> {
    /// The graph's timed frame: rendered again where no pass takes a seed.
    pub prepared: &'a PreparedFrame,
    pub scene: &'a Scene,
    pub gpu: &'a SceneGpu,
    pub size: FrameSize,
    /// The graph's name, for errors.
    pub graph_name: &'a str,
}

/// Renders `run`'s frame with `seeds` seeds and fills the row's seed columns against
/// `reference`.
pub(super) fn set_seed_columns(
    row: &mut BenchRow,
    run: &SeedRun,
    reference: &[[f32; 4]],
    seeds: u32,
    renderer: &mut Renderer,
) -> Result<(), SweepError> {
    let metrics_error = |e: crate::bench::MetricsError| {
        SweepError::Graph(run.graph_name.into(), format!("seeds: {e}"))
    };
    let mut spread = SeedSpreadAccumulator::new(run.size.width, run.size.height);
    for offset in 1..=seeds {
        let image = match reseeded(&run.prepared.graph, offset) {
            Some((graph, history)) => {
                let frame = renderer.prepare(graph, run.scene, run.gpu, run.size, false)?;
                for _ in 0..HISTORY_WARMUP * history {
                    frame.submit(renderer)?;
                }
                frame.render(renderer)?.image
            }
            None => run.prepared.render(renderer)?.image,
        };
        spread.add(&image).map_err(metrics_error)?;
    }
    let spread = spread.finish(reference).map_err(metrics_error)?;
    row.seeds = Some(seeds);
    row.seed_rel_variance = Some(spread.rel_variance);
    row.seed_rel_bias2 = Some(spread.rel_bias2);
    Ok(())
}

/// The seed of a pass kind that takes one (`LightSampling`), and its temporal history.
fn seed_of(kind: &mut PassKind) -> Option<(&mut u32, u32)> {
    match kind {
        PassKind::LightSampling(p) => Some((&mut p.seed, p.history)),
        _ => None,
    }
}

/// `graph` with the seed of every pass that runs and takes one moved by `offset`
/// (wrapping), and the largest temporal history among those passes; `None` when no pass
/// that runs takes a seed (its frame would be the same).
pub(crate) fn reseeded(graph: &CompiledGraph, offset: u32) -> Option<(CompiledGraph, u32)> {
    let mut graph = graph.clone();
    let mut history = None;
    for pass in &mut graph.passes {
        if let Some((seed, h)) = seed_of(&mut pass.kind) {
            *seed = seed.wrapping_add(offset);
            history = Some(history.unwrap_or(0).max(h));
            // The graph file's copy too, so nothing reading the description sees the
            // timed frame's seed.
            if let Some((seed, _)) = seed_of(&mut graph.checked.desc.passes[pass.index].kind) {
                *seed = seed.wrapping_add(offset);
            }
        }
    }
    history.map(|h| (graph, h))
}

#[cfg(test)]
mod tests {
    use super::reseeded;
    use crate::graph::{self, PassKind};
    use crate::scene::SceneFeatures;

    fn compiled(name: &str) -> graph::CompiledGraph {
        let shaders = crate::shader::ShaderLibrary::builtin();
        let (path, text) = crate::shader::assets::project()
            .read(&format!("graphs/{name}"))
            .expect("the graph");
        let checked = graph::check_text(&path, &text, &shaders).expect("a valid graph");
        let features = SceneFeatures {
            has_shadow_casters: true,
            has_lights: true,
            has_point_lights: true,
            ..Default::default()
        };
        graph::compile(
            checked,
            &features,
            graph::FrameSize {
                width: 64,
                height: 32,
                lights: 16,
            },
        )
    }

    fn seeds(g: &graph::CompiledGraph) -> (Vec<u32>, Vec<u32>) {
        let of = |k: &PassKind| match k {
            PassKind::LightSampling(p) => Some(p.seed),
            _ => None,
        };
        (
            g.passes.iter().filter_map(|p| of(&p.kind)).collect(),
            g.checked
                .desc
                .passes
                .iter()
                .filter_map(|p| of(&p.kind))
                .collect(),
        )
    }

    #[test]
    fn only_seeded_passes_are_reseeded() {
        let g = compiled("../benches/graphs/stochastic_k4_temporal.ron");
        assert_eq!(seeds(&g), (vec![0], vec![0]));
        let (moved, history) = reseeded(&g, 3).expect("LightSampling takes a seed");
        assert_eq!((seeds(&moved), history), ((vec![3], vec![3]), 20));
        assert!(reseeded(&compiled("visibility_raycast_shadows_naive.ron"), 3).is_none());
    }
}
