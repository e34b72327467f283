//! Contracts between a buffer's writer and its readers, checked once every pass's slots
//! are matched: a read slot's `needs` (what one of the buffer's writers must have laid it
//! out as), then the reading kind's own [`KindRules::check_inputs`] against what was
//! published. A graph that wires the wrong producer, or none, is refused here with
//! file:line:col, pass and resource, before anything reaches the GPU.

use super::{buffer_layout, BufferLayout, Contents, KindRules};
use crate::graph::error::GraphError;
use crate::graph::location::SourceText;
use crate::graph::model::{GraphDesc, PassDesc};
use crate::graph::plan::FrameSize;
use crate::graph::roles::PassRoles;
use std::sync::Arc;

/// The frame contracts are checked at: what a layout holds and the parameters it carries
/// (tile size, lists per tile) do not depend on the frame; only its bytes do.
const PROBE: FrameSize = FrameSize {
    width: 1280,
    height: 720,
    lights: 1,
};

impl Contents {
    fn describe(self) -> &'static str {
        match self {
            Contents::LightLists => "the tile lists of a LightCulling pass",
            Contents::LightLinks => "light linked lists",
            Contents::ShadowJobs => "the shadow jobs of a ShadowRayJobs pass",
            Contents::ShadowMask => "the shadow mask of a ShadowRayJobs pass",
            Contents::Lights => "the lights of a VplSpawn pass",
            Contents::RsmViews => "the view table of a ReflectiveShadowMaps pass",
            Contents::ShadowViews => "the view table of a ShadowAtlas pass",
            Contents::VplVisibility => "the visibility bits of a VplVisibility pass",
            Contents::LightSamples => "the light samples of a LightSampling pass",
        }
    }
}

/// A pass whose read slots met their `needs`, for its kind's checks of its inputs.
pub struct InputsCtx<'a> {
    pass: &'a PassDesc,
    roles: &'a PassRoles,
    graph: &'a Graph<'a>,
}

impl InputsCtx<'_> {
    /// What the writers of the buffer in `slot` laid it out as (its bytes at a probe frame
    /// size: read its contents and parameters only).
    pub fn published(&self, slot: &str) -> Option<BufferLayout> {
        let name = self.roles.slot(slot)?;
        self.graph.published(name).next()
    }
    pub fn mismatch(&self, resource: &str, problem: impl Into<String>) -> GraphError {
        self.graph.mismatch(self.pass, resource, problem)
    }
    pub fn slot(&self, name: &str) -> Option<&str> {
        self.roles.slot(name)
    }
    /// An error in the pass's parameters, at its declaration.
    pub fn bad(&self, problem: impl Into<String>) -> GraphError {
        GraphError::BadPass {
            at: self.graph.source.of_declaration(&self.pass.name),
            pass: self.pass.name.to_string(),
            problem: problem.into(),
        }
    }
    /// The pass being checked.
    pub fn pass(&self) -> &PassDesc {
        self.pass
    }
    /// Every pass of the graph with its matched slots, in declaration order.
    pub fn passes(&self) -> impl Iterator<Item = (&PassDesc, &PassRoles)> + '_ {
        self.graph
            .desc
            .passes
            .iter()
            .zip(self.graph.roles.iter().map(|r| r.as_ref()))
    }
}

struct Graph<'a> {
    desc: &'a GraphDesc,
    roles: &'a [Arc<PassRoles>],
    source: &'a SourceText,
}

impl Graph<'_> {
    /// The layouts the passes declared to write `name` give it.
    fn published<'n>(&'n self, name: &'n str) -> impl Iterator<Item = BufferLayout> + 'n {
        self.desc
            .passes
            .iter()
            .zip(self.roles)
            .filter(move |(p, _)| p.writes.iter().any(|w| w == name))
            .flat_map(move |(p, r)| {
                r.slots
                    .iter()
                    .filter(move |(_, n)| n.as_str() == name)
                    .filter_map(move |(slot, _)| buffer_layout(&p.kind, slot, PROBE))
            })
    }
    fn mismatch(&self, pass: &PassDesc, resource: &str, problem: impl Into<String>) -> GraphError {
        GraphError::Mismatch {
            at: self.source.in_pass(&pass.name, resource),
            pass: pass.name.to_string(),
            resource: resource.to_string(),
            problem: problem.into(),
        }
    }
}

/// Every built-in pass's read buffers against their writers; `roles` per pass, in
/// declaration order.
pub(crate) fn check(
    desc: &GraphDesc,
    roles: &[Arc<PassRoles>],
    source: &SourceText,
    errors: &mut Vec<GraphError>,
) {
    let graph = Graph {
        desc,
        roles,
        source,
    };
    for (pass, roles) in desc.passes.iter().zip(roles) {
        let Some(rules) = pass.kind.rules() else {
            continue;
        };
        let before = errors.len();
        check_needs(&graph, pass, roles, rules, errors);
        if errors.len() == before {
            let ctx = InputsCtx {
                pass,
                roles,
                graph: &graph,
            };
            rules.check_inputs(&ctx, errors);
        }
    }
}

fn check_needs(
    graph: &Graph,
    pass: &PassDesc,
    roles: &PassRoles,
    rules: &dyn KindRules,
    errors: &mut Vec<GraphError>,
) {
    for spec in rules.slots().iter().filter(|s| !s.needs.is_empty()) {
        let Some(name) = roles.slot(spec.name) else {
            continue;
        };
        if pass.writes.iter().any(|w| w == name) {
            continue;
        }
        let held: Vec<Contents> = graph.published(name).map(|l| l.contents()).collect();
        if held.iter().any(|c| spec.needs.contains(c)) {
            continue;
        }
        let mut producers: Vec<&str> = spec.needs.iter().map(|c| c.producer()).collect();
        producers.dedup();
        let mut problem = format!(
            "no {} pass is declared to write '{name}'",
            producers.join(" or ")
        );
        if let Some(other) = held.first() {
            problem += &format!("; it holds {}", other.describe());
        }
        errors.push(graph.mismatch(pass, name, problem));
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::{errors, validate, CULL, PREPASS};

    const G_BUFFER: &str = r#"Pass(name: "g", kind: GBuffer, reads: ["geometry", "depth"], writes: ["g_position=pos", "g_geometric=geo"]),"#;

    #[test]
    fn a_read_buffer_needs_the_producer_its_slot_names() {
        // The culling pass's tile lists where the ray-cast pass reads its jobs.
        let e = errors(
            &format!(
                r#"{PREPASS} {CULL} {G_BUFFER} Pass(name: "rc", kind: ShadowRayCast(), reads: ["shadow_jobs=lists", "g_position=pos", "g_geometric=geo", "lg", "bn", "bt"], writes: ["shadow_mask=mask"])"#
            ),
            "pos",
        );
        assert!(
            e.contains("pass 'rc', resource 'lists': no ShadowRayJobs pass is declared to write 'lists'; it holds the tile lists of a LightCulling pass"),
            "{e}"
        );
        // The shading passes walk tile lists or linked lists.
        let shade = r#"Pass(name: "f", kind: ForwardShading(lights: Culled), reads: ["geometry", "depth", "lg", "lp", "light_lists=lists"], writes: ["hdr"])"#;
        assert!(validate(&format!("{PREPASS} {CULL} {shade}"), "hdr").is_ok());
    }
}
