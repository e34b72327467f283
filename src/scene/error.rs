//! Scene loading errors. Every error names the file and the element at fault.

use std::fmt;
use std::path::PathBuf;

/// An error from [`crate::scene::load`] and the importers. `Display` reads
/// `FILE: ELEMENT: MESSAGE` (or `FILE:LINE:COL: MESSAGE` for RON syntax errors).
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A file could not be read.
    #[error("{}: cannot read file: {source}", file.display())]
    Io {
        /// The file that could not be read.
        file: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// RON syntax or type error.
    #[error("{}:{line}:{col}: {message}", file.display())]
    Parse {
        /// The scene file.
        file: PathBuf,
        /// 1-based line of the error.
        line: usize,
        /// 1-based column of the error.
        col: usize,
        /// What the RON parser or serde reported.
        message: String,
    },
    /// Bad content: names the element (e.g. `mesh 0 ("box") primitive 1 accessor 3`),
    /// and where a scene file writes it when that is known.
    #[error("{}{}: {element}: {message}", file.display(), at_text(at))]
    Invalid {
        /// The file holding the bad content.
        file: PathBuf,
        /// Line and column (1-based) where the scene file writes the element, when known.
        at: Option<(usize, usize)>,
        /// The element at fault, e.g. `mesh 0 ("box") primitive 1 accessor 3` or `light 3`.
        element: String,
        /// What is wrong with it.
        message: String,
    },
    /// A count past a safety limit.
    #[error("{}{}: {element}: {what} {count} exceeds the limit of {limit}", file.display(), at_text(at))]
    Limit {
        /// The file holding the element.
        file: PathBuf,
        /// Line and column (1-based) where the scene file writes the element, when known.
        at: Option<(usize, usize)>,
        /// The element whose count is too large.
        element: String,
        /// What was counted, e.g. `triangle count after instancing`.
        what: &'static str,
        /// The count found.
        count: u64,
        /// The largest count allowed.
        limit: u64,
    },
}

impl SceneError {
    pub(crate) fn invalid(
        file: impl Into<PathBuf>,
        element: impl fmt::Display,
        message: impl fmt::Display,
    ) -> Self {
        SceneError::Invalid {
            file: file.into(),
            at: None,
            element: element.to_string(),
            message: message.to_string(),
        }
    }

    pub(crate) fn io(file: impl Into<PathBuf>, source: std::io::Error) -> Self {
        SceneError::Io {
            file: file.into(),
            source,
        }
    }

    /// The error with the line and column where the scene file `file`, whose text is
    /// `text`, writes the element it names (when it names one of that file's).
    pub(crate) fn located_in(self, file: &std::path::Path, text: &str) -> Self {
        self.located_by(file, |element, _| super::locate::locate(text, element))
    }

    /// The error with the line and column `find(element, message)` gives, for an element
    /// of `file` not yet located.
    pub(crate) fn located_by(
        mut self,
        file: &std::path::Path,
        find: impl Fn(&str, &str) -> Option<(usize, usize)>,
    ) -> Self {
        match &mut self {
            SceneError::Invalid {
                file: f,
                at,
                element,
                message,
            } if f == file && at.is_none() => *at = find(element, message),
            SceneError::Limit {
                file: f,
                at,
                element,
                ..
            } if f == file && at.is_none() => *at = find(element, ""),
            _ => {}
        }
        self
    }

    /// The file the error is about.
    pub fn file(&self) -> &std::path::Path {
        match self {
            SceneError::Io { file, .. }
            | SceneError::Parse { file, .. }
            | SceneError::Invalid { file, .. }
            | SceneError::Limit { file, .. } => file,
        }
    }
}

fn at_text(at: &Option<(usize, usize)>) -> String {
    at.map(|(line, col)| format!(":{line}:{col}"))
        .unwrap_or_default()
}
