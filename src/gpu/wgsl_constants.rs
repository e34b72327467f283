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
