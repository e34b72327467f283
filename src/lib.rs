//! lightgraph: a data-driven render graph for scenes with thousands of dynamic lights.
//!
//! Pass graphs and materials are RON files; they are parsed, validated and compiled
//! without a GPU (see [`graph`]), then executed headless on wgpu (see [`render`]).

#[cfg(feature = "bench")]
pub mod bench;
pub mod cull;
pub mod file_kind;
pub mod files;
pub mod gpu;
pub mod graph;
pub mod indirect;
pub mod material;
pub mod reload;
pub mod render;
pub mod scene;
pub mod shader;
pub mod shadow;
#[cfg(feature = "viewer")]
pub mod view;

/// The folder the user's shaders/, graphs/ and materials/ are looked for in first (see
/// [`shader::assets`]): the CLI's `--root`, else `LIGHTGRAPH_ROOT`, else the current
/// directory. Files not there come from the copies built into the binary. Never the
/// source tree the binary was built from: code that needs that uses `CARGO_MANIFEST_DIR`.
pub fn project_root() -> std::path::PathBuf {
    shader::assets::project()
        .root
        .unwrap_or_else(|| std::env::current_dir().unwrap_or_else(|_| ".".into()))
}
