//! The lightgraph command line: a thin layer over the library (see [`cli`]).

mod cli;

/// See Cargo.toml: many small allocations (graph compiles, scene imports).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> anyhow::Result<()> {
    // Before anything starts a thread: Mesa's Vulkan loader reads the environment.
    cli::runtime_dir_fallback();
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    cli::run()
}
