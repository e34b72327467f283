//! The dependency graph between passes (petgraph): an edge W -> R for every resource
//! that R reads and another pass W writes.

use super::fxmap::FxHashMap;
use super::model::GraphDesc;
use petgraph::graph::{DiGraph, NodeIndex};

/// Node weights are pass indices into `GraphDesc::passes`; edge weights resource names.
pub type DepGraph = DiGraph<usize, String>;

/// `writers` is [`writers_by_resource`] of `desc`.
pub fn build(desc: &GraphDesc, writers: &Writers) -> DepGraph {
    let mut g = DepGraph::with_capacity(desc.passes.len(), 0);
    let nodes: Vec<NodeIndex> = (0..desc.passes.len()).map(|i| g.add_node(i)).collect();
    for (r, reader) in desc.passes.iter().enumerate() {
        for res in &reader.reads {
            for &w in writers.get(res.as_str()).into_iter().flatten() {
                if w != r {
                    g.update_edge(nodes[w], nodes[r], res.clone());
                }
            }
        }
    }
    g
}

/// Resource name -> indices of the passes that write it, in declaration order.
pub type Writers<'a> = FxHashMap<&'a str, Vec<usize>>;

/// Resource name -> indices of the passes that write it, in declaration order.
pub fn writers_by_resource(desc: &GraphDesc) -> Writers<'_> {
    let mut writers = Writers::default();
    for (i, p) in desc.passes.iter().enumerate() {
        for w in &p.writes {
            writers.entry(w.as_str()).or_default().push(i);
        }
    }
    writers
}

/// The passes on each cycle, in declaration order of their first pass.
pub fn cycles(desc: &GraphDesc, g: &DepGraph) -> Vec<Vec<String>> {
    let mut found: Vec<Vec<usize>> = petgraph::algo::tarjan_scc(g)
        .into_iter()
        .filter(|scc| scc.len() > 1)
        .map(|scc| {
            let mut passes: Vec<usize> = scc.iter().map(|n| g[*n]).collect();
            passes.sort();
            order_along_cycle(g, passes)
        })
        .collect();
    found.sort();
    found
        .into_iter()
        .map(|c| c.into_iter().map(|i| desc.passes[i].name.clone()).collect())
        .collect()
}

/// Orders a strongly connected set as a walk: start at the first declared pass, keep
/// stepping to the first declared successor inside the set that is not yet visited.
fn order_along_cycle(g: &DepGraph, members: Vec<usize>) -> Vec<usize> {
    let mut walk = vec![members[0]];
    while walk.len() < members.len() {
        let here = NodeIndex::new(*walk.last().unwrap());
        let next = g
            .neighbors(here)
            .map(|n| g[n])
            .filter(|p| members.contains(p) && !walk.contains(p))
            .min();
        match next {
            Some(p) => walk.push(p),
            None => {
                // Not a simple cycle through every member: list the rest in order.
                walk.extend(
                    members
                        .iter()
                        .filter(|p| !walk.contains(p))
                        .copied()
                        .collect::<Vec<_>>(),
                );
            }
        }
    }
    walk
}
