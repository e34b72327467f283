//! Step 1: text to [`GraphDesc`], with file:line:col on every syntax error.
//!
//! Two paths to the same value: [`fast`], a small deserializer for the RON subset graph
//! files use, and `ron` itself. The fast path answers only "this value" or "not mine";
//! on the second, and so on every error, `ron` parses the text again, so every value
//! and every error message and position is `ron`'s.

mod fast;

use super::error::GraphError;
use super::location::SourceText;
use super::model::GraphDesc;
use std::path::Path;

/// Reads and parses a graph file.
pub fn load(path: &Path) -> Result<(GraphDesc, SourceText), GraphError> {
    let text =
        crate::files::read_text(path, crate::files::caps::RON).map_err(|e| GraphError::Io {
            at: SourceText::new(path, "").at(1, 1),
            message: e.to_string(),
        })?;
    let source = SourceText::new(path, text);
    let desc = parse(&source)?;
    Ok((desc, source))
}

/// Parses graph text; `source.file` is only used in messages.
pub fn parse(source: &SourceText) -> Result<GraphDesc, GraphError> {
    match parse_fast(&source.text) {
        Some(desc) => Ok(desc),
        None => parse_ron_only(source),
    }
}

/// The fast path alone: `None` where the text is outside its subset or wrong.
fn parse_fast(text: &str) -> Option<GraphDesc> {
    let mut desc: GraphDesc = fast::from_str(text)?;
    for pass in &mut desc.passes {
        pass.split_named_slots();
    }
    Some(desc)
}

/// `ron` alone, with the graph's error messages.
fn parse_ron_only(source: &SourceText) -> Result<GraphDesc, GraphError> {
    // Kinds wrap their parameter struct: `LightCulling(tile: 16)`, not `LightCulling((tile: 16))`.
    let options = ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES);
    let mut desc = options.from_str::<GraphDesc>(&source.text).map_err(|e| {
        let (line, col) = (e.span.start.line, e.span.start.col);
        let at = source.at(line, col);
        let pass = source.pass_around(source.offset_of(line, col));
        if let ron::Error::NoSuchEnumVariant {
            expected, found, ..
        } = &e.code
        {
            if expected.contains(&"DepthPrepass") {
                return GraphError::UnknownPassKind {
                    at,
                    pass: pass.unwrap_or_else(|| "?".into()),
                    kind: found.clone(),
                    known: expected.join(", "),
                };
            }
        }
        GraphError::Parse {
            at,
            context: pass.map(|p| format!("pass '{p}': ")).unwrap_or_default(),
            message: e.code.to_string(),
        }
    })?;
    for pass in &mut desc.passes {
        pass.split_named_slots();
    }
    Ok(desc)
}

/// Both parse paths, for tests that compare them (`graph::parse` is what to call).
impl GraphDesc {
    /// The fast RON-subset path alone: `None` where it does not apply or the text is
    /// wrong. When it returns a value, `ron` returns the same one.
    #[doc(hidden)]
    pub fn parse_fast(text: &str) -> Option<GraphDesc> {
        parse_fast(text)
    }

    /// `ron` alone, with the same errors as [`parse`].
    #[doc(hidden)]
    pub fn parse_ron_only(source: &SourceText) -> Result<GraphDesc, GraphError> {
        parse_ron_only(source)
    }
}
