//! `vpl-error`: for each n, the VPL image's indirect part (the all-lights VPL graph's
//! frame minus the frame without VPLs) against the CPU path-traced bounce
//! (`indirect::reference`): relative MSE, the worst pixel's share of it and any non-finite
//! pixels; and the median GPU time of the passes the VPLs
//! cost in the culled graph (maps, spawn, culling, shading) over `frames` frames, with
//! its list overflows. Writes results.csv, results.md, time_vs_error.png.

use super::vpl_variants::{self, Variant};
use super::{render::load_scene, VplErrorArgs};
use anyhow::{bail, Context, Result};
use lightgraph::graph::{self, FrameSize};
use lightgraph::indirect::reference::{
    indirect_part, relative_mse, worst_pixel, OneBounce, WorstPixel,
};
use lightgraph::render::{Renderer, SceneGpu};
use lightgraph::scene::{light_flags, Scene};
use std::fmt::Write as _;
use std::path::Path;
use std::time::{Duration, Instant};

/// Least warm-up before a graph's timed frames (the sweeps' `warmup_seconds` default).
const WARMUP: Duration = Duration::from_secs(1);

/// Passes whose GPU time the table reports, each by the names the shipped VPL graphs use
/// (shading: Forward+'s or the compute-first frame's; visibility: `VplVisibility`'s).
const PASSES: [&[&str]; 5] = [
    &["rsm"],
    &["vpl_spawn"],
    &["light_culling"],
    &["forward_shading", "visibility_shading"],
    &["vpl_rays"],
];

struct Row {
    scene: String,
    variant: String,
    n: u32,
    vpls: u32,
    dropped: u32,
    overflowed_lists: u32,
    rel_mse: f64,
    energy: f64,
    worst: WorstPixel,
    frame_ms: Option<f64>,
    pass_ms: Vec<Option<f64>>,
}

/// One frame's GPU time per pass (ms).
type PassTimes = Vec<(String, f64)>;

fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

fn frame(
    r: &mut Renderer,
    graph_path: &Path,
    spawn: Option<&str>,
    scene: &Scene,
    w: u32,
    h: u32,
    frames: u32,
) -> Result<(lightgraph::render::FrameResult, Vec<PassTimes>)> {
    let checked = vpl_variants::check(graph_path, spawn)?;
    let size = FrameSize {
        width: w,
        height: h,
        lights: scene.lights.len() as u32,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, scene)?;
    let prepared = r.prepare(compiled, scene, &gpu, size, false)?;
    // Warm up by time as the benchmark does (docs/benchmarks.md): from idle the GPU's
    // clocks take about a second to ramp, and `frames` frames alone left the first n's
    // maps at 2.3–2.8 ms against 0.49 ms after. Each frame waits for its timestamps.
    let start = Instant::now();
    let mut warmed = 0;
    while warmed < frames || start.elapsed() < WARMUP {
        prepared.execute(r)?;
        warmed += 1;
    }
    let mut times = Vec::new();
    for _ in 0..frames {
        if let Some(t) = prepared.execute(r)? {
            times.push(t);
        }
    }
    Ok((prepared.render(r)?, times))
}

/// Where the VPL image errs: red where it has more light than the reference, blue where
/// less, each pixel's luminance difference over the largest one's, square-rooted so that
/// errors a hundredth of the worst still show.
fn error_map(vpl: &[glam::Vec3], reference: &[glam::Vec3]) -> Vec<u8> {
    let luma = |c: glam::Vec3| c.dot(glam::Vec3::new(0.2126, 0.7152, 0.0722));
    let diff: Vec<f32> = vpl
        .iter()
        .zip(reference)
        .map(|(a, b)| luma(*a) - luma(*b))
        .map(|d| if d.is_finite() { d } else { 0.0 })
        .collect();
    let worst = diff.iter().fold(0.0f32, |m, d| m.max(d.abs())).max(1e-30);
    let level = |d: f32| ((d.max(0.0) / worst).sqrt() * 255.0).round() as u8;
    diff.iter()
        .flat_map(|&d| [level(d), 0, level(-d)])
        .collect()
}

/// A label as a file name's part: letters and digits, anything else `_`.
fn file_label(label: &str) -> String {
    label
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

pub fn run(args: &VplErrorArgs) -> Result<()> {
    let graph_path = args
        .graph
        .clone()
        .unwrap_or_else(|| super::project_path("graphs/indirect_vpl.ron"));
    let error_path = args
        .error_graph
        .clone()
        .unwrap_or_else(|| super::project_path("benches/graphs/indirect_vpl_all_lights.ron"));
    let direct_path = args
        .direct
        .clone()
        .unwrap_or_else(|| super::project_path("graphs/forward_plus.ron"));
    if args.n.is_empty() || args.frames == 0 || args.samples == 0 {
        bail!("--n, --frames and --samples need at least one");
    }
    let base = Variant {
        label: "vpl".into(),
        graph: graph_path,
        error_graph: error_path,
        direct: direct_path,
        spawn: None,
    };
    let variants = if args.variant.is_empty() {
        vec![base]
    } else {
        args.variant
            .iter()
            .map(|t| vpl_variants::parse(t, &base))
            .collect::<Result<Vec<_>>>()?
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let mut renderer = Renderer::headless()?;
    let (w, h) = (args.width, args.height);
    let mut rows = Vec::new();
    let mut md = String::from("# VPL one-bounce error against a path-traced bounce\n\n");
    let _ = writeln!(
        md,
        "Adapter: {}. {w}×{h}, reference {} bounce rays a pixel. Relative MSE = Σ(vpl − ref)² / Σ ref² of the indirect part (VPL frame minus the frame without VPLs); the worst pixel is the one with the largest (vpl − ref)², with its share of Σ(vpl − ref)²; times are GPU medians of {} frames after at least 1 s of warm-up.\n",
        renderer.ctx.adapter_name(),
        args.samples,
        args.frames
    );
    for scene_path in &args.scene {
        let base = load_scene(Some(scene_path))?;
        let indirect: Vec<usize> = (0..base.lights.len())
            .filter(|&i| base.lights[i].flags & light_flags::INDIRECT != 0)
            .collect();
        if indirect.is_empty() {
            bail!(
                "{}: no light is marked indirect: true",
                scene_path.display()
            );
        }
        let t = std::time::Instant::now();
        let tracer = OneBounce::new(&base)?;
        let reference = tracer.image(w, h, args.samples);
        let reference_s = t.elapsed().as_secs_f64();
        // Its own noise: half the relative MSE between it and an independent estimate
        // (the two differ by twice one's variance); a VPL image's relative MSE includes it.
        let noise = if args.no_noise {
            "not estimated".to_string()
        } else {
            let second = tracer.image_seeded(w, h, args.samples, 1);
            format!("{:.4}", relative_mse(&second, &reference) / 2.0)
        };
        eprintln!(
            "{}: reference ({} samples) in {reference_s:.1} s, its noise {noise} (relative MSE)",
            base.name, args.samples
        );
        let to_rgb = |v: &[glam::Vec3]| {
            v.iter()
                .map(|p| p.max(glam::Vec3::ZERO).to_array())
                .collect::<Vec<[f32; 3]>>()
        };
        // The indirect images, two stops up (they are dim beside direct light).
        let tonemap = lightgraph::bench::Tonemap::new(2.0, lightgraph::bench::ToneCurve::Reinhard);
        lightgraph::bench::write_png_tonemapped(
            args.out.join(format!("{}_reference.png", base.name)),
            &to_rgb(&reference),
            w,
            h,
            &tonemap,
        )?;
        let _ = writeln!(
            md,
            "## {} ({} indirect lights; reference {reference_s:.1} s on the CPU; its own noise: relative MSE {noise})\n\n| variant | n | VPLs | dropped | lists overflowed (timed graph) | rel. MSE | Σvpl/Σref | worst pixel: share of the squared error (VPL / reference luminance) | VPL passes (ms) | rsm | spawn | culling | shading | visibility |\n|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|",
            base.name,
            indirect.len()
        );
        for variant in &variants {
            let spawn = variant.spawn.as_deref();
            let (direct, _) = frame(&mut renderer, &variant.direct, None, &base, w, h, 1)?;
            for &n in &args.n {
                let mut scene = base.clone();
                for &i in &indirect {
                    let mut c = scene.vpl(i);
                    c.n = n;
                    c.check().map_err(|m| anyhow::anyhow!("--n {n}: {m}"))?;
                    scene.vpl_controls.insert(i as u32, c);
                }
                let (result, times) = frame(
                    &mut renderer,
                    &variant.graph,
                    spawn,
                    &scene,
                    w,
                    h,
                    args.frames,
                )?;
                let v = result
                    .vpls
                    .first()
                    .with_context(|| format!("{} ran no VplSpawn pass", variant.graph.display()))?;
                let (measured, _) =
                    frame(&mut renderer, &variant.error_graph, spawn, &scene, w, h, 0)?;
                let vpl_image = indirect_part(&measured.image, &direct.image);
                let e = relative_mse(&vpl_image, &reference);
                let worst = worst_pixel(&vpl_image, &reference);
                let (wx, wy) = (worst.index as u32 % w, worst.index as u32 / w);
                let luma = |c: glam::Vec3| c.dot(glam::Vec3::new(0.2126, 0.7152, 0.0722));
                lightgraph::bench::write_png_tonemapped(
                    args.out.join(format!(
                        "{}_{}_n{n}.png",
                        base.name,
                        file_label(&variant.label)
                    )),
                    &to_rgb(&vpl_image),
                    w,
                    h,
                    &tonemap,
                )?;
                lightgraph::bench::write_png_rgb8(
                    args.out.join(format!(
                        "{}_{}_n{n}_error.png",
                        base.name,
                        file_label(&variant.label)
                    )),
                    error_map(&vpl_image, &reference),
                    w,
                    h,
                )?;
                // Total indirect light of the VPL image over the reference's: bias, apart from noise.
                let total =
                    |v: &[glam::Vec3]| v.iter().map(|p| (p.x + p.y + p.z) as f64).sum::<f64>();
                let energy = total(&vpl_image) / total(&reference).max(1e-30);
                let overflowed_lists: u32 = result.culling.iter().map(|c| c.overflowed_lists).sum();
                let pass_ms: Vec<Option<f64>> = PASSES
                    .iter()
                    .map(|p| {
                        median(
                            times
                                .iter()
                                .filter_map(|t| {
                                    t.iter().find(|(n, _)| p.contains(&n.as_str())).map(|x| x.1)
                                })
                                .collect(),
                        )
                    })
                    .collect();
                let frame_ms = median(
                    times
                        .iter()
                        .map(|t| {
                            t.iter()
                                .filter(|(n, _)| PASSES.iter().any(|p| p.contains(&n.as_str())))
                                .map(|x| x.1)
                                .sum()
                        })
                        .collect(),
                );
                let ms = |x: Option<f64>| x.map_or("–".to_string(), |x| format!("{x:.3}"));
                let _ = writeln!(
                md,
                "| {} | {n} | {} | {} | {overflowed_lists} | {e:.4} | {energy:.3} | {:.1}% at ({wx}, {wy}) ({:.3} / {:.3}){} | {} | {} | {} | {} | {} | {} |",
                variant.label,
                v.spawned,
                v.dropped,
                100.0 * worst.share,
                luma(worst.value),
                luma(worst.reference),
                if worst.non_finite > 0 {
                    format!("; {} non-finite pixels", worst.non_finite)
                } else {
                    String::new()
                },
                ms(frame_ms),
                ms(pass_ms[0]),
                ms(pass_ms[1]),
                ms(pass_ms[2]),
                ms(pass_ms[3]),
                ms(pass_ms[4])
            );
                println!(
                "{} {} n={n}: {} VPLs ({} dropped, {overflowed_lists} lists overflowed), relative MSE {e:.4}, energy {energy:.3} of the reference's, worst pixel ({wx}, {wy}) {:.1}% of the squared error (VPL {:.3}, reference {:.3}), {} non-finite pixels, VPL passes {} ms",
                base.name,
                variant.label,
                v.spawned,
                v.dropped,
                100.0 * worst.share,
                luma(worst.value),
                luma(worst.reference),
                worst.non_finite,
                ms(frame_ms)
            );
                for line in v.lines().iter().skip(1) {
                    println!("  {line}");
                }
                rows.push(Row {
                    scene: base.name.clone(),
                    variant: variant.label.clone(),
                    n,
                    vpls: v.spawned,
                    dropped: v.dropped,
                    overflowed_lists,
                    rel_mse: e,
                    energy,
                    worst,
                    frame_ms,
                    pass_ms,
                });
            }
        }
        md.push('\n');
    }
    let mut csv = String::from(
        "scene,variant,n,vpls,dropped,overflowed_lists,rel_mse,energy_ratio,worst_pixel,worst_share,non_finite,vpl_passes_ms,rsm_ms,spawn_ms,culling_ms,shading_ms,visibility_ms\n",
    );
    let opt = |x: Option<f64>| x.map_or(String::new(), |x| format!("{x:.4}"));
    for r in &rows {
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{:.6},{:.4},{},{:.6},{},{},{}",
            r.scene,
            r.variant,
            r.n,
            r.vpls,
            r.dropped,
            r.overflowed_lists,
            r.rel_mse,
            r.energy,
            r.worst.index,
            r.worst.share,
            r.worst.non_finite,
            opt(r.frame_ms),
            r.pass_ms
                .iter()
                .map(|x| opt(*x))
                .collect::<Vec<_>>()
                .join(",")
        );
    }
    std::fs::write(args.out.join("results.csv"), csv)?;
    std::fs::write(args.out.join("results.md"), &md)?;
    let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for r in rows.iter().filter(|r| r.frame_ms.is_some()) {
        // One series a scene and variant (the variant's n values along it).
        let name = if variants.len() > 1 {
            format!("{}: {}", r.scene, r.variant)
        } else {
            r.scene.clone()
        };
        let point = (r.rel_mse, r.frame_ms.unwrap_or(0.0));
        match series.iter_mut().find(|(s, _)| *s == name) {
            Some((_, pts)) => pts.push(point),
            None => series.push((name, vec![point])),
        }
    }
    if series.is_empty() {
        println!("no timestamp queries on this adapter: no time plot");
    } else {
        lightgraph::bench::report::plot_time_vs_error_points(
            args.out.join("time_vs_error.png"),
            "VPL passes' GPU time vs one-bounce error",
            "relative MSE against the path-traced bounce (log)",
            &series,
        )?;
    }
    print!("{md}");
    Ok(())
}
