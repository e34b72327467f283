//! lightgraph: a data-driven render graph for scenes with thousands of dynamic lights.
//!
//! Pass graphs and materials are RON files; they are parsed, validated and compiled
//! without a GPU (see [`graph`]), then executed headless on wgpu (see [`render`]).

pub mod bench;
pub mod cull;
pub mod gpu;
pub mod graph;
pub mod material;
pub mod reload;
pub mod render;
pub mod scene;
pub mod shader;
pub mod view;

/// Where the project's shaders/, graphs/ and materials/ are: `LIGHTGRAPH_ROOT` if set,
/// else the source tree the binary was built from, else the current directory (a
/// binary copied to another machine next to a checkout).
pub fn project_root() -> std::path::PathBuf {
    if let Some(root) = std::env::var_os("LIGHTGRAPH_ROOT") {
        return root.into();
    }
    let built = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    if built.join("shaders").is_dir() {
        return built.to_path_buf();
    }
    std::env::current_dir().unwrap_or_else(|_| ".".into())
}
