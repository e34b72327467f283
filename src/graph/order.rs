//! Step 4: a stable topological order of the passes that run: among passes whose inputs
//! are ready, the one declared first goes first, so a graph always runs the same way.

use super::validate::CheckedGraph;
use petgraph::graph::NodeIndex;
use petgraph::Direction;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Pass indices in execution order; `keep[i]` says whether pass i runs.
pub fn order(graph: &CheckedGraph, keep: &[bool]) -> Vec<usize> {
    let g = &graph.deps;
    let mut pending: Vec<usize> = (0..keep.len())
        .map(|i| {
            g.neighbors_directed(NodeIndex::new(i), Direction::Incoming)
                .filter(|n| keep[g[*n]])
                .count()
        })
        .collect();
    let mut ready: BinaryHeap<Reverse<usize>> = (0..keep.len())
        .filter(|&i| keep[i] && pending[i] == 0)
        .map(Reverse)
        .collect();
    let mut out = Vec::new();
    while let Some(Reverse(i)) = ready.pop() {
        out.push(i);
        for n in g.neighbors_directed(NodeIndex::new(i), Direction::Outgoing) {
            let j = g[n];
            if keep[j] {
                pending[j] -= 1;
                if pending[j] == 0 {
                    ready.push(Reverse(j));
                }
            }
        }
    }
    debug_assert_eq!(
        out.len(),
        keep.iter().filter(|k| **k).count(),
        "validated graphs have no cycles"
    );
    out
}
