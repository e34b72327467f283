//! One frame and the checks: `render`, `validate`, `graph`, `compare`, `material`.

use super::{project_path, render_report, RenderArgs};
use anyhow::{bail, Context, Result};
use lightgraph::bench::{self, heatmap, Tonemap};
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{materials, FrameResult, Renderer, SceneGpu};
use lightgraph::scene::{self, Scene};
use lightgraph::shader::{assets, ShaderLibrary};
use std::path::{Path, PathBuf};

/// The scene `lightgraph` renders without arguments: `scenes/gallery.ron` of the project
/// root (a checkout: glTF models, many coloured lights, glass), if there is one; `None`
/// (the built-in atrium, which needs no files) for an installed binary run elsewhere.
pub fn default_scene_path() -> Option<PathBuf> {
    let root = assets::project().root?;
    Some(root.join("scenes/gallery.ron")).filter(|p| p.is_file())
}

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
            if let Some(l) = scene.add_headlight_if_unlit() {
                eprintln!(
                    "warning: {} has no lights; added a headlight at the camera {:.2?} (range {:.2}, {:.2} cd)",
                    p.display(),
                    l.position,
                    l.range,
                    l.intensity
                );
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
        FileKind::Sweep => {
            let text = read_text(f, caps::RON).map_err(|e| format!("{}: {e}", f.display()))?;
            lightgraph::bench::sweep::Sweep::parse(&text, f)
                .map(|_| ())
                .map_err(|e| e.to_string())
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

/// What `render` does without --width/--height on a software adapter: fit the scene's
/// size into this (the atrium at 1920×1080 takes minutes on lavapipe, 640×360 seconds).
const SOFTWARE_SIZE: (u32, u32) = (640, 360);

/// The frame size and why: flags first, else the scene's own size on a GPU, scaled down
/// to fit [`SOFTWARE_SIZE`] on a software adapter.
fn pick_size(
    args: &RenderArgs,
    scene_size: (u32, u32),
    software: bool,
) -> ((u32, u32), &'static str) {
    let (dw, dh) = scene_size;
    match (args.width, args.height) {
        (None, None) if software && (dw > SOFTWARE_SIZE.0 || dh > SOFTWARE_SIZE.1) => {
            let k = (SOFTWARE_SIZE.0 as f64 / dw as f64).min(SOFTWARE_SIZE.1 as f64 / dh as f64);
            let scaled = |v: u32| ((v as f64 * k).round() as u32).max(1);
            (
                (scaled(dw), scaled(dh)),
                "software adapter: small size, --width/--height for another",
            )
        }
        (None, None) if software => ((dw, dh), "the scene's size"),
        (None, None) => ((dw, dh), "GPU adapter: the scene's full size"),
        (w, h) => ((w.unwrap_or(dw), h.unwrap_or(dh)), "from --width/--height"),
    }
}

/// The lower-case extension of `path`, if any.
fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

/// Checks the output flags before anything is loaded or rendered.
fn check_outputs(args: &RenderArgs) -> Result<()> {
    if let Some(out) = &args.out {
        if !matches!(extension(out).as_deref(), Some("png" | "exr")) {
            bail!(
                "--out {}: the output must end in .png or .exr",
                out.display()
            );
        }
    }
    if let Some(h) = &args.heatmap {
        if extension(h).as_deref() != Some("png") {
            bail!("--heatmap {}: the heat map must end in .png", h.display());
        }
    }
    if args.width == Some(0) || args.height == Some(0) {
        bail!("--width and --height must be at least 1");
    }
    if args.time.is_some_and(|t| !t.is_finite()) {
        bail!("--time must be a finite number of seconds");
    }
    Ok(())
}

pub fn render(args: RenderArgs) -> Result<()> {
    check_outputs(&args)?;
    let mut scene = load_scene(args.scene.as_deref())?;
    scene.place_lights_at(args.time.unwrap_or(0.0));
    let graph_path = args
        .graph
        .clone()
        .unwrap_or_else(|| project_path("graphs/default.ron"));
    let options = lightgraph::gpu::ContextOptions {
        disabled_features: match &args.disable_features {
            Some(list) => lightgraph::gpu::ContextOptions::parse_features(list)
                .map_err(|e| anyhow::anyhow!("--disable-features: {e}"))?,
            None => wgpu::Features::empty(),
        },
        ..Default::default()
    };
    let mut renderer = Renderer::headless_with(&options)?;
    let checked = assets::check_graph(&graph_path, &renderer.shaders)?;
    let ((width, height), why) = pick_size(
        &args,
        scene.output_size.unwrap_or((1280, 720)),
        renderer.ctx.is_software(),
    );
    let size = FrameSize {
        width,
        height,
        lights: scene.lights.len() as u32,
    };
    if size.width == 0 || size.height == 0 {
        bail!("output size {}x{} is empty", size.width, size.height);
    }
    let features = scene.features();
    let compiled = graph::compile(checked, &features, size);
    for w in graph::coverage::undrawn(&compiled, &features) {
        eprintln!("warning: {w}");
    }
    if args.heatmap.is_some() && !compiled.has_light_culling() {
        bail!(
            "--heatmap needs a graph with a LightCulling pass; {} has none after culling",
            graph_path.display()
        );
    }
    eprintln!(
        "rendering {} ({} lights) at {width}x{height} ({why}) on {}...",
        scene.name,
        scene.lights.len(),
        renderer.ctx.adapter_name()
    );
    let gpu = SceneGpu::upload(&renderer.ctx.device, &renderer.ctx.queue, &scene)?;
    let stats = compiled.has_forward_shading();
    let memory = (
        graph::memory::by_technique(&compiled),
        graph::memory::total_bytes(&compiled),
    );
    let prepared = renderer.prepare(compiled, &scene, &gpu, size, stats)?;
    // The first frame builds pipelines and warms caches; report the second.
    prepared.execute(&renderer)?;
    let result = prepared.render(&renderer)?;
    render_report::report(&renderer, &scene, &graph_path, &result);
    render_report::memory_report(&memory.0, memory.1);
    render_report::shadow_report(&scene, &gpu, &result);
    render_report::overflow_report(&result);
    match &args.out {
        Some(out) => {
            write_image(out, &result)?;
            let shown = std::path::absolute(out).unwrap_or_else(|_| out.clone());
            println!("wrote {}", shown.display());
        }
        None => println!("(no image written: add --out F.png or --out F.exr)"),
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

pub fn write_image(out: &Path, result: &FrameResult) -> Result<()> {
    match extension(out).as_deref() {
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
    // Both sizes are checked, not only the pixel counts: 64×36 against 36×64 is refused.
    let m = bench::compare_files(a, b, &Default::default())?;
    println!("{}", compare_summary(&m));
    println!("{m}");
    Ok(())
}

/// One line first: identical, or how far apart and where it matters.
fn compare_summary(m: &bench::ImageMetrics) -> String {
    let non_finite = m.reference_non_finite.nan_pixels
        + m.reference_non_finite.inf_pixels
        + m.test_non_finite.nan_pixels
        + m.test_non_finite.inf_pixels;
    if m.rmse == 0.0 && m.max_abs == 0.0 && non_finite == 0 {
        return format!("identical ({}x{})", m.width, m.height);
    }
    let flip = m
        .flip_mean
        .map(|f| format!(", FLIP mean {f:.4}"))
        .unwrap_or_default();
    format!(
        "differ: RMSE {:.3e}, max abs {:.3e}, {} of {} pixels over {}{flip}{}",
        m.rmse,
        m.max_abs,
        m.bad_pixels,
        m.width as usize * m.height as usize,
        m.bad_pixel_threshold,
        if non_finite > 0 {
            format!(", {non_finite} non-finite pixels")
        } else {
            String::new()
        }
    )
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
