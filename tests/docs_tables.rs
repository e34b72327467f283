//! The docs' benchmark tables are generated from the benchmark results kept in
//! `bench/results/`, so they cannot drift from the run they quote.
//!
//! A table in README.md or docs/ is a marker line, the table, and an end line:
//!
//! ```text
//! <!-- table: frame_kinds_harada | columns: lights, graph, ms, range | where: graph=a|b -->
//! | lights | graph | ... |
//! <!-- end table -->
//! ```
//!
//! `table:` names a folder of `bench/results/` (its `results.csv`, else `<folder>.csv`),
//! `columns:` the keys below in order, `where:` optional filters (`key=value`, `|` between
//! alternatives), `group:` optional, a key whose every value becomes one row of medians.
//! `cargo test --test docs_tables` checks every table; with
//! `LIGHTGRAPH_BLESS=1` it rewrites them from the CSVs instead.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

const BEGIN: &str = "<!-- table:";
const END: &str = "<!-- end table -->";

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// README.md and every Markdown file under docs/.
fn doc_files() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "md") {
                out.push(p);
            }
        }
    }
    let mut out = vec![root().join("README.md")];
    walk(&root().join("docs"), &mut out);
    out.sort();
    out
}

struct Spec {
    table: String,
    columns: Vec<String>,
    filters: Vec<(String, Vec<String>)>,
    /// One row per value of this key, each numeric cell the median over its rows.
    group: Option<String>,
}

fn parse_spec(line: &str) -> Result<Spec, String> {
    let body = line
        .trim()
        .strip_prefix("<!--")
        .and_then(|s| s.strip_suffix("-->"))
        .ok_or("a marker is one line: <!-- table: ... -->")?;
    let mut spec = Spec {
        table: String::new(),
        columns: Vec::new(),
        filters: Vec::new(),
        group: None,
    };
    for part in body.split(" | ") {
        let (key, value) = part
            .split_once(':')
            .ok_or_else(|| format!("`{part}` is not `key: value`"))?;
        let value = value.trim();
        match key.trim() {
            "table" => spec.table = value.to_string(),
            "group" => spec.group = Some(value.to_string()),
            "columns" => spec.columns = value.split(',').map(|c| c.trim().to_string()).collect(),
            "where" => {
                for f in value.split(',') {
                    let (k, v) = f
                        .split_once('=')
                        .ok_or_else(|| format!("filter `{f}` is not key=value"))?;
                    let alts = v.split('|').map(|a| a.trim().to_string()).collect();
                    spec.filters.push((k.trim().to_string(), alts));
                }
            }
            other => return Err(format!("unknown marker field `{other}`")),
        }
    }
    if spec.table.is_empty() || spec.columns.is_empty() {
        return Err("a marker needs `table:` and `columns:`".into());
    }
    Ok(spec)
}

struct Csv {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Csv {
    fn load(path: &Path) -> Result<Csv, String> {
        let mut reader =
            csv::Reader::from_path(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let header = reader
            .headers()
            .map_err(|e| format!("{}: {e}", path.display()))?
            .iter()
            .map(str::to_string)
            .collect();
        let mut rows = Vec::new();
        for record in reader.records() {
            let record = record.map_err(|e| format!("{}: {e}", path.display()))?;
            rows.push(record.iter().map(str::to_string).collect());
        }
        Ok(Csv { header, rows })
    }
    fn raw<'a>(&self, row: &'a [String], column: &str) -> Option<&'a str> {
        let i = self.header.iter().position(|h| h == column)?;
        row.get(i).map(String::as_str)
    }
}

/// The CSV of a table: `bench/results/<table>/results.csv`, else `<table>/<table>.csv`.
fn csv_path(table: &str) -> PathBuf {
    let dir = root().join("bench/results").join(table);
    let results = dir.join("results.csv");
    if results.exists() {
        results
    } else {
        dir.join(format!("{table}.csv"))
    }
}

fn number(s: &str) -> Option<f64> {
    s.trim().parse::<f64>().ok()
}

/// Milliseconds to the microsecond.
fn ms(s: &str) -> String {
    number(s).map_or("–".into(), |v| format!("{v:.3}"))
}

/// An error to two significant digits (0 stays 0).
fn error(s: &str) -> String {
    match number(s) {
        None => "–".into(),
        Some(0.0) => "0".into(),
        Some(v) if v.is_infinite() => "∞".into(),
        Some(v) => format!("{v:.1e}"),
    }
}

/// Any other number: integers as they are, others to three decimals without trailing
/// zeros (tiny ones in scientific notation).
fn plain(s: &str) -> String {
    if s.is_empty() {
        return "–".into();
    }
    if s.parse::<i64>().is_ok() {
        return s.to_string();
    }
    match number(s) {
        Some(v) if v.is_infinite() => "∞".into(),
        Some(0.0) => "0".into(),
        Some(v) if v.abs() < 1e-3 => format!("{v:.1e}"),
        Some(v) => {
            let text = format!("{v:.3}");
            text.trim_end_matches('0').trim_end_matches('.').to_string()
        }
        None => s.to_string(),
    }
}

/// A cell and whether it is numeric (right-aligned).
fn cell(csv: &Csv, row: &[String], key: &str) -> Result<(String, bool), String> {
    let get = |col: &str| {
        csv.raw(row, col)
            .ok_or_else(|| format!("the CSV has no column `{col}` (for `{key}`)"))
    };
    Ok(match key {
        "scene" => (get("scene")?.to_string(), false),
        // Benchmark-only variants are named by path (`../benches/graphs/x`): the stem.
        "graph" => (
            get("technique")?
                .rsplit('/')
                .next()
                .unwrap_or("")
                .to_string(),
            false,
        ),
        "reference" => (get("reference")?.to_string(), false),
        "lights" => (plain(get("light_count")?), true),
        "size" => (format!("{}×{}", get("width")?, get("height")?), true),
        "ms" => (ms(get("frame_ms_median")?), true),
        "p10" => (ms(get("frame_ms_p10")?), true),
        "p90" => (ms(get("frame_ms_p90")?), true),
        "range" => {
            let (lo, hi) = (get("round_ms_min")?, get("round_ms_max")?);
            if lo.is_empty() {
                ("–".into(), true)
            } else {
                (format!("{}–{}", ms(lo), ms(hi)), true)
            }
        }
        "rmse" => (error(get("rmse")?), true),
        "max_abs" => (error(get("max_abs")?), true),
        "max_rel" => (error(get("max_rel")?), true),
        "flip" => (error(get("flip_mean")?), true),
        "psnr" => (
            number(get("psnr")?).map_or("–".into(), |v| {
                if v.is_infinite() {
                    "∞".into()
                } else {
                    format!("{v:.1}")
                }
            }),
            true,
        ),
        "listed_exact" => (
            number(get("listed_exact_ratio")?).map_or("–".into(), |v| format!("{v:.2}")),
            true,
        ),
        "max_per_tile" => (plain(get("max_lights_per_tile")?), true),
        "overflow" => (plain(get("overflow_tiles")?), true),
        k => match k.strip_prefix("pass:") {
            Some(pass) => (ms(get(&format!("pass_ms:{pass}"))?), true),
            None => {
                let v = get(k)?;
                (plain(v), number(v).is_some() || v.is_empty())
            }
        },
    })
}

fn label(key: &str) -> String {
    match key {
        "ms" => "ms (median)".into(),
        "range" => "round medians".into(),
        "rmse" => "RMSE".into(),
        "max_abs" => "max abs".into(),
        "max_rel" => "max rel".into(),
        "psnr" => "PSNR dB".into(),
        "flip" => "FLIP".into(),
        "listed_exact" => "listed/exact".into(),
        "max_per_tile" => "max/tile".into(),
        "overflow" => "overflow tiles".into(),
        k => match k.strip_prefix("pass:") {
            Some(pass) => format!("{pass} ms"),
            None => k.replace('_', " "),
        },
    }
}

/// The median of each numeric column over `rows` (the first row's text elsewhere).
fn median_row(rows: &[&Vec<String>]) -> Vec<String> {
    (0..rows[0].len())
        .map(|i| {
            let mut values: Vec<f64> = rows.iter().filter_map(|r| number(&r[i])).collect();
            if values.len() < rows.len() {
                return rows[0][i].clone();
            }
            values.sort_by(f64::total_cmp);
            let n = values.len();
            let median = if n % 2 == 1 {
                values[n / 2]
            } else {
                (values[n / 2 - 1] + values[n / 2]) / 2.0
            };
            median.to_string()
        })
        .collect()
}

/// The table a marker asks for, as Markdown lines.
fn render(spec: &Spec) -> Result<Vec<String>, String> {
    let path = csv_path(&spec.table);
    let csv = Csv::load(&path)?;
    let mut kept = Vec::new();
    'rows: for row in &csv.rows {
        for (key, alts) in &spec.filters {
            let (value, _) = cell(&csv, row, key)?;
            if !alts.contains(&value) {
                continue 'rows;
            }
        }
        kept.push(row);
    }
    let merged: Vec<Vec<String>>;
    let table_rows: Vec<&Vec<String>> = match &spec.group {
        None => kept,
        Some(key) => {
            let mut groups: Vec<(String, Vec<&Vec<String>>)> = Vec::new();
            for row in kept {
                let (value, _) = cell(&csv, row, key)?;
                match groups.iter_mut().find(|(v, _)| *v == value) {
                    Some((_, members)) => members.push(row),
                    None => groups.push((value, vec![row])),
                }
            }
            merged = groups
                .iter()
                .map(|(_, members)| median_row(members))
                .collect();
            merged.iter().collect()
        }
    };
    let mut rows = Vec::new();
    for row in table_rows {
        let mut cells = Vec::new();
        for key in &spec.columns {
            cells.push(cell(&csv, row, key)?);
        }
        rows.push(cells);
    }
    if rows.is_empty() {
        return Err(format!("no row of {} passes the filters", path.display()));
    }
    let mut out = vec![
        format!(
            "| {} |",
            spec.columns
                .iter()
                .map(|k| label(k))
                .collect::<Vec<_>>()
                .join(" | ")
        ),
        format!(
            "|{}|",
            rows[0]
                .iter()
                .map(|(_, numeric)| if *numeric { "--:" } else { "---" })
                .collect::<Vec<_>>()
                .join("|")
        ),
    ];
    for cells in rows {
        let text: Vec<String> = cells
            .into_iter()
            .map(|(c, _)| c.replace('|', "\\|"))
            .collect();
        out.push(format!("| {} |", text.join(" | ")));
    }
    Ok(out)
}

/// Every table of one file regenerated: the new text and the problems found.
fn regenerate(path: &Path, text: &str, tables: &mut BTreeSet<String>) -> (String, Vec<String>) {
    let name = path
        .strip_prefix(root())
        .unwrap_or(path)
        .display()
        .to_string();
    let lines: Vec<&str> = text.lines().collect();
    let mut out: Vec<String> = Vec::new();
    let mut problems = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        out.push(line.to_string());
        i += 1;
        if !line.trim_start().starts_with(BEGIN) {
            continue;
        }
        let marker_line = i;
        let Some(end) = lines[i..]
            .iter()
            .position(|l| l.trim() == END)
            .map(|p| p + i)
        else {
            problems.push(format!(
                "{name}:{marker_line}: table marker without `{END}`"
            ));
            continue;
        };
        match parse_spec(line).and_then(|spec| {
            tables.insert(spec.table.clone());
            render(&spec)
        }) {
            Ok(table) => out.extend(table),
            Err(e) => {
                problems.push(format!("{name}:{marker_line}: {e}"));
                out.extend(lines[i..end].iter().map(|l| l.to_string()));
            }
        }
        i = end;
    }
    let mut new = out.join("\n");
    if text.ends_with('\n') {
        new.push('\n');
    }
    (new, problems)
}

#[test]
fn docs_tables_match_the_results_they_quote() {
    let bless = std::env::var_os("LIGHTGRAPH_BLESS").is_some();
    let mut problems = Vec::new();
    let mut stale = Vec::new();
    let mut tables = BTreeSet::new();
    for path in doc_files() {
        let text = std::fs::read_to_string(&path).unwrap();
        let (new, mut p) = regenerate(&path, &text, &mut tables);
        problems.append(&mut p);
        if new != text {
            if bless {
                std::fs::write(&path, new).unwrap();
            } else {
                stale.push(path.strip_prefix(root()).unwrap().display().to_string());
            }
        }
    }
    assert!(
        problems.is_empty(),
        "bad table markers:\n{}",
        problems.join("\n")
    );
    assert!(
        stale.is_empty(),
        "these docs' tables differ from bench/results (rerun with LIGHTGRAPH_BLESS=1 to \
         regenerate them): {stale:?}"
    );
    assert!(
        !tables.is_empty(),
        "no generated table found in README.md or docs/"
    );
}

/// bench/results keeps only what the docs quote: every folder there is a table's source.
#[test]
fn every_kept_result_is_quoted() {
    let mut tables = BTreeSet::new();
    for path in doc_files() {
        let text = std::fs::read_to_string(&path).unwrap();
        regenerate(&path, &text, &mut tables);
    }
    let mut unquoted = Vec::new();
    for e in std::fs::read_dir(root().join("bench/results"))
        .unwrap()
        .flatten()
    {
        let name = e.file_name().to_string_lossy().to_string();
        if e.path().is_dir() && !tables.contains(&name) {
            unquoted.push(name);
        }
    }
    assert!(
        unquoted.is_empty(),
        "bench/results folders no doc table quotes: {unquoted:?}"
    );
}

#[test]
fn a_table_is_generated_from_its_csv() {
    let csv = Csv {
        header: [
            "technique",
            "light_count",
            "frame_ms_median",
            "round_ms_min",
            "round_ms_max",
            "max_rel",
            "pass_ms:light_culling",
        ]
        .map(String::from)
        .to_vec(),
        rows: vec![[
            "forward_plus",
            "1024",
            "3.1097919",
            "3.10696",
            "3.11104",
            "0.0213",
            "0.139216",
        ]
        .map(String::from)
        .to_vec()],
    };
    let row = &csv.rows[0];
    let cells: Vec<String> = [
        "graph",
        "lights",
        "ms",
        "range",
        "max_rel",
        "pass:light_culling",
    ]
    .iter()
    .map(|k| cell(&csv, row, k).unwrap().0)
    .collect();
    assert_eq!(
        cells,
        [
            "forward_plus",
            "1024",
            "3.110",
            "3.107–3.111",
            "2.1e-2",
            "0.139"
        ]
    );
    assert_eq!(
        [
            plain("0.0980"),
            plain("151.72"),
            plain("2.0"),
            plain("0.00004")
        ],
        ["0.098", "151.72", "2", "4.0e-5"]
    );
    assert!(
        cell(&csv, row, "flip").is_err(),
        "a missing column is an error"
    );
    let spec = parse_spec("<!-- table: x | columns: graph, ms | where: graph=a|b -->").unwrap();
    assert_eq!(
        spec.filters,
        vec![("graph".to_string(), vec!["a".to_string(), "b".to_string()])]
    );
}
