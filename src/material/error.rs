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

/// An error from loading, parsing, validating or compiling a material file. `Display`
/// starts with `file:line:col` where the error is at a place in the file.
#[derive(Debug, Error)]
pub enum MaterialError {
    /// The material file could not be read.
    #[error("{file}: cannot read material: {message}", file = .file.display())]
    Io {
        /// The material file.
        file: PathBuf,
        /// The operating system's error.
        message: String,
    },
    /// RON syntax error or unknown field.
    #[error("{at}: {message}")]
    Syntax {
        /// Where in the file.
        at: Location,
        /// What the RON parser or serde reported.
        message: String,
    },
    /// A lobe kind the material model does not have.
    #[error("{at}: unknown lobe `{found}` (expected one of: {expected})")]
    UnknownLobe {
        /// Where in the file.
        at: Location,
        /// The lobe name written.
        found: String,
        /// The lobe names known, comma-separated.
        expected: String,
    },
    /// A value of the wrong type, e.g. a colour where a number is needed.
    #[error("{at}: wrong parameter type: {message}")]
    WrongType {
        /// Where in the file.
        at: Location,
        /// What was expected.
        message: String,
    },
    /// `layers: []`: a material needs at least one layer.
    #[error("{at}: empty layer list: a material needs at least one layer")]
    EmptyLayers {
        /// Where in the file.
        at: Location,
    },
    /// More layers, or lobes in a layer, than the generated shader unrolls.
    #[error("{at}: {what} {count} is over the limit of {limit} (each is unrolled into the generated shader)")]
    TooMany {
        /// Where in the file.
        at: Location,
        /// What was counted (`layer count`, `lobe count of a layer`).
        what: &'static str,
        /// The count written.
        count: usize,
        /// The most allowed.
        limit: usize,
    },
    /// A value outside its range that is refused rather than clamped (the `Mask` cutoff).
    #[error("{at}: {field} {value} {rule}")]
    OutOfRange {
        /// Where in the file.
        at: Location,
        /// The parameter, e.g. `alpha_mode Mask cutoff`.
        field: &'static str,
        /// The value written.
        value: String,
        /// The range it must be in.
        rule: String,
    },
    /// A layer with `lobes: []`.
    #[error("{at}: empty lobe list: layer {layer} has no lobes")]
    EmptyLobes {
        /// Where in the file.
        at: Location,
        /// 0-based index of the layer.
        layer: usize,
    },
    /// A texture whose file does not exist.
    #[error("{at}: missing texture file `{path}` (looked for {resolved})", resolved = .resolved.display())]
    MissingTextureFile {
        /// Where in the file.
        at: Location,
        /// The path as written in the material file.
        path: String,
        /// Where it was looked for (relative to the material file).
        resolved: PathBuf,
    },
    /// A lobe parameter samples a texture the material does not declare.
    #[error("{at}: unknown texture `{name}` (declared: {declared})")]
    UnknownTexture {
        /// Where in the file.
        at: Location,
        /// The texture name used.
        name: String,
        /// The names declared in `textures`, comma-separated.
        declared: String,
    },
    /// A texture file that is not a decodable PNG or JPEG.
    #[error("texture `{name}`: cannot decode {path}: {message}", path = .path.display())]
    TextureDecode {
        /// The texture's name in the material.
        name: String,
        /// The image file.
        path: PathBuf,
        /// The decoder's error.
        message: String,
    },
    /// A scene's material override that failed: names the scene file and the material.
    #[error("{scene}: material_overrides \"{name}\": {source}", scene = .scene.display())]
    Override {
        /// The scene file naming the override.
        scene: PathBuf,
        /// The imported material name the override replaces.
        name: String,
        /// Why the override's material file failed.
        source: Box<MaterialError>,
    },
    /// naga rejected the generated WGSL (a bug in the generator or the lobe library).
    #[error("material `{material}`: generated WGSL is invalid: {message}")]
    Wgsl {
        /// The material's name.
        material: String,
        /// naga's validation error.
        message: String,
    },
}
