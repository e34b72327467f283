//! The lightgraph command line: a thin layer over the library.

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use lightgraph::bench::{self, heatmap, Tonemap};
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{FrameResult, Renderer, SceneGpu};
use lightgraph::scene::{self, Scene};
use lightgraph::shader::ShaderLibrary;
use std::path::{Path, PathBuf};

#[derive(Parser)]
#[command(
    name = "lightgraph",
    version,
    about = "Render graphs for scenes with thousands of lights"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene through a graph, headless; print per-pass GPU times and light statistics.
    Render(RenderArgs),
    /// Validate graph files; every error is printed as file:line:col. Exit 1 if any.
    Validate { files: Vec<PathBuf> },
    /// Print the compiled schedule (after culling for the scene) as Graphviz.
    Graph {
        graph: PathBuf,
        #[arg(long)]
        scene: Option<PathBuf>,
        #[arg(long)]
        dot: bool,
    },
    /// Hot reload, headless: re-render on every change to shaders/, materials/, the
    /// graph or the scene; print the reload latency or the error (the last good frame
    /// stays in --out).
    Watch {
        #[arg(long)]
        scene: Option<PathBuf>,
        #[arg(long)]
        graph: Option<PathBuf>,
        #[arg(long, default_value_t = 640)]
        width: u32,
        #[arg(long, default_value_t = 360)]
        height: u32,
        #[arg(long)]
        out: PathBuf,
    },
    /// A window onto a hot-reloading graph: fly/orbit camera, per-pass GPU times, light
    /// statistics, reload errors and graph variants in an overlay.
    View(ViewArgs),
    /// Check a layered material; with --wgsl print the WGSL generated for it.
    Material {
        file: PathBuf,
        #[arg(long)]
        wgsl: bool,
    },
    /// Compare two EXR images: RMSE, max abs, PSNR, FLIP mean, bad pixels.
    Compare { a: PathBuf, b: PathBuf },
    /// Time against error: run a sweep file, write CSV, Markdown and plots to --out.
    Bench {
        #[arg(long)]
        sweep: Option<PathBuf>,
        #[arg(long)]
        out: PathBuf,
    },
    /// Hot-reload latency: time real shader, material and graph edits from the file
    /// write to the new frame; write CSV and Markdown to --out.
    ReloadBench(ReloadBenchArgs),
}

#[derive(clap::Args)]
struct ReloadBenchArgs {
    #[arg(long)]
    out: PathBuf,
    #[arg(long, default_value_t = 160)]
    width: u32,
    #[arg(long, default_value_t = 90)]
    height: u32,
    /// Random lights in the benchmark scene.
    #[arg(long, default_value_t = 1024)]
    lights: u32,
    /// Edits of each kind.
    #[arg(long, default_value_t = 10)]
    repeats: usize,
}

#[derive(clap::Args, Default)]
struct RenderArgs {
    /// Scene: .ron, .gltf or .glb (default: the built-in atrium).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Graph file (default: graphs/forward_plus.ron).
    #[arg(long)]
    graph: Option<PathBuf>,
    #[arg(long)]
    width: Option<u32>,
    #[arg(long)]
    height: Option<u32>,
    /// Output image: .png (tonemapped sRGB) or .exr (linear HDR, 32-bit float).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Lights-per-tile heat map (PNG); a histogram CSV is written beside it.
    #[arg(long)]
    heatmap: Option<PathBuf>,
}

#[derive(clap::Args)]
struct ViewArgs {
    /// Scene: .ron, .gltf or .glb (default: the built-in atrium). Watched and reloaded.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Graph file (default: graphs/forward_plus.ron); the other graphs in its folder are
    /// offered as variants.
    #[arg(long)]
    graph: Option<PathBuf>,
    #[arg(long, default_value_t = 1280)]
    width: u32,
    #[arg(long, default_value_t = 720)]
    height: u32,
    /// Render size relative to the window (0.5 shades a quarter of the pixels).
    #[arg(long, default_value_t = 1.0)]
    scale: f32,
    /// Exposure in stops.
    #[arg(long, default_value_t = 0.0)]
    exposure: f32,
    /// Save what the window shows to this PNG after --frames frames, then exit.
    #[arg(long)]
    screenshot: Option<PathBuf>,
    #[arg(long, default_value_t = 10)]
    frames: u32,
}

fn project_path(rel: &str) -> PathBuf {
    lightgraph::project_root().join(rel)
}

fn load_scene(path: Option<&Path>) -> Result<Scene> {
    match path {
        None => Ok(scene::builtin::atrium()),
        Some(p) => {
            let loaded =
                scene::load(p).with_context(|| format!("loading scene {}", p.display()))?;
            for w in &loaded.warnings {
                eprintln!("warning: {w}");
            }
            let mut scene = loaded.scene;
            if scene.lights.is_empty() {
                if let Some(bounds) = scene.bounds() {
                    let l = scene::lights::fallback_light(bounds);
                    eprintln!(
                        "warning: {} has no lights; added a point light at {:.2?} (range {:.2}, {:.2} cd)",
                        p.display(),
                        l.position,
                        l.range,
                        l.intensity
                    );
                    scene.lights.push(l);
                }
            }
            Ok(scene)
        }
    }
}

fn main() -> Result<()> {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    match cli.command {
        None => render(RenderArgs::default()),
        Some(Command::Render(args)) => render(args),
        Some(Command::Validate { files }) => validate(&files),
        Some(Command::Graph { graph, scene, dot }) => print_graph(&graph, scene.as_deref(), dot),
        Some(Command::Compare { a, b }) => compare(&a, &b),
        Some(Command::Material { file, wgsl }) => material(&file, wgsl),
        Some(Command::Watch {
            scene,
            graph,
            width,
            height,
            out,
        }) => watch(scene, graph, width, height, &out),
        Some(Command::Bench { sweep, out }) => run_bench(sweep.as_deref(), &out),
        Some(Command::View(args)) => view(args),
        Some(Command::ReloadBench(args)) => reload_bench(&args),
    }
}

fn validate(files: &[PathBuf]) -> Result<()> {
    let shaders = ShaderLibrary::builtin();
    let mut failed = false;
    for f in files {
        let text = std::fs::read_to_string(f).unwrap_or_default();
        // Graphs, scenes and materials are all RON: the top-level name tells them apart.
        let head = text
            .lines()
            .map(str::trim)
            .find(|l| !l.is_empty() && !l.starts_with("//"))
            .unwrap_or("");
        let result: Result<(), String> = if head.starts_with("Graph") {
            graph::check_file(f, &shaders)
                .map(|_| ())
                .map_err(|e| e.to_string())
        } else if head.starts_with("Scene") || f.extension().is_none_or(|e| e != "ron") {
            scene::load(f).map(|_| ()).map_err(|e| e.to_string())
        } else {
            lightgraph::material::Material::load(f)
                .and_then(|m| m.wgsl().map(|_| ()))
                .map_err(|e| e.to_string())
        };
        match result {
            Ok(()) => println!("{}: ok", f.display()),
            Err(e) => {
                failed = true;
                eprintln!("{e}");
            }
        }
    }
    if failed {
        std::process::exit(1);
    }
    Ok(())
}

fn print_graph(path: &Path, scene_path: Option<&Path>, dot: bool) -> Result<()> {
    let scene = load_scene(scene_path)?;
    let checked = graph::check_file(path, &ShaderLibrary::builtin())?;
    let (w, h) = scene.output_size.unwrap_or((1280, 720));
    let compiled = graph::compile(
        checked,
        &scene.features(),
        FrameSize {
            width: w,
            height: h,
            lights: scene.lights.len() as u32,
        },
    );
    if dot {
        print!("{}", compiled.to_dot());
    } else {
        for (i, p) in compiled.passes.iter().enumerate() {
            println!("{}. {} ({})", i + 1, p.name, p.kind.label());
        }
        for c in &compiled.culled {
            println!("culled: {} ({:?})", c.name, c.reason);
        }
        println!(
            "{} physical resources for {} graph resources",
            compiled.plan.physical.len(),
            compiled.plan.resources.len()
        );
    }
    Ok(())
}

fn render(args: RenderArgs) -> Result<()> {
    let scene = load_scene(args.scene.as_deref())?;
    let graph_path = args
        .graph
        .clone()
        .unwrap_or_else(|| project_path("graphs/forward_plus.ron"));
    let (dw, dh) = scene.output_size.unwrap_or((1280, 720));
    let size = FrameSize {
        width: args.width.unwrap_or(dw),
        height: args.height.unwrap_or(dh),
        lights: scene.lights.len() as u32,
    };
    if size.width == 0 || size.height == 0 {
        bail!("output size {}x{} is empty", size.width, size.height);
    }
    let mut renderer = Renderer::headless()?;
    let checked = graph::check_file(&graph_path, &renderer.shaders)?;
    let compiled = graph::compile(checked, &scene.features(), size);
    let gpu = SceneGpu::upload(&renderer.ctx.device, &renderer.ctx.queue, &scene)?;
    let stats = compiled.has_forward_shading();
    let prepared = renderer.prepare(compiled, &scene, &gpu, size, stats)?;
    // The first frame builds pipelines and warms caches; report the second.
    prepared.execute(&renderer)?;
    let result = prepared.render(&renderer)?;
    report(&renderer, &scene, &graph_path, &result);
    if let Some(out) = &args.out {
        write_image(out, &result)?;
        println!("wrote {}", out.display());
    }
    if let Some(path) = &args.heatmap {
        let Some(c) = result.culling.first() else {
            bail!("--heatmap needs a graph with a LightCulling pass");
        };
        let tile = size.width.div_ceil(c.layout.tiles_x);
        let rgb = heatmap::heatmap_rgb8(
            &c.per_tile(),
            c.layout.tiles_x,
            tile,
            size.width,
            size.height,
        );
        bench::write_png_rgb8(path, rgb, size.width, size.height)?;
        let csv = path.with_extension("csv");
        std::fs::write(&csv, heatmap::histogram_csv(&c.per_tile()))
            .with_context(|| csv.display().to_string())?;
        println!("wrote {} and {}", path.display(), csv.display());
    }
    Ok(())
}

fn report(r: &Renderer, scene: &Scene, graph: &Path, result: &FrameResult) {
    println!("adapter: {}", r.ctx.adapter_name());
    println!(
        "scene: {} ({} meshes, {} lights), graph: {}, {}x{}",
        scene.name,
        scene.meshes.len(),
        scene.lights.len(),
        graph.display(),
        result.width,
        result.height
    );
    match &result.pass_ms {
        Some(times) => {
            let total: f64 = times.iter().map(|t| t.1).sum();
            for (name, ms) in times {
                println!("  {name:<24} {ms:>9.3} ms");
            }
            println!("  {:<24} {total:>9.3} ms", "total");
        }
        None => println!("  (this adapter has no timestamp queries: no per-pass GPU times)"),
    }
    for c in &result.culling {
        let per_tile = c.per_tile();
        let avg = per_tile.iter().map(|&x| x as f64).sum::<f64>() / per_tile.len().max(1) as f64;
        println!(
            "  {}: {} tiles x {} lists, lights per tile avg {avg:.1} max {}, longest list wanted {}",
            c.pass,
            c.layout.tiles_x * c.layout.tiles_y,
            c.layout.lists_per_tile,
            per_tile.iter().max().unwrap_or(&0),
            c.longest_list
        );
        if c.overflowed_lists > 0 {
            println!(
                "  WARNING: {} lists overflowed their capacity of {} (worst wanted {}): lights were dropped there",
                c.overflowed_lists, c.layout.capacity, c.longest_list
            );
        }
    }
    if let Some(s) = &result.light_stats {
        println!(
            "  lights per pixel: listed avg {:.2} max {}, exact avg {:.2} max {}, listed/exact {:.2}",
            s.avg_listed(),
            s.max_listed,
            s.avg_exact(),
            s.max_exact,
            s.false_positive_ratio()
        );
    }
}

fn write_image(out: &Path, result: &FrameResult) -> Result<()> {
    match out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("exr") => bench::write_exr(out, &result.image, result.width, result.height)?,
        Some("png") => bench::write_png_tonemapped(
            out,
            &result.image,
            result.width,
            result.height,
            &Tonemap::default(),
        )?,
        _ => bail!("{}: output must end in .png or .exr", out.display()),
    }
    Ok(())
}

fn compare(a: &Path, b: &Path) -> Result<()> {
    let ia = bench::read_exr(a)?;
    let ib = bench::read_exr(b)?;
    let m = bench::compare(
        &ia.pixels,
        &ib.pixels,
        ia.width,
        ia.height,
        &Default::default(),
    )?;
    println!("{m:#?}");
    Ok(())
}

fn run_bench(sweep: Option<&Path>, out: &Path) -> Result<()> {
    use bench::sweep::SweepEvent;
    let path = sweep
        .map(Path::to_path_buf)
        .unwrap_or_else(|| project_path("benches/sweeps/headline.ron"));
    let sweep = bench::sweep::Sweep::load(&path)?;
    let mut renderer = Renderer::headless()?;
    let progress = bench::progress::SweepProgress::new(sweep.point_count());
    progress.println(&format!("adapter: {}", renderer.ctx.adapter_name()));
    if !renderer.ctx.has_timestamps {
        progress.warn(&format!(
            "{} has no timestamp queries: no GPU times will be reported (time columns stay empty, no time plots)",
            renderer.ctx.adapter_name()
        ));
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    let rows = bench::sweep::run(&sweep, dir, &mut renderer, |event| match event {
        SweepEvent::Start { point, .. } => progress.start(point),
        SweepEvent::Done { done, total, row } => {
            progress.finish_point();
            progress.println(&format!("[{done}/{total}] {}", point_summary(row)));
            if let Some(warning) = non_finite_warning(row) {
                progress.warn(&warning);
            }
        }
    });
    progress.finish();
    let rows = rows?;
    std::fs::create_dir_all(out).with_context(|| out.display().to_string())?;
    let files = bench::write_report(out, &rows)?;
    if let Some(reason) = &files.plots_skipped {
        println!("time plots not drawn: no GPU times ({reason})");
    }
    println!("wrote {}", files.markdown.display());
    Ok(())
}

/// One log line per point: time, error against the reference, NaN / Inf counts.
fn point_summary(row: &bench::BenchRow) -> String {
    let time = match row.frame_ms {
        Some(t) => format!("{:.3} ms (p10 {:.3}, p90 {:.3})", t.median, t.p10, t.p90),
        None => format!(
            "no GPU time: {}",
            row.untimed.as_deref().unwrap_or("not measured")
        ),
    };
    let error = match (row.rmse, row.max_abs, row.max_rel) {
        (Some(rmse), Some(abs), Some(rel)) => {
            format!("rmse {rmse:.3e} max abs {abs:.3e} max rel {rel:.3e}")
        }
        _ => "no reference".into(),
    };
    format!(
        "{} {} {} lights {}x{}: {time}, {error}, NaN px {}, Inf px {}",
        row.scene,
        row.technique,
        row.light_count,
        row.width,
        row.height,
        row.nan_pixels.unwrap_or(0),
        row.inf_pixels.unwrap_or(0)
    )
}

/// A warning naming the first NaN / Inf pixels of a point, if it has any.
fn non_finite_warning(row: &bench::BenchRow) -> Option<String> {
    if row.non_finite_examples.is_empty() {
        return None;
    }
    let listed: Vec<String> = row
        .non_finite_examples
        .iter()
        .take(4)
        .map(|p| format!("{} at ({}, {})", p.kind(), p.x, p.y))
        .collect();
    Some(format!(
        "{} {}: {} NaN and {} Inf pixels, first {}",
        row.scene,
        row.technique,
        row.nan_pixels.unwrap_or(0),
        row.inf_pixels.unwrap_or(0),
        listed.join(", ")
    ))
}

fn reload_bench(args: &ReloadBenchArgs) -> Result<()> {
    use lightgraph::bench::reload_latency as rl;
    if args.width == 0 || args.height == 0 || args.repeats == 0 {
        bail!("--width, --height and --repeats must be positive");
    }
    // A fresh folder of our own to copy the inputs into and edit.
    let work = std::env::temp_dir().join(format!("lightgraph-reload-bench-{}", std::process::id()));
    if work.exists() {
        std::fs::remove_dir_all(&work).with_context(|| work.display().to_string())?;
    }
    let config = rl::ReloadBenchConfig {
        project: lightgraph::project_root(),
        work: work.clone(),
        width: args.width,
        height: args.height,
        lights: args.lights,
        repeats: args.repeats,
    };
    let gpu = lightgraph::gpu::GpuContext::new_headless()?;
    let adapter = gpu.adapter_name();
    println!("adapter: {adapter}");
    let result = rl::run(&config, gpu, |s| {
        println!(
            "{:<8} #{:<3} {:>8.1} ms  (watch {:.1}, compose {:.1}, build {:.1}, render {:.1} [again {:.1}]; {} pipelines built, {} resources reused, {} created)",
            s.kind.to_string(),
            s.index,
            s.total_ms,
            s.watch_ms,
            s.shader_compose_ms,
            s.pipeline_build_ms,
            s.render_ms,
            s.rerender_ms,
            s.pipelines_built,
            s.resources_reused,
            s.resources_created
        );
    });
    let _ = std::fs::remove_dir_all(&work);
    let samples = result?;
    std::fs::create_dir_all(&args.out).with_context(|| args.out.display().to_string())?;
    let csv = args.out.join("reload_latency.csv");
    std::fs::write(&csv, rl::to_csv(&samples)).with_context(|| csv.display().to_string())?;
    let md = args.out.join("reload_latency.md");
    let watch = lightgraph::reload::WatchConfig::default();
    std::fs::write(&md, rl::to_markdown(&samples, &config, &adapter, &watch))
        .with_context(|| md.display().to_string())?;
    for k in rl::summarize_kinds(&samples) {
        println!(
            "{}: median {:.1} ms, p10 {:.1}, p90 {:.1}",
            k.kind, k.total.median, k.total.p10, k.total.p90
        );
    }
    println!("wrote {} and {}", csv.display(), md.display());
    Ok(())
}

fn material(path: &Path, wgsl: bool) -> Result<()> {
    let m = lightgraph::material::Material::load(path)?;
    for w in m.warnings() {
        eprintln!("warning: {w}");
    }
    let code = m.wgsl()?;
    if wgsl {
        print!("{code}");
    } else {
        println!(
            "{}: ok ({} texture slots, type bit {})",
            path.display(),
            m.texture_slots().len(),
            m.type_bit()
        );
    }
    Ok(())
}

fn watch(
    scene: Option<PathBuf>,
    graph: Option<PathBuf>,
    width: u32,
    height: u32,
    out: &Path,
) -> Result<()> {
    use lightgraph::reload::{ReloadSession, SceneSource};
    let graph = graph.unwrap_or_else(|| project_path("graphs/forward_plus.ron"));
    let source = match scene {
        Some(p) => SceneSource::File(p),
        None => SceneSource::Fixed(Box::new(load_scene(None)?)),
    };
    let renderer = Renderer::headless()?;
    let materials = vec![project_path("materials")];
    let mut session = ReloadSession::new(renderer, &graph, source, width, height, &materials)
        .map_err(anyhow::Error::msg)?;
    let write = |s: &ReloadSession| -> Result<()> {
        write_image(out, s.frame.as_ref().expect("a first frame"))
    };
    write(&session)?;
    println!(
        "watching; wrote {} (edit a shader, material, graph or the scene; Ctrl-C stops)",
        out.display()
    );
    loop {
        let Some(reload) = session.wait(std::time::Duration::from_secs(3600)) else {
            continue;
        };
        let names: Vec<String> = reload
            .changed
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        match &reload.outcome {
            Ok(_) if reload.rebuilt.is_empty() => {
                println!("not used by this frame: {}", names.join(", "));
            }
            Ok(latency) => {
                write(&session)?;
                println!(
                    "reloaded {} in {:.1} ms after the change was seen: {}",
                    reload.rebuilt.join(", "),
                    latency.as_secs_f64() * 1e3,
                    names.join(", ")
                );
            }
            Err(e) => eprintln!("error (still showing the last good frame):\n{e}"),
        }
    }
}

fn view(args: ViewArgs) -> Result<()> {
    use lightgraph::reload::SceneSource;
    use lightgraph::view::{self, ViewOptions};
    if !(args.scale > 0.0 && args.scale <= 4.0) {
        bail!("--scale must be in (0, 4], got {}", args.scale);
    }
    let graph = args
        .graph
        .unwrap_or_else(|| project_path("graphs/forward_plus.ron"));
    let folder = graph.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut variants: Vec<PathBuf> = std::fs::read_dir(&folder)
        .with_context(|| format!("listing graph variants in {}", folder.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    variants.sort();
    let (scene, scene_name) = match args.scene {
        Some(p) => {
            let name = p.display().to_string();
            (SceneSource::File(p), name)
        }
        None => (
            SceneSource::Fixed(Box::new(load_scene(None)?)),
            "atrium (built-in)".to_string(),
        ),
    };
    view::run(ViewOptions {
        scene,
        scene_name,
        graph,
        variants,
        watch: vec![project_path("materials")],
        window_size: [args.width, args.height],
        render_scale: args.scale,
        exposure_ev: args.exposure,
        screenshot: args.screenshot.map(|p| (p, args.frames.max(1))),
    })?;
    Ok(())
}
