//! What `render` prints after its frame: passes and their GPU times, light statistics,
//! memory, shadows and the shadow atlas, light linked lists, and anything that overflowed
//! or came out non-finite.

use lightgraph::bench;
use lightgraph::graph;
use lightgraph::render::{FrameResult, Renderer, SceneGpu};
use lightgraph::scene::Scene;
use std::path::Path;

/// A light linked list pass: its resolution, pool and memory, and any overflow.
fn link_report(l: &lightgraph::render::LinkReport) {
    let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
    let pixels = l.layout.pixels().max(1) as f64;
    println!(
        "  {}: {}x{} list pixels (1/{} per side), {} links ({:.2} a list pixel, longest list {}), pool of {} links: {:.2} MiB ({:.2} MiB links of 12 bytes, {:.2} MiB heads)",
        l.pass,
        l.layout.width,
        l.layout.height,
        l.layout.scale,
        l.links(),
        l.links() as f64 / pixels,
        l.longest_list,
        l.layout.pool,
        mib(l.bytes()),
        mib(l.layout.pool_bytes()),
        mib(l.head_bytes()),
    );
    if l.links_dropped > 0 {
        println!(
            "  WARNING: the link pool of {} overflowed: {} links dropped in {} list pixels (wanted {}): those lights are missing there; raise links_per_pixel to at least {:.0}",
            l.layout.pool,
            l.links_dropped,
            l.overflow_pixels,
            l.links_wanted,
            (l.links_wanted as f64 / pixels).ceil()
        );
    }
}

/// Pixels whose shading overflowed f32 (a light very bright for its distance on a
/// sharp lobe): counted, never clamped, so the user sees where.
pub(super) fn overflow_report(result: &FrameResult) {
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
pub(super) fn shadow_report(scene: &Scene, gpu: &SceneGpu, result: &FrameResult) {
    // Virtual lights: what was spawned, and what found no room (never silent).
    for v in &result.vpls {
        for line in v.lines() {
            match line.strip_prefix("warning: ") {
                Some(w) => eprintln!("warning: {w}"),
                None => println!("  {line}"),
            }
        }
    }
    let casters = scene
        .lights
        .iter()
        .filter(|l| l.flags & lightgraph::scene::light_flags::CASTS_SHADOW != 0)
        .count();
    if casters == 0 && result.shadows.is_empty() && result.atlases.is_empty() {
        return;
    }
    println!(
        "  shadow-casting lights: {casters} of {}",
        scene.lights.len()
    );
    if let Some(b) = gpu.built_bvh() {
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
        if b.alpha_triangles > 0 {
            println!(
                "  shadow rays alpha-test {} triangles of alpha-masked casters",
                b.alpha_triangles
            );
        }
    }
    for a in &result.atlases {
        atlas_report(a);
    }
    for c in &result.shadow_compare {
        println!(
            "  {}: {} (pixel, light) pairs; the atlas disagrees with the rays on {:.3}% (5×5 PCF) and {:.3}% (2×2), {:.2}% in a 5×5 penumbra",
            c.pass,
            c.pairs,
            100.0 * c.error_pcf5(),
            100.0 * c.error_2x2(),
            100.0 * c.penumbra_pcf5 as f64 / c.pairs.max(1) as f64
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

/// What each shadow atlas gave this frame, and every light it could not shadow.
fn atlas_report(a: &lightgraph::render::AtlasReport) {
    let mib = |b: u64| b as f64 / (1 << 20) as f64;
    let tiers: Vec<String> = a
        .tiers()
        .iter()
        .map(|(t, n)| format!("{n} at {t}²"))
        .collect();
    println!(
        "  {}: {}² atlas ({:.1} MiB, table {:.2} MiB), {} lights shadowed in {} views ({}), {:.0}% of the atlas used, {} halvings, {} caster draws of {} triangles; {} casters off screen",
        a.pass,
        a.side,
        mib(a.atlas_bytes),
        mib(a.table_bytes),
        a.shadowed.len(),
        a.views,
        if tiers.is_empty() { "none".to_string() } else { tiers.join(", ") },
        100.0 * a.used_texels as f64 / (a.side as f64 * a.side as f64),
        a.halvings,
        a.draws,
        a.triangles,
        a.off_screen
    );
    println!(
        "  {}: {} of {} views drawn this frame (the rest kept: cache: true)",
        a.pass, a.views_rendered, a.views
    );
    if let Some(r) = &a.raster {
        println!(
            "  {}: compute raster: {} of {} records, {} of {} cells; drawn serially because a list was full: {} triangles, {} cells",
            a.pass,
            r.records,
            r.records_capacity,
            r.cells,
            r.cells_capacity,
            r.serial_triangles,
            r.serial_cells
        );
    }
    if !a.dropped.is_empty() {
        let list: Vec<String> = a
            .dropped
            .iter()
            .take(16)
            .map(|d| format!("light {} (wanted {}², {:?})", d.light, d.wanted, d.reason))
            .collect();
        let more = if a.dropped.len() > 16 { ", ..." } else { "" };
        if a.rays_for_the_rest {
            println!(
                "  {} shadow-casting lights in view got no room in '{}' and are ray-cast instead: {}{more}",
                a.dropped.len(),
                a.pass,
                list.join(", "),
            );
        } else {
            println!(
                "  WARNING: {} shadow-casting lights in view got no room in '{}' and are lit unshadowed: {}{more}",
                a.dropped.len(),
                a.pass,
                list.join(", "),
            );
        }
    }
    if !a.left_by_policy.is_empty() {
        println!(
            "  {}: the policy leaves {} shadow-casting lights in view to ray-cast shadows",
            a.pass,
            a.left_by_policy.len()
        );
    }
}

/// What transparency and MSAA add to the frame's memory, resource by resource.
pub(super) fn memory_report(techniques: &[graph::memory::TechniqueMemory], total: u64) {
    let mib = |b: u64| b as f64 / (1 << 20) as f64;
    println!(
        "  memory: {:.2} MiB of planned textures and buffers",
        mib(total)
    );
    for t in techniques {
        let items: Vec<String> = t
            .items
            .iter()
            .map(|i| match &i.shares_with {
                Some(other) => format!(
                    "{} {:.2} MiB (shares {other}'s memory: +0)",
                    i.resource,
                    mib(i.bytes)
                ),
                None if i.added == i.bytes => format!("{} {:.2} MiB", i.resource, mib(i.bytes)),
                None => format!(
                    "{} {:.2} MiB (+{:.2} over 1 sample)",
                    i.resource,
                    mib(i.bytes),
                    mib(i.added)
                ),
            })
            .collect();
        println!(
            "  memory, {}: adds {:.2} MiB: {}",
            t.technique,
            mib(t.added()),
            items.join(", ")
        );
    }
}

pub(super) fn report(r: &Renderer, scene: &Scene, graph: &Path, result: &FrameResult) {
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
    // Passes that ran another way on this adapter (their times above are that way's).
    for f in &result.fallbacks {
        println!("  fallback: {}", f.line());
    }
    for c in &result.culling {
        println!("  {}", c.summary());
        for w in c.warnings() {
            println!("  WARNING: {w}");
        }
    }
    for l in &result.links {
        link_report(l);
    }
    for c in &result.rasters {
        for line in c.lines() {
            match line.strip_prefix("warning: ") {
                Some(w) => println!("  WARNING: {w}"),
                None => println!("  {line}"),
            }
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
