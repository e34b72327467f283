//! Compiling generated graphs of 100 and 500 passes (parse → validate → specialise →
//! order → plan), no GPU. A chain of compute passes, each reading its predecessor's
//! buffer, with a side branch every tenth pass that only a `when:` keeps alive.

use lightgraph::graph::{self, FrameSize};
use lightgraph::scene::SceneFeatures;
use lightgraph::shader::ShaderLibrary;
use std::fmt::Write;
use std::path::Path;

/// The binary's allocator (src/main.rs), so this measures what `lightgraph` pays.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    divan::main();
}

/// Built-in passes only, so the benchmark measures the graph, not shader file reads.
fn generated(passes: usize) -> String {
    let mut s = String::from("Graph(\n  name: \"generated\",\n  resources: [\n");
    s.push_str("    Import(name: \"geometry\", from: Geometry),\n    Import(name: \"lg\", from: LightGeometry),\n    Import(name: \"lp\", from: LightProperties),\n");
    for i in 0..passes {
        let _ = writeln!(s, "    Texture(name: \"depth{i}\", format: Depth32Float),");
        let _ = writeln!(s, "    Buffer(name: \"lists{i}\"),");
        let _ = writeln!(s, "    Texture(name: \"hdr{i}\", format: Rgba32Float),");
    }
    s.push_str("  ],\n  passes: [\n");
    // Groups of three passes: prepass, culling, shading; each group independent.
    for i in 0..passes / 3 {
        let when = if i % 10 == 9 {
            "when: Some(Transparent), "
        } else {
            ""
        };
        let _ = writeln!(s, "    Pass(name: \"pre{i}\", kind: DepthPrepass, {when}reads: [\"geometry\"], writes: [\"depth{i}\"]),");
        let _ = writeln!(s, "    Pass(name: \"cull{i}\", kind: LightCulling(tile: 16), reads: [\"depth{i}\", \"lg\"], writes: [\"lists{i}\"]),");
        let _ = writeln!(s, "    Pass(name: \"shade{i}\", kind: ForwardShading(lights: Culled), reads: [\"depth{i}\", \"lg\", \"lp\", \"lists{i}\"], writes: [\"hdr{i}\"]),");
    }
    let last = passes / 3 - 1;
    let side: Vec<String> = (0..passes / 3).map(|i| format!("\"shade{i}\"")).collect();
    let _ = write!(
        s,
        "  ],\n  output: \"hdr{last}\",\n  side_effects: [{}],\n)\n",
        side.join(", ")
    );
    s
}

fn compile(text: &str) -> graph::CompiledGraph {
    let shaders = ShaderLibrary::builtin();
    let checked = graph::check_text(Path::new("generated.ron"), text, &shaders).expect("valid");
    graph::compile(
        checked,
        &SceneFeatures::default(),
        FrameSize {
            width: 1920,
            height: 1080,
            lights: 1024,
        },
    )
}

#[divan::bench(args = [100, 500])]
fn parse_validate_compile(bencher: divan::Bencher, passes: usize) {
    let text = generated(passes);
    let g = compile(&text);
    assert!(g.passes.len() > passes / 2);
    bencher.bench(|| compile(divan::black_box(&text)));
}

#[divan::bench(args = [100, 500])]
fn specialise_order_plan(bencher: divan::Bencher, passes: usize) {
    let text = generated(passes);
    let checked =
        graph::check_text(Path::new("generated.ron"), &text, &ShaderLibrary::builtin()).unwrap();
    bencher.with_inputs(|| checked.clone()).bench_values(|c| {
        graph::compile(
            c,
            &SceneFeatures::default(),
            FrameSize {
                width: 1920,
                height: 1080,
                lights: 1024,
            },
        )
    });
}

/// Step 1 alone, as `check_text` runs it.
#[divan::bench(args = [100, 500])]
fn parse_only(bencher: divan::Bencher, passes: usize) {
    let source = graph::SourceText::new("generated.ron", generated(passes));
    bencher.bench(|| graph::parse(divan::black_box(&source)).expect("valid"));
}

/// Step 2 alone: validation of an already parsed graph.
#[divan::bench(args = [100, 500])]
fn validate_only(bencher: divan::Bencher, passes: usize) {
    let source = graph::SourceText::new("generated.ron", generated(passes));
    let desc = graph::parse(&source).expect("valid");
    let shaders = ShaderLibrary::builtin();
    bencher
        .with_inputs(|| (desc.clone(), source.clone()))
        .bench_values(|(d, s)| graph::validate(d, s, &shaders).expect("valid"));
}

/// What `compile` above pays per call outside the graph: the built-in shader library.
#[divan::bench]
fn shader_library_builtin() -> ShaderLibrary {
    ShaderLibrary::builtin()
}
