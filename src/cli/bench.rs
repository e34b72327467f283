//! `bench` (time against error) and `reload-bench` (edit-to-frame latency).

use super::{project_path, ReloadBenchArgs};
use anyhow::{bail, Context, Result};
use lightgraph::bench;
use lightgraph::render::Renderer;
use std::path::Path;

pub fn run_bench(sweep: Option<&Path>, out: &Path) -> Result<()> {
    use bench::sweep::SweepEvent;
    let mut renderer = Renderer::headless()?;
    let (path, sweep, why) = match sweep {
        Some(p) => (p.to_path_buf(), bench::sweep::Sweep::load(p)?, None),
        None => {
            let (rel, text, why) = default_sweep(renderer.ctx.is_software());
            // The root's copy if it has one, else the one built into the binary.
            let path = project_path(rel);
            let sweep = match std::fs::read_to_string(&path) {
                Ok(own) => bench::sweep::Sweep::parse(&own, &path)?,
                Err(_) => bench::sweep::Sweep::parse(text, Path::new(rel))?,
            };
            (path, sweep, Some(why))
        }
    };
    let progress = bench::progress::SweepProgress::new(sweep.point_count());
    progress.println(&format!("adapter: {}", renderer.ctx.adapter_name()));
    if let Some(why) = why {
        progress.println(&format!(
            "no --sweep: running {} ({} points; {why})",
            path.display(),
            sweep.point_count()
        ));
    }
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

/// The sweep `bench` runs without --sweep: (path, built-in text, why). headline.ron is
/// 25 points up to 65,536 lights at 1080p, hours on lavapipe; smoke.ron takes seconds.
fn default_sweep(software: bool) -> (&'static str, &'static str, &'static str) {
    if software {
        (
            "benches/sweeps/smoke.ron",
            include_str!("../../benches/sweeps/smoke.ron"),
            "software adapter: the smoke sweep; --sweep benches/sweeps/headline.ron for the full one",
        )
    } else {
        (
            "benches/sweeps/headline.ron",
            include_str!("../../benches/sweeps/headline.ron"),
            "GPU adapter: the headline sweep",
        )
    }
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
    // Lists that lost lights, or whose fill disagreed with their count: never silent.
    let lists = match (row.overflow_tiles, row.list_mismatched) {
        (Some(0) | None, Some(0) | None) => String::new(),
        (cut, mismatched) => format!(
            ", light lists cut {} (wanted {} indices), fills mismatched {}",
            cut.unwrap_or(0),
            row.list_indices_wanted
                .map_or("?".into(), |n| n.to_string()),
            mismatched.unwrap_or(0)
        ),
    };
    format!(
        "{} {} {} lights {}x{}: {time}, {error}, NaN px {}, Inf px {}{lists}",
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

pub fn reload_bench(args: &ReloadBenchArgs) -> Result<()> {
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
        salt: args.salt,
        frames_in_flight: args.frames_in_flight,
        viewer_frames: args.viewer_frames,
        wait_for_idle_before_build: args.wait_for_idle_before_build,
        sequential_builds: args.sequential_builds,
    };
    let gpu = lightgraph::gpu::GpuContext::new_headless()?;
    let adapter = gpu.adapter_name();
    println!("adapter: {adapter}");
    println!("pipeline cache: {}", gpu.pipeline_cache_status());
    let result = rl::run(&config, gpu, |s| {
        println!(
            "{:<8} #{:<3} new frame {:>7.1} ms, read back {:>7.1} ms  (watch {:.1}, compose {:.1}, build {:.1} [modules {:.1}, pipelines {:.1}{}], render {:.1} [submit {:.1}, GPU wait {:.1}, image readback {:.1}; again {:.1}]; {} pipelines built, {} resources reused, {} created)",
            s.kind.to_string(),
            s.index,
            s.frame_ms,
            s.total_ms,
            s.watch_ms,
            s.shader_compose_ms,
            s.pipeline_build_ms,
            s.shader_module_ms,
            s.pipeline_create_ms,
            match s.gpu_busy_at_build {
                Some(true) => ", GPU busy",
                _ => "",
            },
            s.render_ms,
            s.record_submit_ms,
            s.gpu_wait_ms,
            s.image_readback_ms,
            s.rerender_ms,
            s.pipelines_built,
            s.resources_reused,
            s.resources_created
        );
    });
    let _ = std::fs::remove_dir_all(&work);
    let run = result?;
    std::fs::create_dir_all(&args.out).with_context(|| args.out.display().to_string())?;
    let csv = args.out.join("reload_latency.csv");
    std::fs::write(&csv, rl::to_csv(&run.samples)).with_context(|| csv.display().to_string())?;
    let pipelines = args.out.join("reload_pipelines.csv");
    std::fs::write(&pipelines, rl::pipelines_csv(&run.samples))
        .with_context(|| pipelines.display().to_string())?;
    let md = args.out.join("reload_latency.md");
    let watch = lightgraph::reload::WatchConfig::default();
    std::fs::write(&md, rl::to_markdown(&run, &config, &adapter, &watch))
        .with_context(|| md.display().to_string())?;
    let st = &run.startup;
    println!(
        "session start: {:.1} ms, {} pipelines built (compose {:.1} ms, build {:.1} ms)",
        st.total_ms, st.pipelines_built, st.shader_compose_ms, st.pipeline_build_ms
    );
    for k in rl::summarize_kinds(&run.samples) {
        println!(
            "{}: edit -> new frame (viewer) median {:.1} ms, p10 {:.1}, p90 {:.1}; edit -> read back median {:.1} ms",
            k.kind, k.frame.median, k.frame.p10, k.frame.p90, k.total.median
        );
    }
    println!("wrote {} and {}", csv.display(), md.display());
    Ok(())
}
