//! The lightgraph command line: a thin layer over the library. Arguments here; the
//! commands in [`render`] (one frame, checks), [`live`] (watch, view) and [`bench`].

pub mod bench;
pub mod live;
pub mod render;
mod render_report;
pub mod vpl_error;
pub mod vpl_variants;

use anyhow::{bail, Result};
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use lightgraph::shader::assets::{self, Project};
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "lightgraph",
    version,
    about = "Render graphs for scenes with thousands of lights"
)]
pub struct Cli {
    /// The folder whose shaders/, graphs/ and materials/ are read and watched (over the
    /// built-in ones, file by file). Default: LIGHTGRAPH_ROOT, else the current directory
    /// if it has any of them, else built-in files only.
    #[arg(long, global = true, value_name = "DIR")]
    pub root: Option<PathBuf>,
    #[command(subcommand)]
    pub command: Option<Command>,
}

#[derive(Subcommand)]
pub enum Command {
    /// Render a scene through a graph, headless; print per-pass GPU times and light statistics.
    Render(RenderArgs),
    /// Validate graph, scene and material files; every error is printed as file:line:col.
    /// Exit 1 if any.
    Validate {
        /// Files to check: graph RON, scene RON/.gltf/.glb or material RON (told apart by
        /// their contents).
        #[arg(required = true, value_name = "FILE")]
        files: Vec<PathBuf>,
    },
    /// Print the compiled schedule (after culling for the scene): passes in order, culled
    /// passes and the resource count, or Graphviz with --dot.
    Graph {
        /// The graph file (RON).
        graph: PathBuf,
        /// The scene the graph is specialised to (default: the built-in atrium).
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Print Graphviz DOT instead of the list (`| dot -Tsvg > g.svg`).
        #[arg(long)]
        dot: bool,
    },
    /// Hot reload, headless: re-render on every change to shaders/, materials/, the
    /// graph or the scene; print the reload latency or the error (the last good frame
    /// stays in --out).
    Watch {
        /// Scene: .ron, .gltf or .glb (default: the built-in atrium). Watched with every file
        /// it reads.
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Graph file (default: graphs/default.ron of the root, else built in). Watched.
        #[arg(long)]
        graph: Option<PathBuf>,
        /// Frame width in pixels.
        #[arg(long, default_value_t = 640)]
        width: u32,
        /// Frame height in pixels.
        #[arg(long, default_value_t = 360)]
        height: u32,
        /// Where every good frame is written: .png (tonemapped) or .exr (linear HDR).
        #[arg(long)]
        out: PathBuf,
        /// Time in seconds at which moving lights are placed on every load of the scene
        /// (scene `motion:`; default 0, as for `render`).
        #[arg(long, value_name = "SECONDS")]
        time: Option<f64>,
    },
    /// A window onto a hot-reloading graph: fly/orbit camera, per-pass GPU times, light
    /// statistics, reload errors and graph variants in an overlay.
    View(ViewArgs),
    /// Check a layered material; with --wgsl print the WGSL generated for it.
    Material {
        /// The material file (RON).
        file: PathBuf,
        /// Print the WGSL generated for the material.
        #[arg(long)]
        wgsl: bool,
    },
    /// Compare two EXR images: a summary line, then RMSE, max abs and rel, PSNR, FLIP
    /// mean and bad pixels as a table.
    Compare {
        /// The reference image (.exr).
        a: PathBuf,
        /// The image compared with it (.exr, same size).
        b: PathBuf,
    },
    /// Time against error: run a sweep file, write CSV, Markdown and plots to --out.
    Bench {
        /// The sweep file (RON; see benches/sweeps/). Default: a sweep sized for the
        /// adapter, the built-in smoke sweep on a software adapter and headline.ron on a GPU.
        #[arg(long)]
        sweep: Option<PathBuf>,
        /// The folder the report is written to (created if missing).
        #[arg(long)]
        out: PathBuf,
    },
    /// Hot-reload latency: time real shader, material and graph edits from the file
    /// write to the new frame; write CSV and Markdown to --out.
    ReloadBench(ReloadBenchArgs),
    /// One-bounce error of the VPL graph against a CPU path-traced bounce, for each n
    /// (n×n VPLs a map view), with the GPU time of the VPL passes: time against error.
    VplError(VplErrorArgs),
}

#[derive(clap::Args)]
pub struct VplErrorArgs {
    /// Scene files with indirect lights (`indirect: true`).
    #[arg(long, required = true, num_args = 1..)]
    pub scene: Vec<PathBuf>,
    /// The VPL graph timed (default: graphs/indirect_vpl.ron).
    #[arg(long)]
    pub graph: Option<PathBuf>,
    /// The VPL graph whose image is measured: every light at every pixel, so no list
    /// overflow adds to the error (default: benches/graphs/indirect_vpl_all_lights.ron).
    #[arg(long)]
    pub error_graph: Option<PathBuf>,
    /// The same frame without VPLs, subtracted to get the indirect part (default:
    /// graphs/forward_plus.ron).
    #[arg(long)]
    pub direct: Option<PathBuf>,
    /// Output width.
    #[arg(long, default_value_t = 160)]
    pub width: u32,
    /// Output height.
    #[arg(long, default_value_t = 120)]
    pub height: u32,
    /// VPLs per side of each map view (N² = 16, 64, 256, 1024 VPLs a view).
    #[arg(long, value_delimiter = ',', default_values_t = [4u32, 8, 16, 32])]
    pub n: Vec<u32>,
    /// Bounce rays a pixel of the reference.
    #[arg(long, default_value_t = 256)]
    pub samples: u32,
    /// Skip the reference's noise estimate (a second reference from other rays, as long
    /// to trace as the first): its noise per pixel does not depend on the image size, so
    /// a small image with the same samples measures it.
    #[arg(long)]
    pub no_noise: bool,
    /// Timed frames for each n, after as many warm-up frames and at least 1 s of them; medians are reported.
    #[arg(long, default_value_t = 10)]
    pub frames: u32,
    /// Frames to measure against the same reference, each
    /// `label=L;graph=G;error_graph=E;direct=D;spawn=P` (keys but `label` optional: the
    /// graphs default to --graph, --error-graph, --direct; `spawn` adds VplSpawn
    /// parameters such as `merge: 2, falloff: Disc`). None: one frame, labelled `vpl`.
    #[arg(long)]
    pub variant: Vec<String>,
    /// Folder for results.csv, results.md and time_vs_error.png.
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(clap::Args)]
pub struct ReloadBenchArgs {
    /// The folder the CSV and Markdown are written to (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// Frame width in pixels.
    #[arg(long, default_value_t = 160)]
    pub width: u32,
    /// Frame height in pixels.
    #[arg(long, default_value_t = 90)]
    pub height: u32,
    /// Random lights in the benchmark scene.
    #[arg(long, default_value_t = 1024)]
    pub lights: u32,
    /// Edits of each kind.
    #[arg(long, default_value_t = 10)]
    pub repeats: usize,
    /// 1..=1023: shader edits use values no run with another salt used, so a driver's own
    /// shader cache (NVIDIA's on disk) cannot answer from an earlier run. 0: the historical
    /// values, the same in every run.
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..1024))]
    pub salt: u32,
    /// Frames submitted without waiting right before each edit, as a viewer has in flight.
    #[arg(long, default_value_t = 0)]
    pub frames_in_flight: usize,
    /// Frames rendered, each waited for, right before each edit, as a viewer renders
    /// continuously: keeps the GPU as busy as a viewer does (an idle GPU lowers its
    /// clocks, and the new frame then takes longer).
    #[arg(long, default_value_t = 0)]
    pub viewer_frames: usize,
    /// Wait for the GPU to go idle before building pipelines (timed in its own column).
    #[arg(long)]
    pub wait_for_idle_before_build: bool,
    /// Build the pipelines of different passes one after another, as before they were
    /// built in parallel (for comparison).
    #[arg(long)]
    pub sequential_builds: bool,
}

#[derive(clap::Args, Default)]
pub struct RenderArgs {
    /// Scene: .ron, .gltf or .glb (default: the built-in atrium).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Graph file (default: graphs/default.ron).
    #[arg(long)]
    pub graph: Option<PathBuf>,
    /// Frame width in pixels (default: the scene's; on a software adapter, without
    /// --width and --height, scaled to fit 640x360).
    #[arg(long)]
    pub width: Option<u32>,
    /// Frame height in pixels (default: as for --width).
    #[arg(long)]
    pub height: Option<u32>,
    /// Output image: .png (tonemapped sRGB) or .exr (linear HDR, 32-bit float).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Lights-per-tile heat map (PNG); a histogram CSV is written beside it.
    #[arg(long)]
    pub heatmap: Option<PathBuf>,
    /// wgpu features to open the device without, as if the adapter lacked them
    /// (comma-separated, e.g. shader_int64_atomic_min_max: the compute rasterizer then
    /// runs its hardware fallback and says so).
    #[arg(long, value_name = "FEATURES")]
    pub disable_features: Option<String>,
    /// Time in seconds at which moving lights are placed (scene `motion:`; default 0).
    #[arg(long, value_name = "SECONDS")]
    pub time: Option<f64>,
}

#[derive(clap::Args)]
pub struct ViewArgs {
    /// Scene: .ron, .gltf or .glb (default: the built-in atrium). Watched and reloaded.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Graph file (default: graphs/default.ron of the root, else built in); the other
    /// graphs in its folder are offered as variants.
    #[arg(long)]
    pub graph: Option<PathBuf>,
    /// Window width in pixels.
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    /// Window height in pixels.
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Render size relative to the window (0.5 shades a quarter of the pixels).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f32,
    /// Exposure in stops.
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
    /// Save what the window shows to this PNG after --frames frames, then exit.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Frames shown before --screenshot is taken.
    #[arg(long, default_value_t = 10)]
    pub frames: u32,
}

/// What `--help` says about where files are found, with the root it resolved to.
fn where_files_are(project: &Project) -> String {
    format!(
        "Where files are found:\n  \
         shaders/, graphs/ and materials/ are read, and watched by `watch` and `view`, in a root\n  \
         folder; a file the root lacks comes from the copy built into this binary (so the\n  \
         built-in scenes render from any folder; without arguments lightgraph renders the\n  \
         root's scenes/gallery.ron, else the built-in atrium). The root is the first of:\n    \
         1. --root DIR\n    \
         2. the {env} environment variable\n    \
         3. the current directory, if it has shaders/, graphs/ or materials/\n    \
         4. none: built-in files only\n  \
         Root now: {}",
        project.describe(),
        env = assets::ROOT_ENV,
    )
}

/// `--root DIR` or `--root=DIR` from the raw arguments, so that `--help` can name the
/// root before clap has parsed (and exited on) `--help`.
fn root_flag(args: &[std::ffi::OsString]) -> Option<PathBuf> {
    let mut it = args.iter().skip(1);
    while let Some(a) = it.next() {
        let s = a.to_string_lossy();
        if s == "--" {
            break;
        }
        if s == "--root" {
            return it.next().map(PathBuf::from);
        }
        if let Some(v) = s.strip_prefix("--root=") {
            return Some(PathBuf::from(v));
        }
    }
    None
}

/// Parses the arguments, fixes the project root for the library and runs the command.
pub fn run() -> Result<()> {
    let args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    let project = Project::resolve(root_flag(&args).as_deref());
    let command = Cli::command().after_help(where_files_are(&project));
    let cli = Cli::from_arg_matches(&command.get_matches_from(&args))?;
    let project = Project::resolve(cli.root.as_deref());
    if let Err(e) = project.check() {
        bail!("{e}");
    }
    assets::set_project(project);
    match cli.command {
        // The README's first command: the default scene (the root's gallery, else the
        // built-in atrium), sized for the adapter, to a file.
        None => render::render(RenderArgs {
            scene: render::default_scene_path(),
            out: Some(PathBuf::from("lightgraph.png")),
            ..RenderArgs::default()
        }),
        Some(Command::Render(args)) => render::render(args),
        Some(Command::Validate { files }) => render::validate(&files),
        Some(Command::Graph { graph, scene, dot }) => {
            render::print_graph(&graph, scene.as_deref(), dot)
        }
        Some(Command::Compare { a, b }) => render::compare(&a, &b),
        Some(Command::Material { file, wgsl }) => render::material(&file, wgsl),
        Some(Command::Watch {
            scene,
            graph,
            width,
            height,
            out,
            time,
        }) => live::watch(scene, graph, width, height, &out, time),
        Some(Command::Bench { sweep, out }) => bench::run_bench(sweep.as_deref(), &out),
        Some(Command::View(args)) => live::view(args),
        Some(Command::ReloadBench(args)) => bench::reload_bench(&args),
        Some(Command::VplError(args)) => vpl_error::run(&args),
    }
}

/// Sets `XDG_RUNTIME_DIR` to a private folder under the temporary directory when it is
/// unset (containers, ssh without a login session): Mesa's Vulkan drivers load the Wayland
/// client library, which prints "XDG_RUNTIME_DIR is invalid or not set" twice otherwise.
/// A set value, even a wrong one, is left alone. Call before any thread starts.
pub fn runtime_dir_fallback() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_some() {
        return;
    }
    let user = std::env::var("USER").unwrap_or_else(|_| "user".into());
    let dir = std::env::temp_dir().join(format!("lightgraph-runtime-{user}"));
    let mut builder = std::fs::DirBuilder::new();
    #[cfg(unix)]
    std::os::unix::fs::DirBuilderExt::mode(&mut builder, 0o700);
    let made = builder.create(&dir);
    if made.is_ok() || dir.is_dir() {
        std::env::set_var("XDG_RUNTIME_DIR", &dir);
    }
}

/// Project file `rel` (`graphs/forward_plus.ron`): the root's own, else the built-in one.
pub fn project_path(rel: &str) -> PathBuf {
    assets::project().locate(rel)
}

#[cfg(test)]
mod tests {
    use super::Cli;
    use clap::CommandFactory;

    /// Every subcommand says what it does and every flag and argument what it takes.
    #[test]
    fn every_subcommand_and_argument_has_help() {
        let cli = Cli::command();
        cli.clone().debug_assert();
        let mut missing = Vec::new();
        for sub in cli.get_subcommands() {
            if sub.get_about().is_none() {
                missing.push(sub.get_name().to_string());
            }
            for arg in sub.get_arguments() {
                let builtin = matches!(arg.get_id().as_str(), "help" | "version");
                if !builtin && arg.get_help().is_none() {
                    missing.push(format!("{} {}", sub.get_name(), arg.get_id()));
                }
            }
        }
        assert!(missing.is_empty(), "no help for: {missing:?}");
    }
}
