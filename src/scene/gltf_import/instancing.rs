//! What a document's node graph expands to once every node is instanced along every path
//! to it (a node may be the child of many: 24 levels of two parents sharing two children
//! make 2^24 instances from a 50 KB file). Counted from the JSON alone, before any buffer
//! is read or any vertex allocated.

use crate::scene::error::SceneError;
use gltf::json::{mesh::Mode, validation::Checked, Root};

/// Totals after instancing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Expansion {
    pub(crate) node_instances: u64,
    /// Mesh primitives drawn (one mesh per primitive instance in the scene).
    pub(crate) primitives: u64,
    pub(crate) triangles: u64,
}

impl Expansion {
    pub(crate) fn saturating_add(self, o: Expansion) -> Expansion {
        Expansion {
            node_instances: self.node_instances.saturating_add(o.node_instances),
            primitives: self.primitives.saturating_add(o.primitives),
            triangles: self.triangles.saturating_add(o.triangles),
        }
    }
}

/// What the reachable node graph is: a DAG and its expansion, or a cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum NodeGraph {
    Acyclic(Expansion),
    /// Node `parent` lists `child` among its children, and `child` leads back to `parent`.
    Cycle {
        parent: usize,
        child: usize,
    },
}

/// The expansion of the scene the importer walks, or a cycle among its reachable nodes:
/// both found in time linear in nodes and edges, so a cyclic graph of shared children is
/// refused at once rather than after walking a million paths into it.
/// An accessor over `max_accessor` elements counts none here: reading it is refused with
/// its own message.
pub(super) fn expansion(root: &Root, max_accessor: u64) -> NodeGraph {
    let n = root.nodes.len();
    let children = |i: usize| {
        root.nodes[i]
            .children
            .iter()
            .flatten()
            .map(|c| c.value())
            .filter(move |&c| c < n)
    };
    // The same roots as the walk: the default scene, else the first, else parentless nodes.
    let scene = root
        .scene
        .and_then(|s| root.scenes.get(s.value()))
        .or(root.scenes.first());
    let roots: Vec<usize> = match scene {
        Some(s) => s
            .nodes
            .iter()
            .map(|r| r.value())
            .filter(|&r| r < n)
            .collect(),
        None => {
            let mut child = vec![false; n];
            (0..n).flat_map(children).for_each(|c| child[c] = true);
            (0..n).filter(|&i| !child[i]).collect()
        }
    };
    // Reachable nodes and their in-degree from reachable parents (edges with multiplicity).
    let mut reachable = vec![false; n];
    let mut stack = roots.clone();
    while let Some(i) = stack.pop() {
        if !std::mem::replace(&mut reachable[i], true) {
            stack.extend(children(i));
        }
    }
    let mut indegree = vec![0u64; n];
    for i in (0..n).filter(|&i| reachable[i]) {
        children(i).for_each(|c| indegree[c] += 1);
    }
    let mut instances = vec![0u64; n];
    roots.iter().for_each(|&r| instances[r] += 1);
    // Kahn's order: a node's count is final once all its parents are done.
    let mut ready: Vec<usize> = (0..n)
        .filter(|&i| reachable[i] && indegree[i] == 0)
        .collect();
    let (mut done, mut total) = (0usize, Expansion::default());
    while let Some(i) = ready.pop() {
        done += 1;
        let k = instances[i];
        total.node_instances = total.node_instances.saturating_add(k);
        if let Some(mesh) = root.nodes[i].mesh.and_then(|m| root.meshes.get(m.value())) {
            let prims = mesh.primitives.len() as u64;
            let tris = mesh
                .primitives
                .iter()
                .map(|p| triangles(root, p, max_accessor))
                .fold(0, u64::saturating_add);
            total.primitives = total.primitives.saturating_add(k.saturating_mul(prims));
            total.triangles = total.triangles.saturating_add(k.saturating_mul(tris));
        }
        for c in children(i) {
            instances[c] = instances[c].saturating_add(k);
            indegree[c] -= 1;
            if indegree[c] == 0 {
                ready.push(c);
            }
        }
    }
    if done == reachable.iter().filter(|&&r| r).count() {
        return NodeGraph::Acyclic(total);
    }
    // Kahn's order stopped short: a back edge of a depth-first search names the cycle.
    let mut state = vec![0u8; n]; // 0 unvisited, 1 on the path, 2 finished
    for &r in &roots {
        if state[r] != 0 {
            continue;
        }
        state[r] = 1;
        let mut path: Vec<(usize, Vec<usize>)> = vec![(r, children(r).collect())];
        while let Some((node, pending)) = path.last_mut() {
            let node = *node;
            match pending.pop() {
                Some(c) if state[c] == 1 => {
                    return NodeGraph::Cycle {
                        parent: node,
                        child: c,
                    }
                }
                Some(c) if state[c] == 0 => {
                    state[c] = 1;
                    path.push((c, children(c).collect()));
                }
                Some(_) => {}
                None => {
                    state[node] = 2;
                    path.pop();
                }
            }
        }
    }
    // Not reached (the search covers every node Kahn's order left), but never a panic.
    let stuck = (0..n)
        .find(|&i| reachable[i] && indegree[i] > 0)
        .unwrap_or(0);
    NodeGraph::Cycle {
        parent: stuck,
        child: stuck,
    }
}

impl super::Importer {
    /// Refuses a document whose expansion is past the limits, before any buffer is read.
    pub(super) fn check_expansion(&mut self, root: &Root) -> Result<(), SceneError> {
        let e = match expansion(root, self.limits.max_accessor_count) {
            NodeGraph::Acyclic(e) => e,
            NodeGraph::Cycle { parent, child } => {
                let name = |i: usize| root.nodes[i].name.as_deref();
                return Err(self.err(
                    super::named("node", parent, name(parent)),
                    format!(
                        "node hierarchy contains a cycle: its child {} leads back to it",
                        super::named("node", child, name(child))
                    ),
                ));
            }
        };
        let l = self.limits;
        self.limit(
            "nodes",
            "node instance count",
            e.node_instances,
            l.max_nodes,
        )?;
        let what = "mesh primitive count after instancing";
        self.limit("meshes", what, e.primitives, l.max_primitives)?;
        let what = "triangle count after instancing";
        self.limit("meshes", what, e.triangles, l.max_triangles)?;
        self.expansion = e;
        Ok(())
    }
}

/// Triangles a primitive makes, from its index (else POSITION) accessor's count.
fn triangles(root: &Root, p: &gltf::json::mesh::Primitive, max_accessor: u64) -> u64 {
    let count = |i: usize| {
        let n = root.accessors.get(i).map_or(0, |a| a.count.0);
        if n > max_accessor {
            0
        } else {
            n
        }
    };
    let n = match &p.indices {
        Some(i) => count(i.value()),
        None => p
            .attributes
            .get(&Checked::Valid(gltf::Semantic::Positions))
            .map_or(0, |a| count(a.value())),
    };
    match p.mode {
        Checked::Valid(Mode::Triangles) => n / 3,
        Checked::Valid(Mode::TriangleStrip | Mode::TriangleFan) => n.saturating_sub(2),
        _ => 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `levels` of two nodes, each with both nodes of the next level as children; a
    /// one-triangle mesh at the bottom.
    fn diamond(levels: usize) -> Root {
        let mut nodes = Vec::new();
        for l in 0..levels {
            let kids = if l + 1 < levels {
                format!("\"children\": [{}, {}]", 2 * l + 2, 2 * l + 3)
            } else {
                "\"mesh\": 0".to_string()
            };
            nodes.push(format!("{{{kids}}}"));
            nodes.push(format!("{{{kids}}}"));
        }
        let json = format!(
            r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
            "nodes": [{}],
            "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
            "accessors": [{{"componentType": 5126, "count": 3, "type": "VEC3"}}]}}"#,
            nodes.join(",")
        );
        gltf::json::deserialize::from_str(&json).unwrap()
    }

    fn acyclic(g: NodeGraph) -> Expansion {
        match g {
            NodeGraph::Acyclic(e) => e,
            other => panic!("expected a DAG, got {other:?}"),
        }
    }

    #[test]
    fn counts_every_path_to_a_node() {
        let e = acyclic(expansion(&diamond(3), u64::MAX));
        // Level 0: node 0 once (node 1 is unreachable); level 1: 1 + 1; level 2: 2 + 2.
        assert_eq!(e.node_instances, 1 + 2 + 4);
        assert_eq!((e.primitives, e.triangles), (4, 4));
        let e = acyclic(expansion(&diamond(40), 1 << 20));
        assert_eq!(e.triangles, 1 << 39);
    }

    /// A cycle at the bottom of 40 levels of shared children (2^40 paths into it) is
    /// named by its closing edge without walking the paths (the fuzzer's slow input).
    #[test]
    fn names_a_cycle_under_shared_children_at_once() {
        let mut root = diamond(40);
        let last = root.nodes.len() - 1;
        root.nodes[last].children = Some(vec![gltf::json::Index::new(2)]);
        let start = std::time::Instant::now();
        let NodeGraph::Cycle { parent, child } = expansion(&root, 1 << 20) else {
            panic!("the cycle was not found");
        };
        // Any edge closing the cycle will do: it must be a real child edge on it.
        let kids = root.nodes[parent].children.as_ref().unwrap();
        assert!(kids.iter().any(|c| c.value() == child));
        assert!(
            parent >= 2 && child >= 2,
            "{parent} -> {child} is not on the cycle"
        );
        assert!(start.elapsed().as_secs_f32() < 1.0);
    }
}
