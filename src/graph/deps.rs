//! The dependency graph between passes (petgraph): an edge W -> R for every resource
//! that R reads and another pass W writes.

use super::model::{GraphDesc, Name};
use petgraph::graph::{DiGraph, NodeIndex};

/// Node weights are pass indices into `GraphDesc::passes`; edge weights resource names.
pub type DepGraph = DiGraph<usize, Name>;

/// Declared-resource indices of every pass's reads and writes, flat, in declaration
/// order: pass `p`'s reads are `reads[read_start[p]..read_start[p + 1]]`.
#[derive(Clone, Debug)]
pub struct PassIds {
    pub reads: Vec<usize>,
    pub read_start: Vec<usize>,
    pub writes: Vec<usize>,
    pub write_start: Vec<usize>,
}

impl PassIds {
    pub fn reads(&self, pass: usize) -> &[usize] {
        &self.reads[self.read_start[pass]..self.read_start[pass + 1]]
    }
    pub fn writes(&self, pass: usize) -> &[usize] {
        &self.writes[self.write_start[pass]..self.write_start[pass + 1]]
    }
}

/// `writers` is [`writers_by_resource`] of `ids`.
pub fn build(desc: &GraphDesc, ids: &PassIds, writers: &Writers) -> DepGraph {
    let mut g = DepGraph::with_capacity(desc.passes.len(), 0);
    let nodes: Vec<NodeIndex> = (0..desc.passes.len()).map(|i| g.add_node(i)).collect();
    for (r, reader) in desc.passes.iter().enumerate() {
        for (res, &id) in reader.reads.iter().zip(ids.reads(r)) {
            for &w in writers.of(id) {
                if w != r {
                    g.update_edge(nodes[w], nodes[r], res.clone());
                }
            }
        }
    }
    g
}

/// Resource index -> indices of the passes that write it, in declaration order.
pub struct Writers {
    start: Vec<usize>,
    passes: Vec<usize>,
}

impl Writers {
    pub fn of(&self, resource: usize) -> &[usize] {
        &self.passes[self.start[resource]..self.start[resource + 1]]
    }
}

/// Resource index -> indices of the passes that write it, in declaration order, for
/// `resources` declared resources.
pub fn writers_by_resource(ids: &PassIds, resources: usize) -> Writers {
    let mut start = vec![0usize; resources + 1];
    for &w in &ids.writes {
        start[w + 1] += 1;
    }
    for i in 0..resources {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut passes = vec![0usize; ids.writes.len()];
    for p in 0..ids.write_start.len() - 1 {
        for &w in ids.writes(p) {
            passes[fill[w]] = p;
            fill[w] += 1;
        }
    }
    Writers { start, passes }
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
        .map(|c| {
            c.into_iter()
                .map(|i| desc.passes[i].name.to_string())
                .collect()
        })
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
