//! Assertions on compiled graphs, no GPU: what runs, what was culled and why, the order,
//! and how many physical resources the plan needs.

use lightgraph::graph::{self, CullReason, FrameSize};
use lightgraph::scene::SceneFeatures;
use lightgraph::shader::ShaderLibrary;
use std::path::Path;

const SIZE: FrameSize = FrameSize {
    width: 64,
    height: 32,
    lights: 10,
};

fn compile(text: &str, features: SceneFeatures) -> graph::CompiledGraph {
    let checked =
        graph::check_text(Path::new("test.ron"), text, &ShaderLibrary::builtin()).unwrap();
    graph::compile(checked, &features, SIZE)
}

fn with_lights() -> SceneFeatures {
    SceneFeatures {
        has_lights: true,
        ..Default::default()
    }
}

/// Two full-screen passes with same-sized temporaries: `a` lives in passes 1-2, `b` in
/// 3-4, so one physical texture serves both. `stats` reaches nothing.
const CHAIN: &str = r#"Graph(
    name: "chain",
    resources: [
        Texture(name: "a", format: Rgba32Float),
        Texture(name: "b", format: Rgba32Float),
        Texture(name: "c", format: Rgba32Float),
        Texture(name: "out", format: Rgba32Float),
        Texture(name: "unused", format: Rgba32Float),
    ],
    passes: [
        Pass(name: "make_a", kind: Fullscreen(shader: "examples/solid.wgsl"), writes: ["a"]),
        Pass(name: "a_to_c", kind: Fullscreen(shader: "examples/copy.wgsl"), reads: ["a"], writes: ["c"]),
        Pass(name: "stats", kind: Fullscreen(shader: "examples/copy.wgsl", entry: "fs_main"), reads: ["a"], writes: ["unused"], when: Some(Lights)),
        Pass(name: "c_to_b", kind: Fullscreen(shader: "examples/copy_c.wgsl"), reads: ["c"], writes: ["b"]),
        Pass(name: "b_to_out", kind: Fullscreen(shader: "examples/copy_b.wgsl"), reads: ["b"], writes: ["out"]),
    ],
    output: "out",
)"#;

#[test]
fn culls_unreachable_and_when_false_passes() {
    let g = compile(CHAIN, SceneFeatures::default());
    assert_eq!(g.pass_names(), ["make_a", "a_to_c", "c_to_b", "b_to_out"]);
    assert_eq!(
        g.culled_reason("stats"),
        Some(&CullReason::WhenFalse("Lights".into()))
    );
    let g = compile(CHAIN, with_lights());
    assert_eq!(g.culled_reason("stats"), Some(&CullReason::Unreachable));
    assert!(
        g.plan.get("unused").is_none(),
        "a culled pass's output is not allocated"
    );
}

#[test]
fn non_overlapping_temporaries_share_one_texture() {
    let g = compile(CHAIN, SceneFeatures::default());
    let p = |n: &str| g.plan.get(n).unwrap().physical;
    // Schedule positions: a 0..1, c 1..2, b 2..3, out 3..end. a and b do not overlap,
    // nor do c and out; a and c do (pass 1 reads a and writes c).
    assert_eq!(p("a"), p("b"));
    assert_eq!(p("c"), p("out"));
    assert_ne!(p("a"), p("c"));
    assert_eq!(g.plan.physical.len(), 2, "{:#?}", g.plan);
}

#[test]
fn side_effects_keep_a_pass() {
    let text = CHAIN.replace(
        "output: \"out\",",
        "output: \"out\",\n    side_effects: [\"stats\"],",
    );
    let g = compile(&text, with_lights());
    assert!(g.pass_names().contains(&"stats"));
}

#[test]
fn forward_plus_schedule_and_brute_force_culling() {
    let shaders = ShaderLibrary::builtin();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("graphs");
    let fp = graph::compile(
        graph::check_file(&root.join("forward_plus.ron"), &shaders).unwrap(),
        &with_lights(),
        SIZE,
    );
    assert_eq!(
        fp.pass_names(),
        ["depth_prepass", "light_culling", "forward_shading"]
    );
    let lists = fp.plan.get("light_lists").unwrap();
    let bytes = match &fp.plan.physical[lists.physical].desc {
        graph::plan::PhysicalDesc::Buffer { bytes } => *bytes,
        _ => unreachable!(),
    };
    // 4 x 2 tiles of 16 px, compact lists: header + entries + the graph's bound of
    // 16,777,216 indices, in bytes (whatever the size: the pool does not scale).
    assert_eq!(bytes, 4 * (4 + 4 * 8 + 16_777_216));
    let dot = fp.to_dot();
    assert!(
        dot.contains("\"light_culling\" -> \"res:light_lists\""),
        "{dot}"
    );
}

/// Three independent passes kept by `side_effects` and a two-pass chain, declared in
/// the order of `names`.
fn independent_passes(names: &[&str]) -> String {
    let pass = |n: &str| {
        match n {
        "make_a" => r#"Pass(name: "make_a", kind: Fullscreen(shader: "examples/solid.wgsl"), writes: ["a"])"#.to_string(),
        "a_to_out" => r#"Pass(name: "a_to_out", kind: Fullscreen(shader: "examples/copy.wgsl"), reads: ["a"], writes: ["out"])"#.to_string(),
        s => format!(r#"Pass(name: "{s}", kind: Fullscreen(shader: "examples/solid.wgsl"), writes: ["t_{s}"])"#),
    }
    };
    let passes: Vec<String> = names.iter().map(|n| pass(n)).collect();
    format!(
        r#"Graph(
    name: "independent",
    resources: [
        Texture(name: "a", format: Rgba32Float),
        Texture(name: "out", format: Rgba32Float),
        Texture(name: "t_s1", format: Rgba32Float),
        Texture(name: "t_s2", format: Rgba32Float),
        Texture(name: "t_s3", format: Rgba32Float),
    ],
    passes: [
        {}
    ],
    output: "out",
    side_effects: ["s2", "s3", "s1"],
)"#,
        passes.join(",\n        ")
    )
}

#[test]
fn order_is_stable_by_declaration() {
    // Among passes whose inputs are ready the one declared first runs first, so the
    // schedule follows the declaration, not a hash or the edges' insertion order.
    for (declared, expected) in [
        (
            ["s1", "s2", "make_a", "a_to_out", "s3"],
            ["s1", "s2", "make_a", "a_to_out", "s3"],
        ),
        (
            ["s3", "a_to_out", "s1", "make_a", "s2"],
            ["s3", "s1", "make_a", "a_to_out", "s2"],
        ),
        (
            ["a_to_out", "s2", "s3", "s1", "make_a"],
            ["s2", "s3", "s1", "make_a", "a_to_out"],
        ),
    ] {
        let g = compile(&independent_passes(&declared), SceneFeatures::default());
        assert_eq!(g.pass_names(), expected, "declared {declared:?}");
    }
}
