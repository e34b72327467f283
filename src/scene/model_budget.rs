//! One set of import limits for a whole scene file: each model may use what the models
//! before it left, so four models each under the limits cannot add up past them.

use super::error::SceneError;
use super::gltf_import::instancing::Expansion;
use super::gltf_import::ImportLimits;
use std::path::Path;

#[derive(Default)]
pub(crate) struct ModelBudget {
    full: ImportLimits,
    used: Expansion,
}

impl ModelBudget {
    /// The limits for the next model.
    pub(crate) fn limits(&self) -> ImportLimits {
        ImportLimits {
            max_nodes: self.full.max_nodes.saturating_sub(self.used.node_instances),
            max_primitives: self
                .full
                .max_primitives
                .saturating_sub(self.used.primitives),
            max_triangles: self.full.max_triangles.saturating_sub(self.used.triangles),
            ..self.full
        }
    }

    pub(crate) fn record(&mut self, e: Expansion) {
        self.used = self.used.saturating_add(e);
    }

    /// A model's limit error, restated as the scene's when earlier models used part of it.
    pub(crate) fn explain(&self, scene_file: &Path, element: &str, e: SceneError) -> SceneError {
        let SceneError::Limit {
            file, what, count, ..
        } = &e
        else {
            return e;
        };
        let (before, full) = match *what {
            // A file's own node count is held to what is left of the node budget too.
            "node instance count" | "node count" => (self.used.node_instances, self.full.max_nodes),
            "mesh primitive count after instancing" => {
                (self.used.primitives, self.full.max_primitives)
            }
            "triangle count after instancing" => (self.used.triangles, self.full.max_triangles),
            _ => return e,
        };
        if before == 0 {
            return e;
        }
        SceneError::invalid(
            scene_file,
            element,
            format!(
                "{}: {what} {count}, plus {before} from the models before it, exceeds the scene's limit of {full}",
                file.display()
            ),
        )
    }
}
