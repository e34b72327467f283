//! `vpl-error --variant`: several VPL frames measured against one path-traced reference
//! per scene (the reference is the slow part), each a set of graphs and optionally other
//! `VplSpawn` parameters, so one table and one time-vs-error plot hold them all.

use anyhow::{bail, Context, Result};
use lightgraph::graph::CheckedGraph;
use lightgraph::shader::{assets, ShaderLibrary};
use std::path::{Path, PathBuf};

/// One VPL frame to measure: its graphs and what replaces their `VplSpawn` parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Variant {
    /// Its name in the table, the CSV and the plot's legend.
    pub label: String,
    /// The graph timed.
    pub graph: PathBuf,
    /// The all-lights graph whose image is measured.
    pub error_graph: PathBuf,
    /// The frame without VPLs, subtracted.
    pub direct: PathBuf,
    /// `VplSpawn` parameters (`merge: 2, falloff: Disc`) added to every `VplSpawn(...)`
    /// of the variant's graphs.
    pub spawn: Option<String>,
}

/// Parses `label=L;graph=G;error_graph=E;direct=D;spawn=P`: every key but `label` is
/// optional, and a missing graph is `base`'s.
pub fn parse(text: &str, base: &Variant) -> Result<Variant> {
    let mut v = Variant {
        label: String::new(),
        spawn: None,
        ..base.clone()
    };
    for part in text.split(';').map(str::trim).filter(|p| !p.is_empty()) {
        let Some((key, value)) = part.split_once('=') else {
            bail!("--variant '{text}': '{part}' is not key=value");
        };
        let value = value.trim();
        match key.trim() {
            "label" => v.label = value.to_string(),
            "graph" => v.graph = PathBuf::from(value),
            "error_graph" => v.error_graph = PathBuf::from(value),
            "direct" => v.direct = PathBuf::from(value),
            "spawn" => v.spawn = Some(value.to_string()),
            other => bail!(
                "--variant '{text}': unknown key '{other}' (label, graph, error_graph, direct, spawn)"
            ),
        }
    }
    if v.label.is_empty() {
        bail!("--variant '{text}' needs a label=");
    }
    if v.label.contains(',') {
        bail!("--variant '{text}': the label goes into a CSV column: no commas");
    }
    Ok(v)
}

/// `text` with `spawn` added inside every `VplSpawn(...)`.
pub fn with_spawn(text: &str, spawn: &str) -> Result<String> {
    const KIND: &str = "VplSpawn(";
    let mut out = String::with_capacity(text.len() + spawn.len());
    let mut rest = text;
    let mut found = false;
    while let Some(at) = rest.find(KIND) {
        found = true;
        let open = at + KIND.len();
        let close = rest[open..]
            .find(')')
            .map(|c| open + c)
            .context("VplSpawn( without its closing parenthesis")?;
        let inner = rest[open..close].trim().trim_end_matches(',');
        out.push_str(&rest[..open]);
        if inner.is_empty() {
            out.push_str(spawn);
        } else {
            out.push_str(&format!("{inner}, {spawn}"));
        }
        rest = &rest[close..];
    }
    if !found {
        bail!("no VplSpawn pass to give '{spawn}'");
    }
    out.push_str(rest);
    Ok(out)
}

/// The graph at `path` (a built-in name or a file), checked, with the variant's spawn
/// parameters.
pub fn check(path: &Path, spawn: Option<&str>) -> Result<CheckedGraph> {
    let lib = ShaderLibrary::builtin();
    let Some(spawn) = spawn else {
        return Ok(assets::check_graph(path, &lib)?);
    };
    let text = assets::read_path(path).with_context(|| format!("reading {}", path.display()))?;
    let text = with_spawn(&text, spawn).with_context(|| format!("{}", path.display()))?;
    Ok(lightgraph::graph::check_text(path, &text, &lib)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn base() -> Variant {
        Variant {
            label: "vpl".into(),
            graph: "g.ron".into(),
            error_graph: "e.ron".into(),
            direct: "d.ron".into(),
            spawn: None,
        }
    }

    #[test]
    fn a_variant_takes_the_base_graphs_it_does_not_name() {
        let v = parse(
            "label=disc; spawn=falloff: Disc, merge: 2; direct=x.ron",
            &base(),
        )
        .unwrap();
        assert_eq!(v.label, "disc");
        assert_eq!(v.graph, PathBuf::from("g.ron"));
        assert_eq!(v.direct, PathBuf::from("x.ron"));
        assert_eq!(v.spawn.as_deref(), Some("falloff: Disc, merge: 2"));
        let e = parse("spawn=merge: 2", &base()).unwrap_err().to_string();
        assert!(e.contains("needs a label"), "{e}");
        let e = parse("label=a;colour=red", &base())
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown key 'colour'"), "{e}");
    }

    #[test]
    fn spawn_parameters_join_every_vpl_spawn() {
        let t = "kind: VplSpawn(max_vpls: 16384), x, kind: VplSpawn()";
        assert_eq!(
            with_spawn(t, "merge: 2").unwrap(),
            "kind: VplSpawn(max_vpls: 16384, merge: 2), x, kind: VplSpawn(merge: 2)"
        );
        assert!(with_spawn("Pass()", "merge: 2").is_err());
    }
}
