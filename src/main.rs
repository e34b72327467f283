//! The lightgraph command line: a thin layer over the library (see [`cli`]).

mod cli;

/// See Cargo.toml: many small allocations (graph compiles, scene imports).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> anyhow::Result<()> {
    // Piped into `head` or `grep -q`, a closed stdout ends the process quietly as it does
    // for other command-line tools, instead of Rust's ignored SIGPIPE turning the next
    // print into a panic ("failed printing to stdout: Broken pipe").
    // SAFETY: called before any thread starts; SIG_DFL is a valid handler for SIGPIPE.
    #[cfg(unix)]
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    // Before anything starts a thread: Mesa's Vulkan loader reads the environment.
    cli::runtime_dir_fallback();
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    cli::run()
}
