//! What an input file is, for `lightgraph validate`: by its extension, and for RON by the
//! name of its top-level struct (`Graph(`, `Scene(`, or a material's anonymous `(`),
//! after any byte-order mark, comments and `#![enable(...)]` attributes.

use std::path::Path;

/// What kind of input file a path holds, as `lightgraph validate` checks it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    /// A render graph (`Graph(...)` in RON).
    Graph,
    /// A scene (`Scene(...)` in RON).
    Scene,
    /// A material (an anonymous `(...)` RON struct).
    Material,
    /// A glTF model (`.gltf` or `.glb`).
    Gltf,
    /// A WGSL shader (`.wgsl`).
    Shader,
    /// A benchmark sweep (`Sweep(...)` in RON).
    Sweep,
}

/// The kind of `path`; `text` is its contents, needed for `.ron` only.
pub fn detect(path: &Path, text: impl FnOnce() -> Option<String>) -> Result<FileKind, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("gltf" | "glb") => Ok(FileKind::Gltf),
        Some("wgsl") => Ok(FileKind::Shader),
        Some("ron") => {
            let text = text().unwrap_or_default();
            match top_level_name(&text) {
                Some("Graph") => Ok(FileKind::Graph),
                Some("Scene") => Ok(FileKind::Scene),
                Some("Sweep") => Ok(FileKind::Sweep),
                Some("" | "Material" | "MaterialDesc") => Ok(FileKind::Material),
                // Empty or unreadable: let the RON parser of the likeliest kind say why.
                None => Ok(guess_from_folder(path)),
                Some(other) => Err(format!(
                    "{}: top-level struct `{other}` is none of Graph(...), Scene(...), Sweep(...) or a material's (...)",
                    path.display()
                )),
            }
        }
        _ => Err(format!(
            "{}: unknown file type (validate reads .ron graphs, scenes, sweeps and materials, .gltf/.glb models and .wgsl shaders)",
            path.display()
        )),
    }
}

fn guess_from_folder(path: &Path) -> FileKind {
    let under = |dir: &str| path.components().any(|c| c.as_os_str() == dir);
    if under("graphs") {
        FileKind::Graph
    } else if under("scenes") {
        FileKind::Scene
    } else {
        FileKind::Material
    }
}

/// The identifier before the first `(` of RON text ("" for an anonymous struct);
/// `None` if the text has no value.
pub fn top_level_name(text: &str) -> Option<&str> {
    let mut rest = crate::files::strip_bom(text);
    loop {
        rest = rest.trim_start();
        if let Some(r) = rest.strip_prefix("//") {
            rest = r.split_once('\n').map_or("", |(_, r)| r);
        } else if let Some(r) = rest.strip_prefix("/*") {
            rest = r.split_once("*/").map_or("", |(_, r)| r);
        } else if let Some(r) = rest.strip_prefix("#!") {
            rest = r.split_once(']').map_or("", |(_, r)| r);
        } else {
            break;
        }
    }
    let end = rest
        .find(|c: char| !(c.is_alphanumeric() || c == '_'))
        .unwrap_or(rest.len());
    let (name, after) = rest.split_at(end);
    after.trim_start().starts_with('(').then_some(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_struct_name_past_comments_attributes_and_a_bom() {
        assert_eq!(
            top_level_name(
                "\u{feff}// a graph\n/* x */ #![enable(implicit_some)]\n  Graph (name: \"g\")"
            ),
            Some("Graph")
        );
        assert_eq!(top_level_name("// Scene(\n(layers: [])"), Some(""));
        assert_eq!(top_level_name("   "), None);
        let p = Path::new("x.ron");
        assert_eq!(detect(p, || Some("Scene(".into())), Ok(FileKind::Scene));
        let e = detect(p, || Some("Grpah(".into())).unwrap_err();
        assert!(e.contains("top-level struct `Grpah`"), "{e}");
        assert_eq!(detect(Path::new("a.GLB"), || None), Ok(FileKind::Gltf));
        assert!(detect(Path::new("a.txt"), || None).is_err());
    }
}
