//! What a compiled graph leaves undrawn of a scene: blended meshes are drawn only by a
//! `TransparentShading` pass, so a graph without one (or one whose transparency passes
//! were culled) renders the scene without them. Callers say so once per render instead
//! of letting glass vanish silently; one that recompiles for the same render (a resize, a
//! shader reload) keeps a [`Reported`] so a warning is not repeated every time.

use super::model::PassKind;
use super::CompiledGraph;
use crate::scene::SceneFeatures;

/// A warning for each kind of the scene's content that no pass of `graph` draws.
pub fn undrawn(graph: &CompiledGraph, features: &SceneFeatures) -> Vec<String> {
    let mut out = Vec::new();
    let draws_blended = graph
        .passes
        .iter()
        .any(|p| matches!(p.kind, PassKind::TransparentShading(_)));
    if features.has_transparent && !draws_blended {
        out.push(format!(
            "graph '{}' has no TransparentShading pass: the scene's blended (transparent) meshes are not drawn (graphs/default.ron, transparent*.ron, tiled_deferred_transparent.ron and the packed, linked-list, VPL and shadow deferred graphs draw them)",
            graph.name()
        ));
    }
    out
}

/// The warnings of the last compile, for callers that compile again and again for one
/// render (a watcher, a viewer): each is said when it first applies, not on every
/// recompile; one that stopped applying (the graph gained a transparency pass) is said
/// again if it comes back.
#[derive(Debug, Default)]
pub struct Reported {
    last: Vec<String>,
}

impl Reported {
    /// The warnings for `graph` and `features` not given by the last compile.
    pub fn new_warnings(&mut self, graph: &CompiledGraph, features: &SceneFeatures) -> Vec<String> {
        let now = undrawn(graph, features);
        let new = now
            .iter()
            .filter(|w| !self.last.contains(w))
            .cloned()
            .collect();
        self.last = now;
        new
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{compile, FrameSize};
    use crate::shader::{assets, ShaderLibrary};

    fn compiled(graph: &str, features: &SceneFeatures) -> CompiledGraph {
        let path = crate::project_root().join("graphs").join(graph);
        let checked = assets::check_graph(&path, &ShaderLibrary::builtin()).unwrap();
        let size = FrameSize {
            width: 64,
            height: 36,
            lights: 4,
        };
        compile(checked, features, size)
    }

    #[test]
    fn blended_meshes_without_a_transparency_pass_are_reported() {
        let glass = SceneFeatures {
            has_transparent: true,
            has_lights: true,
            has_point_lights: true,
            ..Default::default()
        };
        for graph in [
            "forward_plus.ron",
            "visibility_compute_raster.ron",
            "tiled_deferred.ron",
        ] {
            let w = undrawn(&compiled(graph, &glass), &glass);
            assert_eq!(w.len(), 1, "{graph}: {w:?}");
            assert!(w[0].contains("blended"), "{}", w[0]);
        }
        assert!(undrawn(&compiled("transparent.ron", &glass), &glass).is_empty());
        assert!(undrawn(&compiled("default.ron", &glass), &glass).is_empty());
        let opaque = SceneFeatures {
            has_transparent: false,
            ..glass
        };
        assert!(undrawn(&compiled("forward_plus.ron", &opaque), &opaque).is_empty());
    }

    /// A recompile for the same render (a resize, a shader reload) does not repeat the
    /// warning; a graph that draws the glass clears it, so losing the glass again warns.
    #[test]
    fn a_recompile_repeats_no_warning() {
        let glass = SceneFeatures {
            has_transparent: true,
            has_lights: true,
            has_point_lights: true,
            ..Default::default()
        };
        let mut reported = Reported::default();
        let plain = compiled("visibility_compute_raster.ron", &glass);
        assert_eq!(reported.new_warnings(&plain, &glass).len(), 1);
        for _ in 0..3 {
            assert!(reported.new_warnings(&plain, &glass).is_empty());
        }
        let drawn = compiled("default.ron", &glass);
        assert!(reported.new_warnings(&drawn, &glass).is_empty());
        assert_eq!(reported.new_warnings(&plain, &glass).len(), 1);
    }
}
