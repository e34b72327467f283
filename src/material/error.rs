//! Material errors. Every error about a file carries `file:line:col`.

use std::path::PathBuf;
use thiserror::Error;

/// A position in a material file (1-based line and column).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    pub(crate) file: PathBuf,
    pub(crate) line: usize,
    pub(crate) col: usize,
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}:{}", self.file.display(), self.line, self.col)
    }
}

#[derive(Debug, Error)]
pub enum MaterialError {
    #[error("{file}: cannot read material: {message}", file = .file.display())]
    Io { file: PathBuf, message: String },
    #[error("{at}: {message}")]
    Syntax { at: Location, message: String },
    #[error("{at}: unknown lobe `{found}` (expected one of: {expected})")]
    UnknownLobe {
        at: Location,
        found: String,
        expected: String,
    },
    #[error("{at}: wrong parameter type: {message}")]
    WrongType { at: Location, message: String },
    #[error("{at}: empty layer list: a material needs at least one layer")]
    EmptyLayers { at: Location },
    #[error("{at}: {what} {count} is over the limit of {limit} (each is unrolled into the generated shader)")]
    TooMany {
        at: Location,
        what: &'static str,
        count: usize,
        limit: usize,
    },
    #[error("{at}: {field} {value} {rule}")]
    OutOfRange {
        at: Location,
        field: &'static str,
        value: String,
        rule: String,
    },
    #[error("{at}: empty lobe list: layer {layer} has no lobes")]
    EmptyLobes { at: Location, layer: usize },
    #[error("{at}: missing texture file `{path}` (looked for {resolved})", resolved = .resolved.display())]
    MissingTextureFile {
        at: Location,
        path: String,
        resolved: PathBuf,
    },
    #[error("{at}: unknown texture `{name}` (declared: {declared})")]
    UnknownTexture {
        at: Location,
        name: String,
        declared: String,
    },
    #[error("texture `{name}`: cannot decode {path}: {message}", path = .path.display())]
    TextureDecode {
        name: String,
        path: PathBuf,
        message: String,
    },
    /// A scene's material override that failed: names the scene file and the material.
    #[error("{scene}: material_overrides \"{name}\": {source}", scene = .scene.display())]
    Override {
        scene: PathBuf,
        name: String,
        source: Box<MaterialError>,
    },
    /// naga rejected the generated WGSL (a bug in the generator or the lobe library).
    #[error("material `{material}`: generated WGSL is invalid: {message}")]
    Wgsl { material: String, message: String },
}
