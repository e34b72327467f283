//! A compiled graph: plain data you can print and assert on.

use super::model::{Name, PassKind, ResourceDesc};
use super::plan::ResourcePlan;
use super::roles::PassRoles;
use super::specialise::CullReason;
use super::validate::CheckedGraph;
use std::fmt::Write;
use std::sync::Arc;

/// A pass that runs, in schedule order, with its resolved slots.
#[derive(Clone, Debug)]
pub struct ScheduledPass {
    /// The pass's name in the graph file.
    pub name: Name,
    /// Index into the graph file's passes.
    pub index: usize,
    /// Its kind and parameters, as the graph file gives them.
    pub kind: PassKind,
    /// Which resource fills each of its slots, resolved and checked at validation.
    pub roles: Arc<PassRoles>,
    /// Resources this pass writes first in the schedule: its attachments clear them,
    /// later writers load.
    pub clears: Vec<Name>,
    /// Sample count of the textures in its slots (validation made them agree).
    pub samples: u32,
}

impl ScheduledPass {
    /// Whether this pass writes `resource` first (clear) or after another pass (load).
    pub fn clears(&self, resource: &str) -> bool {
        self.clears.iter().any(|c| c == resource)
    }
    /// The resource in a slot the kind's table marks required, which validation filled.
    pub fn required(&self, slot: &str) -> &str {
        self.roles.slot(slot).unwrap_or_else(|| {
            panic!(
                "pass '{}': slot '{slot}' was checked at validation",
                self.name
            )
        })
    }
}

/// A pass dropped for this scene, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct CulledPass {
    /// The pass's name in the graph file.
    pub name: Name,
    /// Why it does not run.
    pub reason: CullReason,
}

/// A graph compiled for one scene and frame size: the schedule, the culled passes and the
/// resource plan; plain data to print, compare and prepare on the GPU.
#[derive(Clone, Debug)]
pub struct CompiledGraph {
    /// The validated graph it was compiled from.
    pub checked: CheckedGraph,
    /// Passes that run, in order.
    pub passes: Vec<ScheduledPass>,
    /// Passes dropped for this scene, with their reasons.
    pub culled: Vec<CulledPass>,
    /// Where every resource lives and which ones share memory.
    pub plan: ResourcePlan,
}

impl CompiledGraph {
    /// The graph's name.
    pub fn name(&self) -> &str {
        &self.checked.desc.name
    }
    /// The names of the passes that run, in schedule order.
    pub fn pass_names(&self) -> Vec<&str> {
        self.passes.iter().map(|p| p.name.as_str()).collect()
    }
    /// Why `pass` was dropped, or `None` if it runs (or does not exist).
    pub fn culled_reason(&self, pass: &str) -> Option<&CullReason> {
        self.culled
            .iter()
            .find(|c| c.name == pass)
            .map(|c| &c.reason)
    }
    /// Whether a forward shading pass runs (light statistics need one).
    pub fn has_forward_shading(&self) -> bool {
        self.passes
            .iter()
            .any(|p| matches!(p.kind, PassKind::ForwardShading { .. }))
    }
    /// Whether a light-culling pass runs (the lights-per-tile heat map needs one).
    pub fn has_light_culling(&self) -> bool {
        self.passes
            .iter()
            .any(|p| matches!(p.kind, PassKind::LightCulling(_)))
    }
    /// The name of the resource the frame presents.
    pub fn output(&self) -> &str {
        &self.checked.desc.output
    }

    /// The schedule after culling as Graphviz: passes in order, resources as boxes,
    /// culled passes grey and dashed with the reason.
    pub fn to_dot(&self) -> String {
        let desc = &self.checked.desc;
        let mut s = format!("digraph \"{}\" {{\n  rankdir=LR;\n", desc.name);
        for (pos, p) in self.passes.iter().enumerate() {
            let _ = writeln!(
                s,
                "  \"{}\" [shape=ellipse, label=\"{}. {}\\n{}\"];",
                p.name,
                pos + 1,
                p.name,
                p.kind.label()
            );
        }
        for c in &self.culled {
            let why = match &c.reason {
                CullReason::WhenFalse(f) => format!("when {f} is false"),
                CullReason::Unreachable => "reaches no output".to_string(),
            };
            let _ = writeln!(
                s,
                "  \"{}\" [shape=ellipse, style=dashed, color=grey, fontcolor=grey, label=\"{}\\nculled: {}\"];",
                c.name, c.name, why
            );
        }
        for r in &self.plan.resources {
            let _ = writeln!(
                s,
                "  \"res:{0}\" [shape=box, label=\"{0}\\nphysical #{1}\"];",
                r.name, r.physical
            );
        }
        for p in &self.passes {
            let pass = &desc.passes[p.index];
            for r in &pass.reads {
                let _ = writeln!(s, "  \"res:{r}\" -> \"{}\";", p.name);
            }
            for w in &pass.writes {
                let _ = writeln!(s, "  \"{}\" -> \"res:{w}\";", p.name);
            }
        }
        s.push_str("}\n");
        s
    }
}

/// The scheduled passes, in order.
pub(crate) fn scheduled_passes(checked: &CheckedGraph, schedule: &[usize]) -> Vec<ScheduledPass> {
    let resources = &checked.desc.resources;
    let mut written = vec![false; resources.len()];
    let ids = &checked.ids;
    schedule
        .iter()
        .map(|&i| {
            let desc = &checked.desc.passes[i];
            let roles = checked.roles[i].clone();
            let clears = desc
                .writes
                .iter()
                .zip(ids.writes(i))
                .filter(|&(_, &id)| !std::mem::replace(&mut written[id], true))
                .map(|(w, _)| w.clone())
                .collect();
            let samples_of = |id: usize| match resources[id] {
                ResourceDesc::Texture { samples, .. } => Some(samples),
                _ => None,
            };
            // A built-in kind's resources all fill slots; a generic pass draws at its
            // target's count whatever its bindings sample.
            let samples = match &roles.target {
                _ if desc.kind.shader_file().is_none() => ids
                    .reads(i)
                    .iter()
                    .chain(ids.writes(i))
                    .filter_map(|&id| samples_of(id))
                    .max(),
                Some(target) => desc
                    .writes
                    .iter()
                    .zip(ids.writes(i))
                    .find(|(w, _)| *w == target)
                    .and_then(|(_, &id)| samples_of(id)),
                None => None,
            }
            .unwrap_or(1);
            ScheduledPass {
                name: desc.name.clone(),
                index: i,
                kind: desc.kind.clone(),
                roles,
                clears,
                samples,
            }
        })
        .collect()
}

/// Assembles the compiled graph from the steps' results.
pub(crate) fn assemble(
    checked: CheckedGraph,
    culled: Vec<Option<CullReason>>,
    passes: Vec<ScheduledPass>,
    plan: ResourcePlan,
) -> CompiledGraph {
    let culled = culled
        .into_iter()
        .enumerate()
        .filter_map(|(i, c)| {
            c.map(|reason| CulledPass {
                name: checked.desc.passes[i].name.clone(),
                reason,
            })
        })
        .collect();
    CompiledGraph {
        checked,
        passes,
        culled,
        plan,
    }
}
