//! Where an element of a scene file is written: `lights[3]`, `material_overrides "tri"` or
//! `camera` to the line and column of its text, so that errors found after parsing (a
//! light's range, a model's budget) point at the line like syntax errors do. RON's serde
//! parser keeps no spans for values, so this walks the text's tokens instead.

/// 1-based line and column (in characters).
pub type Location = (usize, usize);

/// What an error's element names in the file's top-level struct.
#[derive(Debug, PartialEq)]
enum Path<'a> {
    Field(&'a str),
    Index(&'a str, usize),
    Key(&'a str, String),
}

/// Reads the leading `field`, `field[N]` or `field "key"` of an element description
/// (`lights[0] ("fill")`, `material_overrides "tri_mat"`); None for descriptions that
/// do not start with a field name (`light 3`, `mesh 0 ("tri") vertex 1` name the built
/// scene, not the file).
fn element_path(element: &str) -> Option<Path<'_>> {
    let end = element
        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(element.len());
    let (field, rest) = element.split_at(end);
    if field.is_empty() {
        return None;
    }
    if let Some(rest) = rest.strip_prefix('[') {
        let n = rest.split(']').next()?.parse().ok()?;
        return Some(Path::Index(field, n));
    }
    if let Some(rest) = rest.strip_prefix(" \"") {
        let key = rest.split('"').next()?;
        return Some(Path::Key(field, key.to_string()));
    }
    if rest.is_empty() || rest.starts_with(':') || rest.starts_with(" (") {
        return Some(Path::Field(field));
    }
    None
}

/// RON tokens; JSON's too (a JSON number may come as several tokens, which the walkers
/// below never count: they step by commas and brackets).
#[derive(Debug, PartialEq)]
pub(super) enum Token<'a> {
    Open(char),
    Close,
    Comma,
    Colon,
    Ident(&'a str),
    Str(String),
    Other,
}

/// The tokens of RON text with where each starts; comments and whitespace dropped.
pub(super) fn tokens(text: &str) -> Vec<(Token<'_>, Location)> {
    let chars: Vec<(usize, char)> = text.char_indices().collect();
    let mut out = Vec::new();
    let (mut i, mut line, mut col) = (0, 1, 1);
    // Advances over `n` characters, counting lines.
    let step = |i: &mut usize, line: &mut usize, col: &mut usize, n: usize| {
        for _ in 0..n {
            if *i >= chars.len() {
                return;
            }
            if chars[*i].1 == '\n' {
                *line += 1;
                *col = 1;
            } else {
                *col += 1;
            }
            *i += 1;
        }
    };
    let at = |i: usize| chars.get(i).map(|c| c.1);
    while i < chars.len() {
        let c = chars[i].1;
        let start = (line, col);
        match c {
            c if c.is_whitespace() => step(&mut i, &mut line, &mut col, 1),
            '/' if at(i + 1) == Some('/') => {
                while i < chars.len() && chars[i].1 != '\n' {
                    step(&mut i, &mut line, &mut col, 1);
                }
            }
            '/' if at(i + 1) == Some('*') => {
                // RON block comments nest.
                let mut depth = 0;
                while i < chars.len() {
                    if at(i) == Some('/') && at(i + 1) == Some('*') {
                        depth += 1;
                        step(&mut i, &mut line, &mut col, 2);
                    } else if at(i) == Some('*') && at(i + 1) == Some('/') {
                        depth -= 1;
                        step(&mut i, &mut line, &mut col, 2);
                        if depth == 0 {
                            break;
                        }
                    } else {
                        step(&mut i, &mut line, &mut col, 1);
                    }
                }
            }
            '"' => {
                step(&mut i, &mut line, &mut col, 1);
                let mut s = String::new();
                while let Some(c) = at(i) {
                    step(&mut i, &mut line, &mut col, 1);
                    match c {
                        '"' => break,
                        '\\' => {
                            if let Some(e) = at(i) {
                                s.push(e);
                                step(&mut i, &mut line, &mut col, 1);
                            }
                        }
                        c => s.push(c),
                    }
                }
                out.push((Token::Str(s), start));
            }
            'r' if matches!(at(i + 1), Some('"') | Some('#')) => {
                // Raw string r#"..."#: ends at a quote followed by as many hashes.
                let mut j = i + 1;
                while at(j) == Some('#') {
                    j += 1;
                }
                let hashes = j - i - 1;
                step(&mut i, &mut line, &mut col, hashes + 2);
                let mut s = String::new();
                while let Some(c) = at(i) {
                    if c == '"' && (1..=hashes).all(|k| at(i + k) == Some('#')) {
                        step(&mut i, &mut line, &mut col, hashes + 1);
                        break;
                    }
                    s.push(c);
                    step(&mut i, &mut line, &mut col, 1);
                }
                out.push((Token::Str(s), start));
            }
            '\'' => {
                // A char literal: 'a' or '\n'.
                let n = if at(i + 1) == Some('\\') { 4 } else { 3 };
                step(&mut i, &mut line, &mut col, n);
                out.push((Token::Other, start));
            }
            '(' | '[' | '{' => {
                step(&mut i, &mut line, &mut col, 1);
                out.push((Token::Open(c), start));
            }
            ')' | ']' | '}' => {
                step(&mut i, &mut line, &mut col, 1);
                out.push((Token::Close, start));
            }
            ',' => {
                step(&mut i, &mut line, &mut col, 1);
                out.push((Token::Comma, start));
            }
            ':' => {
                step(&mut i, &mut line, &mut col, 1);
                out.push((Token::Colon, start));
            }
            c if c.is_alphanumeric() || c == '_' => {
                let from = chars[i].0;
                while at(i).is_some_and(|c| c.is_alphanumeric() || c == '_') {
                    step(&mut i, &mut line, &mut col, 1);
                }
                let to = chars.get(i).map_or(text.len(), |c| c.0);
                out.push((Token::Ident(&text[from..to]), start));
            }
            _ => {
                step(&mut i, &mut line, &mut col, 1);
                out.push((Token::Other, start));
            }
        }
    }
    out
}

/// Where `element` (an error's element description) is written in the scene file `text`:
/// the start of the list entry, map key or field it names; None when it names no field of
/// the top-level struct or the text does not have it.
pub(crate) fn locate(text: &str, element: &str) -> Option<Location> {
    let path = element_path(element)?;
    let field = match &path {
        Path::Field(f) | Path::Index(f, _) | Path::Key(f, _) => *f,
    };
    let toks = tokens(text);
    let mut depth = 0usize;
    let mut k = 0;
    while k < toks.len() {
        let (tok, _) = &toks[k];
        match tok {
            Token::Open(_) => depth += 1,
            Token::Close => depth = depth.saturating_sub(1),
            Token::Ident(name)
                if depth == 1
                    && *name == field
                    && matches!(toks.get(k + 1), Some((Token::Colon, _))) =>
            {
                let at = match &path {
                    Path::Field(_) => Some(k),
                    Path::Index(_, n) => entry(&toks, k + 2, *n),
                    Path::Key(_, key) => key_of(&toks, k + 2, key),
                };
                return at.map(|j| toks[j].1);
            }
            _ => {}
        }
        k += 1;
    }
    None
}

/// The token where entry `n` of the list opening at `toks[open]` starts.
pub(super) fn entry(toks: &[(Token<'_>, Location)], open: usize, n: usize) -> Option<usize> {
    if !matches!(toks.get(open), Some((Token::Open('['), _))) {
        return None;
    }
    let (mut depth, mut index, mut at_start) = (0usize, 0usize, true);
    for (j, (tok, _)) in toks.iter().enumerate().skip(open + 1) {
        if depth == 0 {
            if matches!(tok, Token::Close) {
                return None;
            }
            if matches!(tok, Token::Comma) {
                index += 1;
                at_start = true;
                continue;
            }
            if at_start && index == n {
                return Some(j);
            }
            at_start = false;
        }
        match tok {
            Token::Open(_) => depth += 1,
            Token::Close => depth -= 1,
            _ => {}
        }
    }
    None
}

/// The token of the quoted key `key` in the map (RON) or object (JSON) opening at
/// `toks[open]`; its value starts two tokens later.
pub(super) fn key_of(toks: &[(Token<'_>, Location)], open: usize, key: &str) -> Option<usize> {
    if !matches!(toks.get(open), Some((Token::Open('{'), _))) {
        return None;
    }
    let mut depth = 0usize;
    for (j, (tok, _)) in toks.iter().enumerate().skip(open + 1) {
        match tok {
            Token::Open(_) => depth += 1,
            Token::Close if depth == 0 => return None,
            Token::Close => depth -= 1,
            Token::Str(s)
                if depth == 0 && s == key && matches!(toks.get(j + 1), Some((Token::Colon, _))) =>
            {
                return Some(j)
            }
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::locate;

    const SCENE: &str = r##"// a scene /* with ( a comment */
Scene(
    models: [(path: "a.gltf"), /* ] */ (path: "b(.gltf")],
    lights: [
        (position: (0, 1, 2), range: 3, name: "key \" ]"),
        // (a comment, with a comma)
        (position: (4, 5, 6), range: r#"x"]"#),
    ],
    material_overrides: { "tri": "m.ron", "box": "n.ron" },
    camera: LookAt(eye: (0, 0, 3)),
)"##;

    #[test]
    fn finds_entries_keys_and_fields() {
        assert_eq!(locate(SCENE, "models[0] (\"a.gltf\")"), Some((3, 14)));
        assert_eq!(locate(SCENE, "models[1] (\"b.gltf\")"), Some((3, 40)));
        assert_eq!(locate(SCENE, "lights[0] (\"key\")"), Some((5, 9)));
        assert_eq!(locate(SCENE, "lights[1]"), Some((7, 9)));
        assert_eq!(locate(SCENE, "material_overrides \"box\""), Some((9, 43)));
        assert_eq!(locate(SCENE, "camera"), Some((10, 5)));
    }

    #[test]
    fn names_of_the_built_scene_are_not_located() {
        assert_eq!(locate(SCENE, "lights[2]"), None);
        assert_eq!(locate(SCENE, "light 1"), None);
        assert_eq!(locate(SCENE, "mesh 0 (\"tri\") vertex 1"), None);
        assert_eq!(locate(SCENE, "material_overrides \"cone\""), None);
        // `range` is a field of a light, not of the scene.
        assert_eq!(locate(SCENE, "range"), None);
        assert_eq!(locate("", "camera"), None);
        assert_eq!(locate("Scene(lights: [", "lights[0]"), None);
    }
}
