//! Pass graphs: the RON model and its compilation, as a recipe of named steps that need
//! no GPU: parse → validate → specialise → order → plan. Building pipelines (step 6)
//! happens in the renderer, through its pipeline cache.

mod compiled;
pub mod coverage;
mod deps;
mod error;
pub mod kinds;
mod location;
pub mod memory;
pub mod model;
mod name;
mod order;
mod parse;
pub mod plan;
mod roles;
pub(crate) mod sizes;
mod specialise;
mod validate;

pub use compiled::{CompiledGraph, CulledPass, ScheduledPass};
pub use error::{GraphError, GraphErrors};
pub use kinds::light_culling::{ListLayout, ListStorage};
pub use kinds::{slot, BufferLayout, SlotSpec};
pub use location::{Location, SourceText};
pub use model::*;
pub use plan::{FrameSize, ResourcePlan};
pub use roles::{PassRoles, BUILTIN_BINDINGS};
pub use specialise::CullReason;
pub use validate::CheckedGraph;

use crate::scene::SceneFeatures;
use crate::shader::ShaderLibrary;
use std::path::Path;

pub use parse::{load, parse};
pub use validate::validate;

/// Parses and validates a graph file (no scene needed): what `lightgraph validate` runs.
pub fn check_file(path: &Path, shaders: &ShaderLibrary) -> Result<CheckedGraph, GraphErrors> {
    let (desc, source) = load(path)?;
    validate(desc, source, shaders)
}

/// Parses and validates graph text.
pub fn check_text(
    file: &Path,
    text: &str,
    shaders: &ShaderLibrary,
) -> Result<CheckedGraph, GraphErrors> {
    let source = SourceText::new(file, text);
    let desc = parse(&source)?;
    validate(desc, source, shaders)
}

/// Steps 3 to 5 for one scene and frame size.
pub fn compile(checked: CheckedGraph, features: &SceneFeatures, frame: FrameSize) -> CompiledGraph {
    let culled = specialise::specialise(&checked, features);
    let keep: Vec<bool> = culled.iter().map(Option::is_none).collect();
    let schedule = order::order(&checked, &keep);
    let plan = plan::plan(
        &checked.desc,
        &checked.roles,
        &checked.ids,
        &schedule,
        frame,
    );
    let passes = compiled::scheduled_passes(&checked, &schedule);
    compiled::assemble(checked, culled, passes, plan)
}
