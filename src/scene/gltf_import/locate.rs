//! Where an element of a .gltf file is written: an error's element (`mesh 0 ("box")
//! primitive 1 accessor 3`, `node 5`) or a glTF validation path
//! (`meshes[0].primitives[1].indices`) to the line and column of its JSON, so semantic
//! errors point at the text like JSON syntax errors do. serde_json's parse keeps no spans,
//! so this walks the text's tokens with the scene file locator's tokenizer and walkers
//! (JSON's syntax is within RON's). A .glb's JSON chunk is not located (its line and column
//! would not be the file's).

use crate::scene::locate::{entry, key_of, tokens, Location, Token};

/// One step into the JSON document.
#[derive(Clone, Debug, PartialEq)]
enum Step {
    Key(String),
    Index(usize),
}

/// glTF element words as the importer writes them, to their top-level arrays.
fn array_of(word: &str) -> Option<&'static [&'static str]> {
    Some(match word {
        "node" => &["nodes"],
        "mesh" => &["meshes"],
        "accessor" => &["accessors"],
        "buffer" => &["buffers"],
        "bufferView" => &["bufferViews"],
        "image" => &["images"],
        "material" => &["materials"],
        "texture" => &["textures"],
        "sampler" => &["samplers"],
        "camera" => &["cameras"],
        "skin" => &["skins"],
        "scene" => &["scenes"],
        "light" => &["extensions", "KHR_lights_punctual", "lights"],
        _ => return None,
    })
}

/// Candidate paths for an element description, most specific first: the last element
/// it names on its own (`accessor 3` → `accessors[3]`), then a primitive within its mesh.
fn element_paths(element: &str) -> Vec<Vec<Step>> {
    // `light 0 ("lamp") on node 1`: the light is what is wrong, the node where it hangs.
    let element = element.split(" on ").next().unwrap_or(element);
    // Words followed by an index; quoted names in parentheses skipped.
    let mut pairs: Vec<(&str, usize)> = Vec::new();
    let mut words = element.split_whitespace().peekable();
    while let Some(w) = words.next() {
        if let Some(n) = words.peek().and_then(|n| n.parse::<usize>().ok()) {
            pairs.push((w, n));
            words.next();
        }
    }
    let mut paths = Vec::new();
    for &(word, n) in pairs.iter().rev() {
        if let Some(keys) = array_of(word) {
            let mut p: Vec<Step> = keys.iter().map(|k| Step::Key(k.to_string())).collect();
            p.push(Step::Index(n));
            paths.push(p);
            break;
        }
    }
    if let [("mesh", m), ("primitive", p), ..] = pairs.as_slice() {
        paths.push(vec![
            Step::Key("meshes".into()),
            Step::Index(*m),
            Step::Key("primitives".into()),
            Step::Index(*p),
        ]);
    }
    if let Some((field, rest)) = element.split_once('[') {
        // `extensionsRequired[0]`
        if let Ok(n) = rest.trim_end_matches(']').parse() {
            paths.push(vec![Step::Key(field.into()), Step::Index(n)]);
        }
    }
    paths
}

/// A validation path as the gltf crate prints it: `meshes[0].attributes["POSITION"]`.
fn json_path(path: &str) -> Vec<Step> {
    let mut steps = Vec::new();
    let mut rest = path;
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix("[\"") {
            let Some((key, after)) = r.split_once("\"]") else {
                break;
            };
            steps.push(Step::Key(key.into()));
            rest = after;
        } else if let Some(r) = rest.strip_prefix('[') {
            let Some((n, after)) = r.split_once(']') else {
                break;
            };
            let Ok(n) = n.parse() else { break };
            steps.push(Step::Index(n));
            rest = after;
        } else {
            let r = rest.strip_prefix('.').unwrap_or(rest);
            let end = r.find(['.', '[']).unwrap_or(r.len());
            if end == 0 {
                break;
            }
            steps.push(Step::Key(r[..end].into()));
            rest = &r[end..];
        }
    }
    steps
}

/// Follows `path` from the value starting at token `i`; the location of the value it
/// ends at (for an object member, its key).
fn find(toks: &[(Token<'_>, Location)], i: usize, path: &[Step]) -> Option<Location> {
    let Some(step) = path.first() else {
        return toks.get(i).map(|t| t.1);
    };
    match step {
        Step::Key(key) => {
            let k = key_of(toks, i, key)?;
            if path.len() == 1 {
                Some(toks[k].1)
            } else {
                find(toks, k + 2, &path[1..])
            }
        }
        Step::Index(n) => find(toks, entry(toks, i, *n)?, &path[1..]),
    }
}

/// Where the .gltf JSON `text` writes what an error names: its element, or the
/// validation path at the start of its message. None when the text has no such element.
pub(crate) fn locate(text: &str, element: &str, message: &str) -> Option<Location> {
    let toks = tokens(text);
    // The document is the first object (after a byte-order mark, if any).
    let root = toks.iter().position(|t| t.0 == Token::Open('{'))?;
    let mut paths = Vec::new();
    if element == "glTF validation" {
        let path = message.split(':').next().unwrap_or("");
        let mut steps = json_path(path);
        // The longest prefix present: `attributes["NORMAL"]` may be what is missing.
        while !steps.is_empty() {
            paths.push(steps.clone());
            steps.pop();
        }
    }
    // A message that starts with a field of the element (`alphaCutoff 2 must ...`)
    // points at that field, else at the element.
    let field = message.split_whitespace().next().filter(|w| {
        w.chars().all(|c| c.is_ascii_alphanumeric())
            && w.starts_with(|c: char| c.is_ascii_lowercase())
    });
    for p in element_paths(element) {
        if let Some(f) = field {
            let mut with_field = p.clone();
            with_field.push(Step::Key(f.to_string()));
            paths.push(with_field);
        }
        paths.push(p);
    }
    paths.iter().find_map(|p| find(&toks, root, p))
}

#[cfg(test)]
mod tests {
    use super::locate;

    const GLTF: &str = r#"{
  "asset": {"version": "2.0"},
  "extensionsRequired": ["KHR_a", "KHR_b"],
  "meshes": [
    {"name": "box", "primitives": [
      {"attributes": {"POSITION": 0}},
      {"attributes": {"POSITION": 1, "NORMAL": 2}, "indices": 3}
    ]}
  ],
  "accessors": [{"count": 3}, {"count": "x\"]"}, {}, {"count": 9}],
  "nodes": [{"mesh": 0}, {"children": [0]}]
}"#;

    #[test]
    fn finds_elements_and_validation_paths() {
        assert_eq!(locate(GLTF, "node 1", ""), Some((11, 26)));
        assert_eq!(
            locate(GLTF, "mesh 0 (\"box\") primitive 1 accessor 3", ""),
            Some((10, 54))
        );
        // An accessor that does not exist: the primitive that names it.
        assert_eq!(
            locate(GLTF, "mesh 0 (\"box\") primitive 1 accessor 7", ""),
            Some((7, 7))
        );
        assert_eq!(locate(GLTF, "extensionsRequired[1]", ""), Some((3, 35)));
        assert_eq!(
            locate(
                GLTF,
                "glTF validation",
                "meshes[0].primitives[1].indices: invalid index"
            ),
            Some((7, 52))
        );
        // The longest prefix present.
        assert_eq!(
            locate(
                GLTF,
                "glTF validation",
                "meshes[0].primitives[0].attributes[\"NORMAL\"]: missing"
            ),
            Some((6, 8))
        );
    }

    #[test]
    fn what_is_not_there_is_not_located() {
        assert_eq!(locate(GLTF, "node 2", ""), None);
        assert_eq!(locate(GLTF, "document", "x"), None);
        assert_eq!(locate("{", "node 0", ""), None);
        assert_eq!(locate("not json", "node 0", ""), None);
    }
}
