//! What a compiled graph leaves undrawn of a scene: blended meshes are drawn only by a
//! `TransparentShading` pass, so a graph without one (or one whose transparency passes
//! were culled) renders the scene without them. Callers say so once per compile instead
//! of letting glass vanish silently.

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
            "graph '{}' has no TransparentShading pass: the scene's blended (transparent) meshes are not drawn (graphs/transparent.ron and transparent_msaa.ron draw them)",
            graph.name()
        ));
    }
    out
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
        let opaque = SceneFeatures {
            has_transparent: false,
            ..glass
        };
        assert!(undrawn(&compiled("forward_plus.ron", &opaque), &opaque).is_empty());
    }
}
