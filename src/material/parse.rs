//! Loading a material file: RON syntax and type errors with ron's position, then semantic
//! checks (empty layer or lobe lists, undeclared textures, missing texture files) located
//! by finding the offending token in the source text.

use super::error::{Location, MaterialError};
use super::model::{MaterialDesc, Source};
use super::{TextureSlot, TextureSource};
use crate::scene::AlphaMode;
use std::path::Path;

fn loc(path: &Path, line: usize, col: usize) -> Location {
    Location {
        file: path.to_path_buf(),
        line,
        col,
    }
}

/// 1-based line and column (in characters) of a byte offset.
pub(crate) fn line_col(src: &str, offset: usize) -> (usize, usize) {
    let before = &src[..offset.min(src.len())];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[start..].chars().count() + 1)
}

/// Byte offsets of `needle` outside `//` comments.
fn occurrences(src: &str, needle: &str) -> Vec<usize> {
    let mut out = Vec::new();
    let mut base = 0;
    for line in src.split_inclusive('\n') {
        let code_end = line.find("//").unwrap_or(line.len());
        let mut from = 0;
        while let Some(i) = line[from..code_end].find(needle) {
            out.push(base + from + i);
            from += i + needle.len();
        }
        base += line.len();
    }
    out
}

/// Offsets of `key: [ ]` (an empty list under `key`).
fn empty_lists(src: &str, key: &str) -> Vec<(usize, bool)> {
    occurrences(src, key)
        .into_iter()
        .filter(|&i| {
            // a whole identifier
            let prev = src[..i].chars().next_back();
            !prev.is_some_and(|c| c.is_alphanumeric() || c == '_')
        })
        .filter_map(|i| {
            let rest = src[i + key.len()..].trim_start();
            let rest = rest.strip_prefix(':')?.trim_start();
            let rest = rest.strip_prefix('[')?;
            Some((i, rest.trim_start().starts_with(']')))
        })
        .collect()
}

fn locate(src: &str, path: &Path, needle: &str, nth: usize) -> Location {
    let (line, col) = occurrences(src, needle)
        .get(nth)
        .map_or((1, 1), |&i| line_col(src, i));
    loc(path, line, col)
}

/// RON to the model, with syntax and type errors at ron's position.
pub(crate) fn parse_desc(src: &str, path: &Path) -> Result<MaterialDesc, MaterialError> {
    let desc: MaterialDesc = ron::Options::default().from_str(src).map_err(|e| {
        let at = loc(path, e.span.start.line, e.span.start.col);
        match e.code {
            ron::Error::NoSuchEnumVariant {
                expected,
                found,
                outer: Some(outer),
            } if outer == "Lobe" => MaterialError::UnknownLobe {
                at,
                found,
                expected: expected.join(", "),
            },
            ron::Error::Message(m) if m.contains("untagged enum") => {
                let what = if m.contains("Color") {
                    "expected a colour: (r, g, b), Tex(texture: ..), Mix(..) or Scale(..)"
                } else {
                    "expected a number or Tex(texture: .., channel: ..), OneMinus(..), Mul(..)"
                };
                MaterialError::WrongType {
                    at,
                    message: what.to_string(),
                }
            }
            code @ (ron::Error::InvalidValueForType { .. }
            | ron::Error::ExpectedFloat
            | ron::Error::ExpectedInteger
            | ron::Error::ExpectedString
            | ron::Error::ExpectedStringEnd
            | ron::Error::ExpectedBoolean
            | ron::Error::ExpectedArray
            | ron::Error::ExpectedMap
            | ron::Error::ExpectedOption) => MaterialError::WrongType {
                at,
                message: code.to_string(),
            },
            code => MaterialError::Syntax {
                at,
                message: code.to_string(),
            },
        }
    })?;
    check(&desc, src, path)?;
    Ok(desc)
}

/// Most layers in a material, and lobes in a layer: compile time grows faster than
/// linearly with them (4,000 layers took 6 s).
pub(crate) const MAX_LAYERS: usize = 32;
pub(crate) const MAX_LOBES_PER_LAYER: usize = 8;

/// Semantic checks that serde cannot express.
fn check(desc: &MaterialDesc, src: &str, path: &Path) -> Result<(), MaterialError> {
    if desc.layers.is_empty() {
        let at = empty_lists(src, "layers").into_iter().find(|e| e.1).map_or(
            loc(path, 1, 1),
            |(i, _)| {
                let (l, c) = line_col(src, i);
                loc(path, l, c)
            },
        );
        return Err(MaterialError::EmptyLayers { at });
    }
    if desc.layers.len() > MAX_LAYERS {
        return Err(MaterialError::TooMany {
            at: locate(src, path, "layers", 0),
            what: "layer count",
            count: desc.layers.len(),
            limit: MAX_LAYERS,
        });
    }
    if let AlphaMode::Mask(cutoff) = desc.alpha_mode {
        if let Some(rule) = alpha_cutoff_rule(cutoff) {
            return Err(MaterialError::OutOfRange {
                at: locate(src, path, "Mask", 0),
                field: "alpha_mode Mask cutoff",
                value: format!("{cutoff}"),
                rule: rule.to_string(),
            });
        }
    }
    let lists = empty_lists(src, "lobes");
    for (i, layer) in desc.layers.iter().enumerate() {
        if layer.lobes.len() > MAX_LOBES_PER_LAYER {
            return Err(MaterialError::TooMany {
                at: locate(src, path, "lobes", i),
                what: "lobe count of a layer",
                count: layer.lobes.len(),
                limit: MAX_LOBES_PER_LAYER,
            });
        }
        if layer.lobes.is_empty() {
            let at = lists.get(i).map_or(loc(path, 1, 1), |&(o, _)| {
                let (l, c) = line_col(src, o);
                loc(path, l, c)
            });
            return Err(MaterialError::EmptyLobes { at, layer: i });
        }
    }
    // Every texture the material names must be declared.
    let used = desc.sources().into_iter().filter_map(|s| match s {
        Source::Texture(name) => Some(name),
        Source::Vertex => None,
    });
    for name in used {
        if !desc.textures.contains_key(name) {
            return Err(MaterialError::UnknownTexture {
                at: locate(src, path, &format!("\"{name}\""), 0),
                name: name.to_string(),
                declared: desc.textures.keys().cloned().collect::<Vec<_>>().join(", "),
            });
        }
    }
    Ok(())
}

/// Why an alpha cutoff is refused, if it is: coverage lies in [0, 1], so a cutoff outside
/// it keeps every fragment or none, and a non-finite one is no WGSL literal at all.
pub(crate) fn alpha_cutoff_rule(cutoff: f32) -> Option<&'static str> {
    (!(0.0..=1.0).contains(&cutoff)).then_some("must be a finite number in 0..=1")
}

/// Texture slots of a RON material: its declared files, in name order, which must exist.
pub(crate) fn file_slots(
    desc: &MaterialDesc,
    src: &str,
    path: &Path,
) -> Result<Vec<TextureSlot>, MaterialError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut slots = Vec::new();
    for (i, (name, tex)) in desc.textures.iter().enumerate() {
        if tex.tex_coord > 1 {
            return Err(MaterialError::OutOfRange {
                at: locate(src, path, "tex_coord", 0),
                field: "texture tex_coord",
                value: tex.tex_coord.to_string(),
                rule: "must be 0 (TEXCOORD_0) or 1 (TEXCOORD_1)".to_string(),
            });
        }
        let resolved = dir.join(&tex.file);
        if !resolved.is_file() {
            return Err(MaterialError::MissingTextureFile {
                at: locate(src, path, &format!("\"{}\"", tex.file), 0),
                path: tex.file.clone(),
                resolved,
            });
        }
        slots.push(TextureSlot {
            binding: i as u32 + 1,
            name: name.clone(),
            source: TextureSource::File {
                path: resolved,
                srgb: tex.srgb,
            },
            sampler: tex.sampler,
            tex_coord: tex.tex_coord,
            transform: tex.transform,
        });
    }
    Ok(slots)
}
