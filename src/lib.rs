//! lightgraph: a data-driven render graph for scenes with thousands of dynamic lights.
//!
//! Pass graphs and materials are RON files; they are parsed, validated and compiled
//! without a GPU (see [`graph`]), then executed headless on wgpu (see [`render`]).

pub mod bench;
pub mod gpu;
pub mod graph;
pub mod material;
pub mod reload;
pub mod render;
pub mod scene;
pub mod shader;
