//! Graph errors. Every variant names the file position, and the pass and resource involved.

use super::location::Location;
use thiserror::Error;

/// An error in a graph file found while loading, parsing or validating it; each variant's
/// `at` is the file position it is reported at.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum GraphError {
    /// The graph file could not be read.
    #[error("{at}: cannot read graph file: {message}")]
    Io {
        /// The file (at line 1).
        at: Location,
        /// Why it could not be read (missing, too large, not UTF-8).
        message: String,
    },
    /// The RON text does not parse into a graph (syntax, unknown field, wrong type).
    #[error("{at}: {context}syntax error: {message}")]
    Parse {
        /// Where the parser stopped.
        at: Location,
        /// "pass 'x': " when the error lies inside a pass.
        context: String,
        /// The parser's message.
        message: String,
    },
    /// A pass names a `kind` that is neither a built-in kind nor `Compute`/`Fullscreen`.
    #[error("{at}: pass '{pass}': unknown pass kind '{kind}' (known: {known})")]
    UnknownPassKind {
        /// The pass's `kind` field.
        at: Location,
        /// The pass's name.
        pass: String,
        /// The kind as written.
        kind: String,
        /// The variants of `PassKind`, as serde lists them.
        known: String,
    },
    /// Two passes or two resources share a name.
    #[error("{at}: {what} '{name}' is declared twice")]
    Duplicate {
        /// The repeated declaration.
        at: Location,
        /// `"pass"` or `"resource"`.
        what: &'static str,
        /// The name declared twice.
        name: String,
    },
    /// A pass reads or writes a resource the graph does not declare.
    #[error("{at}: pass '{pass}': unknown resource '{resource}'")]
    UnknownResource {
        /// The pass's reads or writes.
        at: Location,
        /// The pass's name.
        pass: String,
        /// The undeclared resource name.
        resource: String,
    },
    /// The graph's `output` is missing or not a colour texture the frame can be read back
    /// from.
    #[error("{at}: output '{resource}' {problem}")]
    BadOutput {
        /// The `output` field.
        at: Location,
        /// The resource named as output.
        resource: String,
        /// What is wrong with it.
        problem: String,
    },
    /// A `side_effects` entry names no declared pass.
    #[error("{at}: side effect '{pass}' is not a declared pass")]
    UnknownSideEffect {
        /// The `side_effects` entry.
        at: Location,
        /// The name that is not a pass.
        pass: String,
    },
    /// A pass reads a resource that no pass writes and that is not imported from the scene.
    #[error("{at}: pass '{pass}' reads resource '{resource}', which no pass writes")]
    ReadNeverWritten {
        /// The pass's reads.
        at: Location,
        /// The reading pass.
        pass: String,
        /// The resource nobody writes.
        resource: String,
    },
    /// Two passes write the same resource and neither depends on the other, so their order
    /// would be arbitrary.
    #[error("{at}: passes '{first}' and '{second}' both write resource '{resource}' with no order between them (make one read what the other writes)")]
    UnorderedWriters {
        /// Where the second writer names the resource.
        at: Location,
        /// The resource both write.
        resource: String,
        /// The first writer, in file order.
        first: String,
        /// The second writer.
        second: String,
    },
    /// The passes depend on each other in a loop, so no order exists.
    #[error("{at}: the passes form a cycle: {}", cycle_text(.passes))]
    Cycle {
        /// The first pass of the loop.
        at: Location,
        /// The passes of the loop, in dependency order.
        passes: Vec<String>,
    },
    /// A pass binds a resource in a way its kind or shader does not accept (format, usage,
    /// size or slot).
    #[error("{at}: pass '{pass}', resource '{resource}': {problem}")]
    Mismatch {
        /// The pass's reads or writes.
        at: Location,
        /// The pass's name.
        pass: String,
        /// The resource in question.
        resource: String,
        /// What does not match, in words.
        problem: String,
    },
    /// A resource declaration is invalid (size, format, sample count or limits).
    #[error("{at}: resource '{resource}': {problem}")]
    BadResource {
        /// The resource's declaration.
        at: Location,
        /// The resource's name.
        resource: String,
        /// What is wrong with it.
        problem: String,
    },
    /// A pass's parameters are invalid for its kind or the frame (dispatch, workgroup,
    /// options).
    #[error("{at}: pass '{pass}': {problem}")]
    BadPass {
        /// The pass's declaration.
        at: Location,
        /// The pass's name.
        pass: String,
        /// What is wrong with it.
        problem: String,
    },
    /// A generic pass's shader binds a name the pass neither reads nor writes.
    #[error("{at}: pass '{pass}': shader {shader} binds '{binding}', which the pass does not declare in reads or writes")]
    UndeclaredBinding {
        /// The pass's shader field.
        at: Location,
        /// The pass's name.
        pass: String,
        /// The shader file.
        shader: String,
        /// The shader's binding name.
        binding: String,
    },
    /// A generic pass declares a resource its shader never binds.
    #[error("{at}: pass '{pass}': resource '{resource}' is declared but shader {shader} has no binding of that name")]
    UnboundResource {
        /// The pass's reads or writes.
        at: Location,
        /// The pass's name.
        pass: String,
        /// The shader file.
        shader: String,
        /// The declared resource name.
        resource: String,
    },
    /// A pass's shader fails to load, compose or validate (naga), or does not have the
    /// named entry point.
    #[error("{at}: pass '{pass}': {message}")]
    Shader {
        /// Where the pass names the shader.
        at: Location,
        /// The pass's name.
        pass: String,
        /// The shader error, already `file:line:col: message`.
        message: String,
    },
}

fn cycle_text(passes: &[String]) -> String {
    let mut s = passes.join(" -> ");
    if let Some(first) = passes.first() {
        s.push_str(" -> ");
        s.push_str(first);
    }
    s
}

impl GraphError {
    /// The file position the error is reported at, for editors and messages.
    pub fn location(&self) -> &Location {
        match self {
            GraphError::Io { at, .. }
            | GraphError::Parse { at, .. }
            | GraphError::UnknownPassKind { at, .. }
            | GraphError::Duplicate { at, .. }
            | GraphError::UnknownResource { at, .. }
            | GraphError::BadOutput { at, .. }
            | GraphError::UnknownSideEffect { at, .. }
            | GraphError::ReadNeverWritten { at, .. }
            | GraphError::UnorderedWriters { at, .. }
            | GraphError::Cycle { at, .. }
            | GraphError::Mismatch { at, .. }
            | GraphError::BadResource { at, .. }
            | GraphError::BadPass { at, .. }
            | GraphError::UndeclaredBinding { at, .. }
            | GraphError::UnboundResource { at, .. }
            | GraphError::Shader { at, .. } => at,
        }
    }
}

/// Several errors found in one go (validation reports all it finds).
#[derive(Debug, Error, Clone, PartialEq)]
#[error("{}", .0.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\n"))]
pub struct GraphErrors(pub Vec<GraphError>);

impl From<GraphError> for GraphErrors {
    fn from(e: GraphError) -> Self {
        GraphErrors(vec![e])
    }
}
