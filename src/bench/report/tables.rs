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
/// empty where a row lacks that pass. Time columns are empty, not 0, for untimed rows.
pub const CSV_COLUMNS: [&str; 23] = [
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
    "rmse",
    "max_abs",
    "max_rel",
    "psnr",
    "flip_mean",
    "listed_exact_ratio",
    "max_lights_per_tile",
    "overflow_tiles",
    "nan_pixels",
    "inf_pixels",
    "lit_pixels",
    "pass_count",
    "passes_ms_total",
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
            opt(r.rmse),
            opt(r.max_abs),
            opt(r.max_rel),
            opt(r.psnr),
            opt(r.flip_mean),
            opt(r.listed_exact_ratio),
            opt(r.max_lights_per_tile),
            opt(r.overflow_tiles),
            opt(r.nan_pixels),
            opt(r.inf_pixels),
            opt(r.lit_pixels),
            r.pass_ms.len().to_string(),
            opt(r.passes_ms_total()),
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

/// The rows as GitHub-flavoured Markdown: a results table, a note when nothing was timed, then
/// a per-pass table (median, p10–p90 per pass name) if any row has timed passes.
pub fn to_markdown(rows: &[BenchRow]) -> String {
    let mut out = String::new();
    out.push_str("| scene | technique | params | lights | size | adapter | median ms | p10 | p90 | RMSE | max abs | max rel | PSNR dB | FLIP | listed/exact | max/tile | overflow | NaN px | Inf px | lit px |\n");
    out.push_str(
        "|---|---|---|--:|--:|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n",
    );
    for r in rows {
        let t = r.frame_ms;
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {}x{} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
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
        );
    }
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

/// Write [`to_csv`] to `path` (creating the parent directory).
pub fn write_csv(path: impl AsRef<Path>, rows: &[BenchRow]) -> Result<(), ReportError> {
    write_file(path.as_ref(), &to_csv(rows))
}

/// Write [`to_markdown`] to `path` (creating the parent directory).
pub fn write_markdown(path: impl AsRef<Path>, rows: &[BenchRow]) -> Result<(), ReportError> {
    write_file(path.as_ref(), &to_markdown(rows))
}
