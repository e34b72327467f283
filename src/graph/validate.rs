//! Step 2: everything that can be wrong with a graph, found before anything reaches the GPU.

use super::deps::{self, DepGraph, PassIds, Writers};
use super::error::{GraphError, GraphErrors};
use super::location::SourceText;
use super::model::{GenericShader, GraphDesc, Name, PassKind, ResourceDesc, TextureFormat};
use super::roles::{PassRoles, RoleCtx};
use crate::shader::{reflect_bindings, Composed, ShaderLibrary};
use rustc_hash::{FxHashMap, FxHashSet};
use std::collections::BTreeSet;
use std::sync::Arc;

/// A graph that passed validation: its roles resolved and its shaders composed.
#[derive(Clone, Debug)]
pub struct CheckedGraph {
    /// The graph as parsed.
    pub desc: GraphDesc,
    /// Its text, for error positions in later steps.
    pub source: SourceText,
    pub(crate) deps: DepGraph,
    /// Per pass, in declaration order.
    /// Shared with the scheduled passes of every compile.
    pub roles: Vec<Arc<PassRoles>>,
    /// Per pass: the composed shader of a generic pass.
    pub shaders: Vec<Option<Composed>>,
    /// Per pass: the declared-resource index of each read and write, so the compile
    /// steps never look a name up.
    pub(crate) ids: PassIds,
}

/// Checks a parsed graph against the shaders in `shaders` (names, references, slots,
/// formats, sizes, pass order, shader bindings), reporting every error found, each with its
/// file position.
pub fn validate(
    desc: GraphDesc,
    source: SourceText,
    shaders: &ShaderLibrary,
) -> Result<CheckedGraph, GraphErrors> {
    let mut errors = Vec::new();
    let (resources, passes) = names_and_duplicates(&desc, &source, &mut errors);
    let ids = check_references(&desc, &source, &resources, &passes, &mut errors);
    check_conditions(&desc, &source, &mut errors);
    super::sizes::check_resources(&desc, &source, &mut errors);
    if !errors.is_empty() {
        // Role and order checks assume every name resolves.
        return Err(GraphErrors(errors));
    }
    // Every name resolves and is declared once: from here on, resources by index.
    let writers = deps::writers_by_resource(&ids, desc.resources.len());
    check_writes(&desc, &source, &ids, &writers, &mut errors);

    let deps = deps::build(&desc, &ids, &writers);
    for cycle in deps::cycles(&desc, &deps) {
        errors.push(GraphError::Cycle {
            at: source.of_declaration(&cycle[0]),
            passes: cycle,
        });
    }
    if errors.is_empty() {
        check_writer_order(&desc, &source, &deps, &writers, &mut errors);
    }

    let ctx = RoleCtx {
        source: &source,
        resources: &resources,
    };
    let mut roles = Vec::with_capacity(desc.passes.len());
    let mut composed = Vec::with_capacity(desc.passes.len());
    for pass in &desc.passes {
        let (r, c) = match pass.kind.shader_file() {
            None => (ctx.builtin(pass), None),
            Some(file) => match generic_shader(pass, file, shaders, &source) {
                Ok(c) => {
                    let module = c.1;
                    (
                        ctx.generic(pass, file, &reflect_bindings(&module)),
                        Some(c.0),
                    )
                }
                Err(e) => (Err(vec![e]), None),
            },
        };
        match r {
            Ok(r) => roles.push(Arc::new(r)),
            Err(mut e) => errors.append(&mut e),
        }
        composed.push(c);
    }
    if errors.is_empty() {
        super::sizes::check_laid_out_buffers(&desc, &resources, &roles, &source, &mut errors);
        super::kinds::contracts::check(&desc, &roles, &source, &mut errors);
    }
    if errors.is_empty() {
        Ok(CheckedGraph {
            desc,
            source,
            deps,
            roles,
            shaders: composed,
            ids,
        })
    } else {
        Err(GraphErrors(errors))
    }
}

/// The index [`pass_ids`] gives a name no resource declares.
const UNKNOWN: usize = usize::MAX;

/// The declared-resource index of every read and write, or [`UNKNOWN`].
fn pass_ids(desc: &GraphDesc, resources: &FxHashMap<&str, &ResourceDesc>) -> PassIds {
    // The map holds references into `desc.resources`: their index is their offset.
    let base = desc.resources.as_ptr() as usize;
    let size = std::mem::size_of::<ResourceDesc>();
    let index_of = |name: &Name| match resources.get(name.as_str()) {
        Some(r) => (*r as *const ResourceDesc as usize - base) / size,
        None => UNKNOWN,
    };
    let n = desc.passes.len();
    let mut ids = PassIds {
        reads: Vec::with_capacity(n * 4),
        read_start: Vec::with_capacity(n + 1),
        writes: Vec::with_capacity(n * 2),
        write_start: Vec::with_capacity(n + 1),
    };
    ids.read_start.push(0);
    ids.write_start.push(0);
    for p in &desc.passes {
        ids.reads.extend(p.reads.iter().map(index_of));
        ids.read_start.push(ids.reads.len());
        ids.writes.extend(p.writes.iter().map(index_of));
        ids.write_start.push(ids.writes.len());
    }
    ids
}

/// Resource name -> declaration, and the set of pass names.
type Names<'a> = (FxHashMap<&'a str, &'a ResourceDesc>, FxHashSet<&'a str>);

fn names_and_duplicates<'a>(
    desc: &'a GraphDesc,
    source: &SourceText,
    errors: &mut Vec<GraphError>,
) -> Names<'a> {
    let mut resources =
        FxHashMap::with_capacity_and_hasher(desc.resources.len(), Default::default());
    for r in &desc.resources {
        if resources.insert(r.name(), r).is_some() {
            errors.push(GraphError::Duplicate {
                at: source.of_declaration(r.name()),
                what: "resource",
                name: r.name().to_string(),
            });
        }
    }
    let mut passes = FxHashSet::with_capacity_and_hasher(desc.passes.len(), Default::default());
    for p in &desc.passes {
        if !passes.insert(p.name.as_str()) || resources.contains_key(p.name.as_str()) {
            errors.push(GraphError::Duplicate {
                at: source.of_declaration(&p.name),
                what: "pass",
                name: p.name.to_string(),
            });
        }
    }
    (resources, passes)
}

fn check_references(
    desc: &GraphDesc,
    source: &SourceText,
    resources: &FxHashMap<&str, &ResourceDesc>,
    passes: &FxHashSet<&str>,
    errors: &mut Vec<GraphError>,
) -> PassIds {
    let ids = pass_ids(desc, resources);
    for (p, pass) in desc.passes.iter().enumerate() {
        let names = pass.reads.iter().chain(&pass.writes);
        for (name, &id) in names.zip(ids.reads(p).iter().chain(ids.writes(p))) {
            if id == UNKNOWN {
                errors.push(GraphError::UnknownResource {
                    at: source.in_pass(&pass.name, name),
                    pass: pass.name.to_string(),
                    resource: name.to_string(),
                });
            }
        }
    }
    let output_at = || {
        let i = source.text.find("output").unwrap_or(0);
        source.at_offset(i)
    };
    // The frame is read back and presented as linear HDR.
    let problem = match resources.get(desc.output.as_str()) {
        Some(ResourceDesc::Texture {
            format: TextureFormat::Rgba32Float,
            samples: 1,
            ..
        }) => None,
        Some(ResourceDesc::Texture { format, samples, .. }) if !format.is_depth() => Some(format!(
            "must be a single-sample Rgba32Float texture to be read back; it is {format:?} with {samples} sample(s)"
        )),
        _ => Some("is not a declared colour texture".to_string()),
    };
    if let Some(problem) = problem {
        errors.push(GraphError::BadOutput {
            at: output_at(),
            resource: desc.output.to_string(),
            problem,
        });
    }
    for s in &desc.side_effects {
        if !passes.contains(s.as_str()) {
            let at = source.at_offset(source.text.find(&format!("\"{s}\"")).unwrap_or(0));
            errors.push(GraphError::UnknownSideEffect {
                at,
                pass: s.to_string(),
            });
        }
    }
    ids
}

/// `when: Msaa` is refused: MSAA is a property of the graph (its textures' sample
/// counts), not of the scene, so the condition would be the same for every scene.
fn check_conditions(desc: &GraphDesc, source: &SourceText, errors: &mut Vec<GraphError>) {
    for pass in &desc.passes {
        if pass.when == Some(super::model::SceneFeature::Msaa) {
            errors.push(GraphError::BadPass {
                at: source.in_pass(&pass.name, "Msaa"),
                pass: pass.name.to_string(),
                problem: "when: Msaa is not a scene feature: MSAA is chosen by the graph (samples: 4 on its textures), so it would hold for every scene or none. Drop the condition, and put what only an MSAA frame needs in an MSAA graph (graphs/msaa.ron)".into(),
            });
        }
    }
}

fn check_writes(
    desc: &GraphDesc,
    source: &SourceText,
    ids: &PassIds,
    writers: &Writers,
    errors: &mut Vec<GraphError>,
) {
    for (index, pass) in desc.passes.iter().enumerate() {
        for (name, &id) in pass.writes.iter().zip(ids.writes(index)) {
            if let ResourceDesc::Import { from, .. } = &desc.resources[id] {
                errors.push(GraphError::Mismatch {
                    at: source.in_pass(&pass.name, name),
                    pass: pass.name.to_string(),
                    resource: name.to_string(),
                    problem: format!("scene import {from:?} is read-only and cannot be written"),
                });
            }
        }
        for (name, &id) in pass.reads.iter().zip(ids.reads(index)) {
            let is_import = matches!(desc.resources[id], ResourceDesc::Import { .. });
            let written_elsewhere = writers.of(id).iter().any(|&i| i != index);
            if !is_import && !written_elsewhere {
                errors.push(GraphError::ReadNeverWritten {
                    at: source.in_pass(&pass.name, name),
                    pass: pass.name.to_string(),
                    resource: name.to_string(),
                });
            }
        }
    }
}

/// Two passes writing one resource must be ordered by a path between them.
fn check_writer_order(
    desc: &GraphDesc,
    source: &SourceText,
    deps: &DepGraph,
    by_resource: &Writers,
    errors: &mut Vec<GraphError>,
) {
    use petgraph::algo::has_path_connecting;
    use petgraph::graph::NodeIndex;
    let mut reported = BTreeSet::new();
    for (ri, r) in desc.resources.iter().enumerate() {
        let writers = by_resource.of(ri);
        for (k, &a) in writers.iter().enumerate() {
            for &b in &writers[k + 1..] {
                let (na, nb) = (NodeIndex::new(a), NodeIndex::new(b));
                if !has_path_connecting(deps, na, nb, None)
                    && !has_path_connecting(deps, nb, na, None)
                    && reported.insert((a, b))
                {
                    errors.push(GraphError::UnorderedWriters {
                        at: source.in_pass(&desc.passes[b].name, r.name()),
                        resource: r.name().to_string(),
                        first: desc.passes[a].name.to_string(),
                        second: desc.passes[b].name.to_string(),
                    });
                }
            }
        }
    }
}

fn generic_shader(
    pass: &super::model::PassDesc,
    file: &str,
    shaders: &ShaderLibrary,
    source: &SourceText,
) -> Result<(Composed, naga::Module), GraphError> {
    let shader_error = |message: String| GraphError::Shader {
        at: source.in_pass(&pass.name, file),
        pass: pass.name.to_string(),
        message,
    };
    let composed = shaders
        .compose(file, &Default::default(), &Default::default())
        .map_err(|e| shader_error(e.to_string()))?;
    let module = composed
        .validate()
        .map_err(|e| shader_error(e.to_string()))?;
    let Some(GenericShader { entry, stage, .. }) = pass.kind.generic_shader() else {
        unreachable!("only generic passes name a shader")
    };
    if !module
        .entry_points
        .iter()
        .any(|e| e.name == entry && e.stage == stage)
    {
        return Err(shader_error(format!(
            "{file} has no {stage:?} entry point named '{entry}'"
        )));
    }
    if let PassKind::Compute { dispatch, .. } = &pass.kind {
        let ep = module.entry_points.iter().find(|e| e.name == entry);
        let workgroup = ep.map_or([1, 1, 1], |e| e.workgroup_size);
        if let Some(e) = super::sizes::check_dispatch(pass, *dispatch, workgroup, source, file) {
            return Err(e);
        }
    }
    Ok((composed, module))
}
