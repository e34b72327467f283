//! Pipelines of different passes are built on one thread per pass ahead of the
//! sequential prepare (`Renderer::prepare_reusing`): the result must not depend on it.
//! The same pipelines are reported built, in the same order and with the same names and
//! counts, the image is the same, and a broken shader fails with the same error.

mod common;
use common::*;
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{PrepareStats, Renderer, SceneGpu};
use lightgraph::shader::ShaderLibrary;
use std::path::Path;

const W: u32 = 64;
const H: u32 = 36;

/// The forward+ graph with fixed light lists of `capacity` (a define of both culling
/// pipelines, which one pass builds).
fn graph_text(capacity: u32) -> String {
    let text = std::fs::read_to_string(graph_path("forward_plus.ron")).unwrap();
    let marker = "lists: Compact(max_indices: ";
    let start = text
        .find(marker)
        .expect("compact lists in forward_plus.ron");
    let end = start + text[start..].find(')').unwrap() + 1;
    format!("{}capacity: {capacity}{}", &text[..start], &text[end..])
}

struct Run {
    /// Cold, after the graph edit (capacity 256 -> 252), and the same again.
    stats: [PrepareStats; 3],
    images: [Vec<[f32; 4]>; 2],
}

/// Prepares and renders the forward+ graph on a renderer of its own reading `shaders`:
/// cold, then after a graph edit that changes both culling pipelines' keys, then the
/// same again (all hits). Or the first prepare's error.
fn run(parallel: bool, shaders: ShaderLibrary) -> Result<Run, String> {
    let mut r = Renderer::new(
        lightgraph::gpu::GpuContext::new_headless().unwrap(),
        shaders,
    );
    r.pipelines.parallel_builds = parallel;
    let scene = random_scene(40, 11);
    let size = FrameSize {
        width: W,
        height: H,
        lights: scene.lights.len() as u32,
    };
    let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, &scene).unwrap();
    let compiled = |capacity| {
        let checked = graph::check_text(
            Path::new("<test>"),
            &graph_text(capacity),
            &ShaderLibrary::builtin(),
        )
        .unwrap();
        graph::compile(checked, &scene.features(), size)
    };
    let first = r
        .prepare(compiled(256), &scene, &gpu, size, false)
        .map_err(|e| e.to_string())?;
    let image = first.render(&r).unwrap().image;
    let edited = r
        .prepare_reusing(compiled(252), &scene, &gpu, size, false, Some(&first))
        .unwrap();
    let edited_image = edited.render(&r).unwrap().image;
    let again = r
        .prepare_reusing(compiled(252), &scene, &gpu, size, false, Some(&edited))
        .unwrap();
    Ok(Run {
        stats: [
            first.stats().clone(),
            edited.stats().clone(),
            again.stats().clone(),
        ],
        images: [image, edited_image],
    })
}

fn names(s: &PrepareStats) -> Vec<String> {
    s.builds.iter().map(|b| b.name()).collect()
}

#[test]
fn parallel_builds_report_and_render_what_sequential_builds_do() {
    let par = run(true, ShaderLibrary::builtin()).unwrap();
    let seq = run(false, ShaderLibrary::builtin()).unwrap();
    assert!(
        par.stats[0].pipelines_built.len() >= 3,
        "{:?}",
        par.stats[0].pipelines_built
    );
    for (p, s) in par.stats.iter().zip(&seq.stats) {
        assert_eq!(p.pipelines_built, s.pipelines_built);
        assert_eq!(names(p), names(s));
        assert_eq!(
            (p.pipeline_hits, p.pipeline_misses),
            (s.pipeline_hits, s.pipeline_misses)
        );
        assert_eq!(s.pipelines_built_in_parallel, 0);
    }
    assert_eq!(par.images, seq.images);
    // Cold: every pipeline came from the passes' threads.
    let cold = &par.stats[0];
    assert_eq!(cold.pipelines_built_in_parallel, cold.pipelines_built.len());
    // The names say which pass asked: forward shading's pipelines name their material.
    assert!(
        names(cold)
            .iter()
            .any(|n| n.starts_with("forward_shading: ") && n.contains('`')),
        "{:?}",
        names(cold)
    );
    // The graph edit rebuilds the culling pass's two pipelines, each on its own thread
    // (one pass, two forks: ForkMode::Only).
    let edit = &par.stats[1];
    let culling: Vec<String> = names(edit)
        .into_iter()
        .filter(|n| n.starts_with("light_culling: "))
        .collect();
    assert!(culling.len() >= 2, "{:?}", names(edit));
    assert_eq!(edit.pipelines_built_in_parallel, edit.pipelines_built.len());
    assert!(edit.build_threads >= 2, "{} threads", edit.build_threads);
    // Prepared again, everything is a hit either way and nothing runs ahead.
    let again = &par.stats[2];
    assert!(
        again.pipelines_built.is_empty(),
        "{:?}",
        again.pipelines_built
    );
    assert_eq!(again.pipelines_built_in_parallel, 0);
    assert_eq!(
        again.pipeline_hits,
        edit.pipeline_hits + edit.pipeline_misses
    );
}

#[test]
fn a_broken_shader_fails_the_same_way_in_parallel() {
    let dir = tempfile::tempdir().unwrap();
    let shaders = dir.path().join("shaders");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let rel = "common/lighting.wgsl";
    let to = shaders.join(rel);
    std::fs::create_dir_all(to.parent().unwrap()).unwrap();
    let text = std::fs::read_to_string(root.join(rel)).unwrap();
    let broken = format!("{text}\nfn broken( -> f32 {{ return 1.0; }}\n");
    std::fs::write(&to, broken).unwrap();
    let library = || ShaderLibrary::with_builtin(&shaders);
    let par = run(true, library()).map(|_| ()).unwrap_err();
    let seq = run(false, library()).map(|_| ()).unwrap_err();
    assert_eq!(par, seq);
    assert!(par.contains("lighting.wgsl:"), "{par}");
}
