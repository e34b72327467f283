//! Graph errors. Every variant names the file position, and the pass and resource involved.

use super::location::Location;
use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum GraphError {
    #[error("{at}: cannot read graph file: {message}")]
    Io { at: Location, message: String },
    #[error("{at}: {context}syntax error: {message}")]
    Parse {
        at: Location,
        /// "pass 'x': " when the error lies inside a pass.
        context: String,
        message: String,
    },
    #[error("{at}: pass '{pass}': unknown pass kind '{kind}' (known: {known})")]
    UnknownPassKind {
        at: Location,
        pass: String,
        kind: String,
        /// The variants of `PassKind`, as serde lists them.
        known: String,
    },
    #[error("{at}: {what} '{name}' is declared twice")]
    Duplicate {
        at: Location,
        what: &'static str,
        name: String,
    },
    #[error("{at}: pass '{pass}': unknown resource '{resource}'")]
    UnknownResource {
        at: Location,
        pass: String,
        resource: String,
    },
    #[error("{at}: output '{resource}' {problem}")]
    BadOutput {
        at: Location,
        resource: String,
        problem: String,
    },
    #[error("{at}: side effect '{pass}' is not a declared pass")]
    UnknownSideEffect { at: Location, pass: String },
    #[error("{at}: pass '{pass}' reads resource '{resource}', which no pass writes")]
    ReadNeverWritten {
        at: Location,
        pass: String,
        resource: String,
    },
    #[error("{at}: passes '{first}' and '{second}' both write resource '{resource}' with no order between them (make one read what the other writes)")]
    UnorderedWriters {
        at: Location,
        resource: String,
        first: String,
        second: String,
    },
    #[error("{at}: the passes form a cycle: {}", cycle_text(.passes))]
    Cycle { at: Location, passes: Vec<String> },
    #[error("{at}: pass '{pass}', resource '{resource}': {problem}")]
    Mismatch {
        at: Location,
        pass: String,
        resource: String,
        problem: String,
    },
    #[error("{at}: resource '{resource}': {problem}")]
    BadResource {
        at: Location,
        resource: String,
        problem: String,
    },
    #[error("{at}: pass '{pass}': {problem}")]
    BadPass {
        at: Location,
        pass: String,
        problem: String,
    },
    #[error("{at}: pass '{pass}': shader {shader} binds '{binding}', which the pass does not declare in reads or writes")]
    UndeclaredBinding {
        at: Location,
        pass: String,
        shader: String,
        binding: String,
    },
    #[error("{at}: pass '{pass}': resource '{resource}' is declared but shader {shader} has no binding of that name")]
    UnboundResource {
        at: Location,
        pass: String,
        shader: String,
        resource: String,
    },
    #[error("{at}: pass '{pass}': {message}")]
    Shader {
        /// Where the pass names the shader.
        at: Location,
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
