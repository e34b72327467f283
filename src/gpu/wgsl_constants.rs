//! The buffer layouts written as word counts on both sides: each WGSL constant must equal
//! the Rust constant that sizes and clears the buffer (tests/gpu_structs.rs checks the
//! structs; these are crate-private, so they are checked here).

use crate::graph::kinds::light_linked_list::LinkLayout;
use crate::graph::kinds::shadow_ray_jobs::{
    JOB_HEADER_WORDS, JOB_SURFACE_WORDS, JOB_WORDS, MASK_WORDS,
};
use crate::graph::ListLayout;
use crate::shader::ShaderLibrary;
use std::collections::BTreeMap;

/// `file` composed with `defines` and validated by naga.
fn module(file: &str, defines: &[(&str, &str)]) -> naga::Module {
    let defines: BTreeMap<String, String> = defines
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    ShaderLibrary::builtin()
        .compose(file, &defines, &BTreeMap::new())
        .unwrap()
        .validate()
        .unwrap()
}

/// The value of u32 constant `name`.
fn constant(module: &naga::Module, name: &str) -> u64 {
    let (_, c) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no constant {name}"));
    match module.global_expressions[c.init] {
        naga::Expression::Literal(naga::Literal::U32(v)) => v as u64,
        ref e => panic!("{name} is not a u32 literal: {e:?}"),
    }
}

#[test]
fn light_list_words_match() {
    let m = module("common/types.wgsl", &[]);
    assert_eq!(
        constant(&m, "HEADER_WORDS"),
        ListLayout::HEADER_WORDS as u64
    );
    assert_eq!(constant(&m, "ENTRY_WORDS"), ListLayout::ENTRY_WORDS as u64);
    assert_eq!(constant(&m, "LINK_HEADER_WORDS"), LinkLayout::HEADER_WORDS);
    assert_eq!(constant(&m, "LINK_WORDS"), LinkLayout::LINK_WORDS);
}

#[test]
fn shadow_job_and_mask_words_match() {
    let m = module("common/shadows.wgsl", &[("SHADOW_NORMAL_OFFSET", "1e-4")]);
    assert_eq!(constant(&m, "JOB_HEADER_WORDS"), JOB_HEADER_WORDS);
    assert_eq!(constant(&m, "JOB_WORDS"), JOB_WORDS);
    assert_eq!(constant(&m, "JOB_SURFACE_WORDS"), JOB_SURFACE_WORDS);
    assert_eq!(constant(&m, "SHADOW_MASK_WORDS"), MASK_WORDS);
}

#[test]
fn shadow_ray_alpha_layout_matches() {
    use crate::shadow::alpha as a;
    let m = module(
        "shadow/bvh.wgsl",
        &[("BVH_STANDALONE", "1"), ("BVH_ALPHA_TEST", "1")],
    );
    let pairs = [
        ("BVH_ALPHA_RECORD_WORDS", a::RECORD_WORDS as u32),
        ("BVH_ALPHA_TEXTURE_WORDS", a::TEXTURE_WORDS as u32),
        ("BVH_ALPHA_OP_WORDS", a::OP_WORDS as u32),
        ("BVH_ALPHA_STACK", a::STACK as u32),
        ("BVH_ALPHA_OP_CONST", a::OP_CONST),
        ("BVH_ALPHA_OP_TEXTURE", a::OP_TEXTURE),
        ("BVH_ALPHA_OP_VERTEX_ALPHA", a::OP_VERTEX_ALPHA),
        ("BVH_ALPHA_OP_ONE_MINUS", a::OP_ONE_MINUS),
        ("BVH_ALPHA_OP_MUL", a::OP_MUL),
        ("BVH_ALPHA_LINEAR", a::FLAG_LINEAR),
        ("BVH_ALPHA_SRGB", a::FLAG_SRGB),
        ("BVH_ALPHA_UV1", a::FLAG_UV1),
        ("BVH_ALPHA_WRAP_REPEAT", a::WRAP_REPEAT),
        ("BVH_ALPHA_WRAP_MIRROR", a::WRAP_MIRROR),
    ];
    for (name, value) in pairs {
        assert_eq!(constant(&m, name), value as u64, "{name}");
    }
}
