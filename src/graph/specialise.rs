//! Step 3: keep only what this scene needs. Passes whose `when:` is false go first, then
//! every pass from which no root (the output's writers, declared side effects) is reachable.

use super::model::Name;
use super::validate::CheckedGraph;
use crate::scene::SceneFeatures;
use petgraph::graph::NodeIndex;
use petgraph::Direction;

/// Why a pass does not run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CullReason {
    /// Its `when:` scene feature is false (the feature's name).
    WhenFalse(String),
    /// Nothing it writes reaches the output or a side effect.
    Unreachable,
}

/// Per pass (declaration order): `None` if it runs, or why not.
pub fn specialise(graph: &CheckedGraph, features: &SceneFeatures) -> Vec<Option<CullReason>> {
    let desc = &graph.desc;
    let mut culled: Vec<Option<CullReason>> = desc
        .passes
        .iter()
        .map(|p| match p.when {
            Some(f) if !f.holds(features) => Some(CullReason::WhenFalse(format!("{f:?}"))),
            _ => None,
        })
        .collect();
    let side_effects: rustc_hash::FxHashSet<&str> =
        desc.side_effects.iter().map(Name::as_str).collect();
    let roots: Vec<usize> = (0..desc.passes.len())
        .filter(|&i| {
            culled[i].is_none()
                && (desc.passes[i].writes.contains(&desc.output)
                    || side_effects.contains(desc.passes[i].name.as_str()))
        })
        .collect();
    let mut reached = vec![false; desc.passes.len()];
    let mut stack = roots;
    while let Some(i) = stack.pop() {
        if std::mem::replace(&mut reached[i], true) {
            continue;
        }
        for n in graph
            .deps
            .neighbors_directed(NodeIndex::new(i), Direction::Incoming)
        {
            let w = graph.deps[n];
            if culled[w].is_none() && !reached[w] {
                stack.push(w);
            }
        }
    }
    for (i, c) in culled.iter_mut().enumerate() {
        if c.is_none() && !reached[i] {
            *c = Some(CullReason::Unreachable);
        }
    }
    culled
}
