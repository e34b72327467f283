//! One frame and the checks: `render`, `validate`, `graph`, `compare`, `material`.

use super::{project_path, RenderArgs};
use anyhow::{bail, Context, Result};
use lightgraph::bench::{self, heatmap, Tonemap};
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{materials, FrameResult, Renderer, SceneGpu};
use lightgraph::scene::{self, Scene};
use lightgraph::shader::{assets, ShaderLibrary};
use std::path::{Path, PathBuf};

pub fn load_scene(path: Option<&Path>) -> Result<Scene> {
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

pub fn validate(files: &[PathBuf]) -> Result<()> {
    let shaders = ShaderLibrary::builtin();
    let mut failed = false;
    for f in files {
        match validate_one(f, &shaders) {
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

/// One file, by its extension and (for RON) its top-level struct name.
fn validate_one(f: &Path, shaders: &ShaderLibrary) -> Result<(), String> {
    use lightgraph::file_kind::{detect, FileKind};
    use lightgraph::files::{caps, read_text};
    let kind = detect(f, || read_text(f, caps::RON).ok())?;
    match kind {
        FileKind::Graph => graph::check_file(f, shaders)
            .map(|_| ())
            .map_err(|e| e.to_string()),
        FileKind::Scene | FileKind::Gltf => {
            let scene = scene::load(f).map_err(|e| e.to_string())?.scene;
            // Render loads every override; a broken one is known without a GPU.
            for (name, _) in &scene.material_overrides {
                if let Some(path) = lightgraph::render::materials::override_path(&scene, name) {
                    lightgraph::material::Material::load(&path)
                        .and_then(|m| m.wgsl())
                        .map_err(|e| materials::override_error(&scene, name, e).to_string())?;
                }
            }
            Ok(())
        }
        FileKind::Material => lightgraph::material::Material::load(f)
            .and_then(|m| m.wgsl().map(|_| ()))
            .map_err(|e| e.to_string()),
        FileKind::Shader => {
            // Includes resolve against the shader root, as for a graph's shaders.
            let file = std::path::absolute(f).map_err(|e| format!("{}: {e}", f.display()))?;
            shaders
                .compose(
                    &file.to_string_lossy(),
                    &Default::default(),
                    &Default::default(),
                )
                .and_then(|c| c.validate().map(|_| ()))
                .map_err(|e| e.to_string())
        }
    }
}

pub fn print_graph(path: &Path, scene_path: Option<&Path>, dot: bool) -> Result<()> {
    let scene = load_scene(scene_path)?;
    let checked = assets::check_graph(path, &ShaderLibrary::builtin())?;
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

pub fn render(args: RenderArgs) -> Result<()> {
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
    let checked = assets::check_graph(&graph_path, &renderer.shaders)?;
    let compiled = graph::compile(checked, &scene.features(), size);
    let gpu = SceneGpu::upload(&renderer.ctx.device, &renderer.ctx.queue, &scene)?;
    let stats = compiled.has_forward_shading();
    let prepared = renderer.prepare(compiled, &scene, &gpu, size, stats)?;
    // The first frame builds pipelines and warms caches; report the second.
    prepared.execute(&renderer)?;
    let result = prepared.render(&renderer)?;
    report(&renderer, &scene, &graph_path, &result);
    shadow_report(&scene, &gpu, &result);
    overflow_report(&result);
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

/// Pixels whose shading overflowed f32 (a light very bright for its distance on a
/// sharp lobe): counted, never clamped, so the user sees where.
fn overflow_report(result: &FrameResult) {
    let (n, first) = bench::non_finite_pixels(&result.image, result.width, 3);
    if n.nan_pixels + n.inf_pixels == 0 {
        return;
    }
    let at: Vec<String> = first
        .iter()
        .map(|p| format!("({}, {})", p.x, p.y))
        .collect();
    eprintln!(
        "warning: {} Inf and {} NaN pixels (an f32 overflow in shading), first at {}",
        n.inf_pixels,
        n.nan_pixels,
        at.join(", ")
    );
}

/// What ray-cast shadows cast this frame: casters, rays, drops, memory, the BVH.
fn shadow_report(scene: &Scene, gpu: &SceneGpu, result: &FrameResult) {
    let casters = scene
        .lights
        .iter()
        .filter(|l| l.flags & lightgraph::scene::light_flags::CASTS_SHADOW != 0)
        .count();
    if casters == 0 && result.shadows.is_empty() {
        return;
    }
    println!(
        "  shadow-casting lights: {casters} of {}",
        scene.lights.len()
    );
    if let Some(b) = &gpu.bvh {
        let s = &b.stats;
        println!(
            "  shadow BVH: {} triangles ({} degenerate, {} non-finite, {} bad indices skipped), {} nodes, built in {:.1} ms, {:.1} MiB",
            s.triangles,
            s.skipped_degenerate,
            s.skipped_non_finite,
            s.skipped_bad_index,
            s.nodes,
            s.build_time.as_secs_f64() * 1e3,
            b.bytes() as f64 / (1 << 20) as f64
        );
    }
    for s in &result.shadows {
        println!(
            "  {}: {} rays traced ({:.2} a pixel), job buffer {:.1} MiB for {} jobs, mask {:.1} MiB",
            s.pass,
            s.rays(),
            s.rays() as f64 / s.pixels.max(1) as f64,
            s.job_bytes as f64 / (1 << 20) as f64,
            s.capacity,
            s.mask_bytes as f64 / (1 << 20) as f64
        );
        if s.jobs_dropped > 0 {
            println!(
                "  WARNING: {} of {} shadow jobs did not fit the job buffer (raise jobs_per_pixel): those lights were lit unshadowed",
                s.jobs_dropped, s.jobs_wanted
            );
        }
        if s.overflow_pixels > 0 {
            println!(
                "  WARNING: {} pixels have more than 128 shadow-casting lights: the rest were lit unshadowed",
                s.overflow_pixels
            );
        }
    }
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

pub fn write_image(out: &Path, result: &FrameResult) -> Result<()> {
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

pub fn compare(a: &Path, b: &Path) -> Result<()> {
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

pub fn material(path: &Path, wgsl: bool) -> Result<()> {
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
