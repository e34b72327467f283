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

/// Prepares (twice: cold, then all from the cache) and renders the forward+ graph on a
/// renderer of its own reading `shaders`: both prepares' stats and the image, or the
/// first prepare's error.
fn run(
    parallel: bool,
    shaders: ShaderLibrary,
) -> Result<(PrepareStats, PrepareStats, Vec<[f32; 4]>), String> {
    let mut r = Renderer::new(
        lightgraph::gpu::GpuContext::new_headless().unwrap(),
        shaders,
    );
    r.pipelines.parallel_builds = parallel;
    let scene = random_scene(40, 11);
    let text = std::fs::read_to_string(graph_path("forward_plus.ron")).unwrap();
    let size = FrameSize {
        width: W,
        height: H,
        lights: scene.lights.len() as u32,
    };
    let checked =
        || graph::check_text(Path::new("<test>"), &text, &ShaderLibrary::builtin()).unwrap();
    let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, &scene).unwrap();
    let compiled = graph::compile(checked(), &scene.features(), size);
    let first = r
        .prepare(compiled, &scene, &gpu, size, false)
        .map_err(|e| e.to_string())?;
    let image = first.render(&r).unwrap().image;
    let compiled = graph::compile(checked(), &scene.features(), size);
    let again = r
        .prepare_reusing(compiled, &scene, &gpu, size, false, Some(&first))
        .unwrap();
    Ok((first.stats().clone(), again.stats().clone(), image))
}

fn names(s: &PrepareStats) -> Vec<String> {
    s.builds.iter().map(|b| b.name()).collect()
}

#[test]
fn parallel_builds_report_and_render_what_sequential_builds_do() {
    let (par, par_again, par_image) = run(true, ShaderLibrary::builtin()).unwrap();
    let (seq, seq_again, seq_image) = run(false, ShaderLibrary::builtin()).unwrap();
    assert!(par.pipelines_built.len() >= 3, "{:?}", par.pipelines_built);
    assert_eq!(par.pipelines_built, seq.pipelines_built);
    assert_eq!(names(&par), names(&seq));
    assert_eq!(
        (par.pipeline_hits, par.pipeline_misses),
        (seq.pipeline_hits, seq.pipeline_misses)
    );
    // Every pipeline of the first prepare came from the passes' threads.
    assert_eq!(par.pipelines_built_in_parallel, par.pipelines_built.len());
    assert_eq!(seq.pipelines_built_in_parallel, 0);
    // The names say which pass asked: forward shading's pipelines name their material.
    assert!(
        names(&par)
            .iter()
            .any(|n| n.starts_with("forward_shading: ") && n.contains('`')),
        "{:?}",
        names(&par)
    );
    assert_eq!(par_image, seq_image);
    // Prepared again, everything is a hit either way and nothing runs ahead.
    for again in [&par_again, &seq_again] {
        assert!(
            again.pipelines_built.is_empty(),
            "{:?}",
            again.pipelines_built
        );
        assert_eq!(again.pipeline_hits, par.pipeline_hits + par.pipeline_misses);
        assert_eq!(again.pipelines_built_in_parallel, 0);
    }
}

#[test]
fn a_broken_shader_fails_the_same_way_in_parallel() {
    let dir = tempfile::tempdir().unwrap();
    let shaders = dir.path().join("shaders");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    for rel in ["common/lighting.wgsl"] {
        let from = root.join(rel);
        let to = shaders.join(rel);
        std::fs::create_dir_all(to.parent().unwrap()).unwrap();
        let text = std::fs::read_to_string(from).unwrap();
        std::fs::write(
            &to,
            format!("{text}\nfn broken( -> f32 {{ return 1.0; }}\n"),
        )
        .unwrap();
    }
    let library = || ShaderLibrary::with_builtin(&shaders);
    let par = run(true, library()).map(|_| ()).unwrap_err();
    let seq = run(false, library()).map(|_| ()).unwrap_err();
    assert_eq!(par, seq);
    assert!(par.contains("lighting.wgsl:"), "{par}");
}
