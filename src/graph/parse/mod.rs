//! Step 1: text to [`GraphDesc`] with `ron`, with file:line:col on every syntax error.

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
