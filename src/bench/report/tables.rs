//! The rows as tables: CSV (results and non-finite pixels) and GitHub-flavoured Markdown.

use super::{write_file, BenchRow, ReportError, TimingSummary};
use std::fmt::Write as _;
use std::path::Path;

/// Pass names over all rows, in first-seen order.
fn pass_names(rows: &[BenchRow]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for row in rows {
        for (name, _) in &row.pass_ms {
            if !names.contains(name) {
                names.push(name.clone());
            }
        }
    }
    names
}

fn pass_ms(row: &BenchRow, name: &str) -> Option<TimingSummary> {
    row.pass_ms.iter().find(|(n, _)| n == name).map(|(_, t)| *t)
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn opt<T: ToString>(v: Option<T>) -> String {
    v.map(|v| v.to_string()).unwrap_or_default()
}

/// The fixed CSV columns, in order; per-pass columns follow, three per pass name seen in any
/// row (first-seen order): `pass_ms:<name>` (median), `pass_ms_p10:<name>`, `pass_ms_p90:<name>`,
/// empty where a row lacks that pass. Time columns are empty, not 0, for untimed rows; the
/// ray-cast shadow columns (`shadow_*`, `bvh_*`) are empty for graphs without those passes.
pub const CSV_COLUMNS: [&str; 60] = [
    "scene",
    "technique",
    "params",
    "light_count",
    "width",
    "height",
    "adapter",
    "frame_ms_median",
    "frame_ms_p10",
    "frame_ms_p90",
    "rounds",
    "round_ms_min",
    "round_ms_max",
    "warmup_s",
    "light_update_cpu_ms",
    "sm_mhz_start",
    "sm_mhz_end",
    "sm_mhz_max",
    "rmse",
    "max_abs",
    "max_rel",
    "psnr",
    "flip_mean",
    "rel_mse",
    "seeds",
    "seed_rel_variance",
    "seed_rel_bias2",
    "listed_exact_ratio",
    "max_lights_per_tile",
    "overflow_tiles",
    "list_storage",
    "list_mib",
    "list_indices",
    "list_indices_wanted",
    "list_mismatched",
    "nan_pixels",
    "inf_pixels",
    "lit_pixels",
    "pass_count",
    "passes_ms_total",
    "reference",
    "shadow_rays",
    "shadow_rays_per_s",
    "shadow_jobs_dropped",
    "shadow_overflow_pixels",
    "shadow_buffers_mib",
    "bvh_mib",
    "bvh_build_ms",
    "atlas_mib",
    "atlas_shadowed",
    "atlas_dropped",
    "atlas_views",
    "atlas_views_rendered",
    "shadow_pairs",
    "pair_error_pcf5",
    "pair_error_2x2",
    "link_mib",
    "links_per_list_pixel",
    "link_scale",
    "links_dropped",
];

/// The rows as CSV (RFC 4180 quoting; floats in Rust's shortest round-trip form, `inf` for an
/// infinite PSNR, empty for `None`).
pub fn to_csv(rows: &[BenchRow]) -> String {
    let passes = pass_names(rows);
    let mut out = String::new();
    let mut header: Vec<String> = CSV_COLUMNS.iter().map(|s| s.to_string()).collect();
    for p in &passes {
        for column in ["pass_ms", "pass_ms_p10", "pass_ms_p90"] {
            header.push(csv_field(&format!("{column}:{p}")));
        }
    }
    out.push_str(&header.join(","));
    out.push('\n');
    for r in rows {
        let t = r.frame_ms;
        let mut f = vec![
            csv_field(&r.scene),
            csv_field(&r.technique),
            csv_field(&r.params),
            r.light_count.to_string(),
            r.width.to_string(),
            r.height.to_string(),
            csv_field(&r.adapter),
            opt(t.map(|t| t.median)),
            opt(t.map(|t| t.p10)),
            opt(t.map(|t| t.p90)),
            opt(r.rounds),
            opt(r.round_ms_min),
            opt(r.round_ms_max),
            opt(r.warmup_s),
            opt(r.light_update_cpu_ms),
            opt(r.sm_mhz_start),
            opt(r.sm_mhz_end),
            opt(r.sm_mhz_max),
            opt(r.rmse),
            opt(r.max_abs),
            opt(r.max_rel),
            opt(r.psnr),
            opt(r.flip_mean),
            opt(r.rel_mse),
            opt(r.seeds),
            opt(r.seed_rel_variance),
            opt(r.seed_rel_bias2),
            opt(r.listed_exact_ratio),
            opt(r.max_lights_per_tile),
            opt(r.overflow_tiles),
            csv_field(r.list_storage.as_deref().unwrap_or_default()),
            opt(r.list_mib),
            opt(r.list_indices),
            opt(r.list_indices_wanted),
            opt(r.list_mismatched),
            opt(r.nan_pixels),
            opt(r.inf_pixels),
            opt(r.lit_pixels),
            r.pass_ms.len().to_string(),
            opt(r.passes_ms_total()),
            csv_field(r.reference.as_deref().unwrap_or_default()),
            opt(r.shadow_rays),
            opt(r.shadow_rays_per_s),
            opt(r.shadow_jobs_dropped),
            opt(r.shadow_overflow_pixels),
            opt(r.shadow_buffers_mib),
            opt(r.bvh_mib),
            opt(r.bvh_build_ms),
            opt(r.atlas_mib),
            opt(r.atlas_shadowed),
            opt(r.atlas_dropped),
            opt(r.atlas_views),
            opt(r.atlas_views_rendered),
            opt(r.shadow_pairs),
            opt(r.pair_error_pcf5),
            opt(r.pair_error_2x2),
            opt(r.link_mib),
            opt(r.links_per_list_pixel),
            opt(r.link_scale),
            opt(r.links_dropped),
        ];
        for p in &passes {
            let t = pass_ms(r, p);
            f.extend([
                opt(t.map(|t| t.median)),
                opt(t.map(|t| t.p10)),
                opt(t.map(|t| t.p90)),
            ]);
        }
        out.push_str(&f.join(","));
        out.push('\n');
    }
    out
}

/// The non-finite pixels the rows list, as CSV: one line per pixel with its point.
pub fn non_finite_csv(rows: &[BenchRow]) -> String {
    let mut out = String::from("scene,technique,params,light_count,width,height,kind,x,y,r,g,b\n");
    for r in rows {
        for p in &r.non_finite_examples {
            let _ = writeln!(
                out,
                "{},{},{},{},{},{},{},{},{},{},{},{}",
                csv_field(&r.scene),
                csv_field(&r.technique),
                csv_field(&r.params),
                r.light_count,
                r.width,
                r.height,
                p.kind(),
                p.x,
                p.y,
                p.rgb[0],
                p.rgb[1],
                p.rgb[2]
            );
        }
    }
    out
}

/// Why time plots cannot be drawn for these rows, if they cannot.
pub fn untimed_reason(rows: &[BenchRow]) -> Option<String> {
    if rows.is_empty() {
        return Some("no rows".into());
    }
    if rows.iter().any(|r| r.frame_ms.is_some()) {
        return None;
    }
    let mut reasons: Vec<&str> = rows
        .iter()
        .map(|r| r.untimed.as_deref().unwrap_or("not measured"))
        .collect();
    reasons.sort_unstable();
    reasons.dedup();
    Some(reasons.join("; "))
}

fn md_cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

fn md_num(v: Option<f64>, digits: usize) -> String {
    match v {
        None => "–".to_string(),
        Some(x) if x.is_infinite() && x > 0.0 => "∞".to_string(),
        Some(x) if x != 0.0 && (x.abs() < 1e-3 || x.abs() >= 1e6) => format!("{x:.2e}"),
        Some(x) => format!("{x:.digits$}"),
    }
}

/// "1.71–1.78 (5)": the range of the round medians and the number of rounds.
fn round_spread(r: &BenchRow) -> String {
    match (r.round_ms_min, r.round_ms_max, r.rounds) {
        (Some(lo), Some(hi), Some(n)) => {
            format!("{}–{} ({n})", md_num(Some(lo), 3), md_num(Some(hi), 3))
        }
        _ => "–".into(),
    }
}

/// "1980→1980": the SM clock before the warm-up and after the last round.
fn sm_clocks(r: &BenchRow) -> String {
    match (r.sm_mhz_start, r.sm_mhz_end) {
        (Some(a), Some(b)) => format!("{a}→{b}"),
        _ => "–".into(),
    }
}

/// The rows as GitHub-flavoured Markdown: a results table, a note when nothing was timed, then
/// a per-pass table (median, p10–p90 per pass name) if any row has timed passes.
pub fn to_markdown(rows: &[BenchRow]) -> String {
    let mut out = String::new();
    out.push_str("| scene | technique | params | lights | size | adapter | median ms | p10 | p90 | rounds min–max | SM MHz | RMSE | max abs | max rel | PSNR dB | FLIP | listed/exact | max/tile | overflow | NaN px | Inf px | lit px | reference |\n");
    out.push_str(
        "|---|---|---|--:|--:|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|---|\n",
    );
    for r in rows {
        let t = r.frame_ms;
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {}x{} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            md_cell(&r.scene),
            md_cell(&r.technique),
            md_cell(&r.params),
            r.light_count,
            r.width,
            r.height,
            md_cell(&r.adapter),
            md_num(t.map(|t| t.median), 3),
            md_num(t.map(|t| t.p10), 3),
            md_num(t.map(|t| t.p90), 3),
            round_spread(r),
            sm_clocks(r),
            md_num(r.rmse, 5),
            md_num(r.max_abs, 4),
            md_num(r.max_rel, 4),
            md_num(r.psnr, 2),
            md_num(r.flip_mean, 4),
            md_num(r.listed_exact_ratio, 3),
            opt(r.max_lights_per_tile),
            opt(r.overflow_tiles),
            opt(r.nan_pixels),
            opt(r.inf_pixels),
            opt(r.lit_pixels),
            md_cell(r.reference.as_deref().unwrap_or("–")),
        );
    }
    lists_markdown(&mut out, rows);
    seeds_markdown(&mut out, rows);
    shadow_markdown(&mut out, rows);
    atlas_markdown(&mut out, rows);
    links_markdown(&mut out, rows);
    if let Some(reason) = untimed_reason(rows).filter(|_| !rows.is_empty()) {
        let _ = writeln!(
            out,
            "\nNo GPU times ({reason}): the time columns are empty and the time plots were not drawn."
        );
    }
    let passes = pass_names(rows);
    if !passes.is_empty() {
        out.push_str(
            "\nPer-pass GPU time, ms: median (p10–p90):\n\n| scene | technique | params | lights |",
        );
        for p in &passes {
            let _ = write!(out, " {} |", md_cell(p));
        }
        out.push_str("\n|---|---|---|--:|");
        for _ in &passes {
            out.push_str("--:|");
        }
        out.push('\n');
        for r in rows {
            let _ = write!(
                out,
                "| {} | {} | {} | {} |",
                md_cell(&r.scene),
                md_cell(&r.technique),
                md_cell(&r.params),
                r.light_count
            );
            for p in &passes {
                let cell = match pass_ms(r, p) {
                    Some(t) => format!(
                        "{} ({}–{})",
                        md_num(Some(t.median), 3),
                        md_num(Some(t.p10), 3),
                        md_num(Some(t.p90), 3)
                    ),
                    None => "–".into(),
                };
                let _ = write!(out, " {cell} |");
            }
            out.push('\n');
        }
    }
    out
}

/// The spread over seeds, if some row measured it: rel_mse beside its variance and
/// squared-bias parts.
fn seeds_markdown(out: &mut String, rows: &[BenchRow]) {
    if !rows.iter().any(|r| r.seeds.is_some()) {
        return;
    }
    out.push_str(
        "\nSpread over seeds (each graph's frame rendered with S other seeds; variance: the \
         mean over channels of each channel's sample variance over the seeds, bias²: the \
         squared error of their mean less its own variance, both weighted as rel MSE \
         weighs a squared error, so rel MSE ≈ bias² + variance):\n\n\
         | scene | technique | lights | size | frame ms | seeds | rel MSE | rel variance | rel bias² |\n\
         |---|---|--:|--:|--:|--:|--:|--:|--:|\n",
    );
    for r in rows.iter().filter(|r| r.seeds.is_some()) {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {}x{} | {} | {} | {} | {} | {} |",
            md_cell(&r.scene),
            md_cell(&r.technique),
            r.light_count,
            r.width,
            r.height,
            md_num(r.frame_ms.map(|t| t.median), 3),
            opt(r.seeds),
            md_num(r.rel_mse, 4),
            md_num(r.seed_rel_variance, 4),
            md_num(r.seed_rel_bias2, 4),
        );
    }
}

fn has_shadow_columns(r: &BenchRow) -> bool {
    r.shadow_rays.is_some() || r.bvh_mib.is_some()
}

/// The ray-cast shadow table, if some row traced shadow rays or read a BVH.
fn shadow_markdown(out: &mut String, rows: &[BenchRow]) {
    if !rows.iter().any(has_shadow_columns) {
        return;
    }
    out.push_str(
        "\nRay-cast shadows (rays per second over the ShadowRayCast passes' median time; \
         dropped jobs and pixels over 128 casters are lit unshadowed):\n\n\
         | scene | technique | params | lights | size | rays | rays/px | Mrays/s | dropped jobs | px > 128 casters | jobs+mask MiB | BVH MiB | BVH build ms |\n\
         |---|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n",
    );
    for r in rows.iter().filter(|r| has_shadow_columns(r)) {
        let pixels = (r.width as u64 * r.height as u64).max(1) as f64;
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {}x{} | {} | {} | {} | {} | {} | {} | {} | {} |",
            md_cell(&r.scene),
            md_cell(&r.technique),
            md_cell(&r.params),
            r.light_count,
            r.width,
            r.height,
            r.shadow_rays.map_or("–".into(), |n| n.to_string()),
            md_num(r.shadow_rays.map(|n| n as f64 / pixels), 2),
            md_num(r.shadow_rays_per_s.map(|x| x / 1e6), 1),
            r.shadow_jobs_dropped.map_or("–".into(), |n| n.to_string()),
            r.shadow_overflow_pixels
                .map_or("–".into(), |n| n.to_string()),
            md_num(r.shadow_buffers_mib, 1),
            md_num(r.bvh_mib, 1),
            md_num(r.bvh_build_ms, 1),
        );
    }
}

/// The shadow atlas table, if some row ran a ShadowAtlas pass.
fn atlas_markdown(out: &mut String, rows: &[BenchRow]) {
    if !rows.iter().any(|r| r.atlas_mib.is_some()) {
        return;
    }
    out.push_str(
        "\nShadow atlases (lights without room are lit unshadowed; pair error: the fraction of \
         (pixel, light) pairs in front of the surface whose visibility disagrees with ray-cast \
         shadows, from a ShadowCompare pass):\n\n\
         | scene | technique | lights | size | atlas MiB | shadowed | dropped | views | pairs | pair error 5×5 | pair error 2×2 | RMSE | FLIP |\n\
         |---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n",
    );
    let pct = |x: Option<f64>| match x {
        Some(x) => format!("{}%", md_num(Some(100.0 * x), 3)),
        None => "–".into(),
    };
    for r in rows.iter().filter(|r| r.atlas_mib.is_some()) {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {}x{} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            md_cell(&r.scene),
            md_cell(&r.technique),
            r.light_count,
            r.width,
            r.height,
            md_num(r.atlas_mib, 1),
            r.atlas_shadowed.map_or("–".into(), |n| n.to_string()),
            r.atlas_dropped.map_or("–".into(), |n| n.to_string()),
            r.atlas_views.map_or("–".into(), |n| n.to_string()),
            r.shadow_pairs.map_or("–".into(), |n| n.to_string()),
            pct(r.pair_error_pcf5),
            pct(r.pair_error_2x2),
            md_num(r.rmse, 6),
            md_num(r.flip_mean, 5),
        );
    }
}

/// The tile light list table, if some row's graph culls lights: storage, memory, indices
/// held and wanted, lists cut, the culling pass's time and the error it leaves.
fn lists_markdown(out: &mut String, rows: &[BenchRow]) {
    if !rows.iter().any(|r| r.list_mib.is_some()) {
        return;
    }
    out.push_str(
        "\nTile light lists (cut: lists that lost lights, past a fixed capacity or a compact \
         max_indices; wanted: the indices compact lists asked for):\n\n\
         | scene | technique | lights | size | storage | MiB | indices | wanted | cut | mismatched | culling ms | frame ms | RMSE | max rel |\n\
         |---|---|--:|--:|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n",
    );
    for r in rows.iter().filter(|r| r.list_mib.is_some()) {
        let culling = r
            .list_pass
            .as_deref()
            .and_then(|p| r.pass_ms.iter().find(|(n, _)| n == p))
            .map(|(_, t)| t.median);
        let _ = writeln!(
            out,
            "| {} | {} | {} | {}x{} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            md_cell(&r.scene),
            md_cell(&r.technique),
            r.light_count,
            r.width,
            r.height,
            md_cell(r.list_storage.as_deref().unwrap_or("–")),
            md_num(r.list_mib, 2),
            opt(r.list_indices),
            r.list_indices_wanted.map_or("–".into(), |n| n.to_string()),
            opt(r.overflow_tiles),
            opt(r.list_mismatched),
            md_num(culling, 3),
            md_num(r.frame_ms.map(|t| t.median), 3),
            md_num(r.rmse, 6),
            md_num(r.max_rel, 4),
        );
    }
}

/// The light linked list table, if some row ran a LightLinkedList pass.
fn links_markdown(out: &mut String, rows: &[BenchRow]) {
    if !rows.iter().any(|r| r.link_mib.is_some()) {
        return;
    }
    out.push_str(
        "\nLight linked lists (scale: output pixels per list-pixel side; dropped links are \
         lights missing at their pixels):\n\n\
         | scene | technique | lights | size | scale | MiB | links / list pixel | dropped | frame ms | RMSE | max abs | FLIP |\n\
         |---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n",
    );
    for r in rows.iter().filter(|r| r.link_mib.is_some()) {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {}x{} | 1/{} | {} | {} | {} | {} | {} | {} | {} |",
            md_cell(&r.scene),
            md_cell(&r.technique),
            r.light_count,
            r.width,
            r.height,
            r.link_scale.unwrap_or(1),
            md_num(r.link_mib, 2),
            md_num(r.links_per_list_pixel, 1),
            r.links_dropped.map_or("–".into(), |n| n.to_string()),
            md_num(r.frame_ms.map(|t| t.median), 3),
            md_num(r.rmse, 6),
            md_num(r.max_abs, 4),
            md_num(r.flip_mean, 5),
        );
    }
}

/// Write [`to_csv`] to `path` (creating the parent directory).
pub fn write_csv(path: impl AsRef<Path>, rows: &[BenchRow]) -> Result<(), ReportError> {
    write_file(path.as_ref(), &to_csv(rows))
}

/// Write [`to_markdown`] to `path` (creating the parent directory).
pub fn write_markdown(path: impl AsRef<Path>, rows: &[BenchRow]) -> Result<(), ReportError> {
    write_file(path.as_ref(), &to_markdown(rows))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shadow_columns_and_table() {
        let plain = BenchRow {
            scene: "chairs".into(),
            technique: "forward_plus".into(),
            width: 4,
            height: 2,
            reference: Some("brute_force".into()),
            ..Default::default()
        };
        let shadowed = BenchRow {
            technique: "raycast_shadows".into(),
            reference: Some("raycast_shadows_naive".into()),
            shadow_rays: Some(16),
            shadow_rays_per_s: Some(2.5e9),
            shadow_jobs_dropped: Some(0),
            shadow_overflow_pixels: Some(1),
            shadow_buffers_mib: Some(1.5),
            bvh_mib: Some(20.4),
            bvh_build_ms: Some(180.0),
            ..plain.clone()
        };
        let csv = to_csv(&[plain.clone(), shadowed.clone()]);
        let lines: Vec<&str> = csv.lines().collect();
        assert!(lines[0].ends_with(
            ",passes_ms_total,reference,shadow_rays,shadow_rays_per_s,shadow_jobs_dropped,shadow_overflow_pixels,shadow_buffers_mib,bvh_mib,bvh_build_ms,atlas_mib,atlas_shadowed,atlas_dropped,atlas_views,atlas_views_rendered,shadow_pairs,pair_error_pcf5,pair_error_2x2,link_mib,links_per_list_pixel,link_scale,links_dropped"
        ));
        assert!(
            lines[1].ends_with(",0,,brute_force,,,,,,,,,,,,,,,,,,,"),
            "{}",
            lines[1]
        );
        assert!(
            lines[2].ends_with(",raycast_shadows_naive,16,2500000000,0,1,1.5,20.4,180,,,,,,,,,,,,"),
            "{}",
            lines[2]
        );
        assert!(!to_markdown(std::slice::from_ref(&plain)).contains("Ray-cast shadows"));
        let md = to_markdown(&[plain, shadowed]);
        assert!(md.contains("| brute_force |\n"), "{md}");
        assert!(
            md.contains("| chairs | raycast_shadows |  | 0 | 4x2 | 16 | 2.00 | 2500.0 | 0 | 1 | 1.5 | 20.4 | 180.0 |"),
            "{md}"
        );
    }
}
