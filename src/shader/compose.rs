use super::limits::{
    longest_statement_over_limit, on_naga_stack, MAX_INCLUDE_DEPTH, MAX_OPERATORS_PER_STATEMENT,
};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// An error loading, composing or compiling a WGSL shader, naming the file and line in the
/// original source.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ShaderError {
    /// The shader file could not be read.
    #[error("{file}: cannot read shader: {message}")]
    Io {
        /// The shader file.
        file: PathBuf,
        /// Why it could not be read.
        message: String,
    },
    /// A preprocessor directive (`#include`, `#if`, `#else`, `#endif`) is malformed,
    /// unmatched, names nothing, or nests includes too deep.
    #[error("{file}:{line}: {message}")]
    Directive {
        /// The file holding the directive.
        file: PathBuf,
        /// Its 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// naga rejected the WGSL; `line`/`col` are in the original file.
    #[error("{file}:{line}:{col}: {message}\n    {source_line}")]
    Invalid {
        /// The original file (after following includes back).
        file: PathBuf,
        /// 1-based line in that file.
        line: usize,
        /// 1-based column.
        col: usize,
        /// naga's message.
        message: String,
        /// The offending source line, shown under the message.
        source_line: String,
    },
    /// The composed shader binds more of a resource than the device allows.
    #[error("{file}: {message}")]
    OverLimit {
        /// The shader file.
        file: PathBuf,
        /// What it binds, with which options, and the device's limit.
        message: String,
    },
}

/// Where shader files are found; `#include "x.wgsl"` resolves against `root`, and with
/// `builtin_fallback` a file not there comes from the shaders built into the binary
/// (named `<built-in>/shaders/x.wgsl` in errors). Virtual files (generated code such as
/// materials) are included as `#include <name>`.
#[derive(Clone, Debug)]
pub struct ShaderLibrary {
    /// The shader folder on disk (`<built-in>/shaders` when there is none).
    pub root: PathBuf,
    /// Whether files missing under `root` are taken from the built-in shaders.
    pub builtin_fallback: bool,
}

/// A shader after includes and defines, with a map from each line back to its origin.
#[derive(Clone, Debug)]
pub struct Composed {
    /// The composed WGSL source, ready for naga.
    pub text: String,
    /// For line i (0-based) of `text`: the file it came from and its 1-based line there.
    pub origin: Vec<(PathBuf, usize)>,
    /// Every real file that went into it (for hot reload dependencies).
    pub files: Vec<PathBuf>,
}

impl ShaderLibrary {
    /// Shaders from `root` only.
    pub fn new(root: impl Into<PathBuf>) -> Self {
        Self {
            root: root.into(),
            builtin_fallback: false,
        }
    }

    /// Shaders from `root` first, file by file, then the built-in ones.
    pub fn with_builtin(root: impl Into<PathBuf>) -> Self {
        Self {
            root: root.into(),
            builtin_fallback: true,
        }
    }

    /// The project's shaders: `shaders/` of the process's root (see
    /// [`assets`](super::assets): `--root`, `LIGHTGRAPH_ROOT`, the current directory)
    /// over the built-in ones.
    pub fn builtin() -> Self {
        Self::for_project(&super::assets::project())
    }

    /// `project`'s shaders/ over the built-in ones.
    pub fn for_project(project: &super::assets::Project) -> Self {
        Self::with_builtin(project.shader_dir())
    }

    /// The name shader file `rel` (relative to the root) is read by: `root/rel` when
    /// that file exists (or there is no fallback), else `<built-in>/shaders/rel` when it
    /// is built in.
    pub fn locate(&self, rel: &str) -> PathBuf {
        let disk = self.root.join(rel);
        if self.builtin_fallback && !disk.is_file() {
            let name = format!("shaders/{rel}");
            if super::assets::builtin(&name).is_some() {
                return super::assets::builtin_path(&name);
            }
        }
        disk
    }

    /// The text of shader file `rel` (e.g. `common/fullscreen_vs.wgsl`), found as
    /// `#include` finds it: on disk under the root first, then built in.
    pub fn read_source(&self, rel: &str) -> Result<String, ShaderError> {
        let file = self.locate(rel);
        super::assets::read_path(&file).map_err(|e| ShaderError::Io {
            message: e.to_string(),
            file,
        })
    }

    /// Reads `file` (relative to the root), expands includes and `#if`, and prepends the
    /// defines as WGSL constants (`const NAME = VALUE;`).
    pub fn compose(
        &self,
        file: &str,
        defines: &BTreeMap<String, String>,
        virtual_files: &BTreeMap<String, String>,
    ) -> Result<Composed, ShaderError> {
        let mut out = Composed {
            text: String::new(),
            origin: Vec::new(),
            files: Vec::new(),
        };
        for (name, value) in defines {
            out.push_line(
                &format!("const {name} = {value};"),
                Path::new("<defines>"),
                0,
            );
        }
        self.include(file, defines, virtual_files, &mut out, 0)?;
        Ok(out)
    }

    /// Includes file `rel` (relative to the root) once. `files` records where it is or
    /// would be on disk, so that a file created there later to override a built-in one
    /// invalidates what used it; line origins name the file it was read from.
    fn include(
        &self,
        rel: &str,
        defines: &BTreeMap<String, String>,
        virtual_files: &BTreeMap<String, String>,
        out: &mut Composed,
        depth: usize,
    ) -> Result<(), ShaderError> {
        let disk = self.root.join(rel);
        if out.files.iter().any(|f| f == &disk) {
            return Ok(()); // include once
        }
        let path = self.locate(rel);
        let text = self.read_source(rel)?;
        out.files.push(disk);
        self.expand(&path, &text, defines, virtual_files, out, depth)
    }

    /// `depth`: how many `#include`s led here (recursion is one stack frame pair each).
    fn expand(
        &self,
        path: &Path,
        text: &str,
        defines: &BTreeMap<String, String>,
        virtual_files: &BTreeMap<String, String>,
        out: &mut Composed,
        depth: usize,
    ) -> Result<(), ShaderError> {
        // Stack of (this branch active, some branch taken) for nested #if.
        let mut conditions: Vec<(bool, bool)> = Vec::new();
        let directive_error = |line: usize, message: String| ShaderError::Directive {
            file: path.to_path_buf(),
            line,
            message,
        };
        for (i, line) in text.lines().enumerate() {
            let n = i + 1;
            let active = conditions.iter().all(|c| c.0);
            let trimmed = line.trim_start();
            if let Some(rest) = trimmed.strip_prefix("#if ") {
                let on = active && is_set(defines, rest.trim());
                conditions.push((on, on));
                out.push_line("", path, n);
            } else if trimmed.starts_with("#else") {
                let parent =
                    conditions.len() < 2 || conditions[..conditions.len() - 1].iter().all(|c| c.0);
                let top = conditions
                    .last_mut()
                    .ok_or_else(|| directive_error(n, "#else without #if".into()))?;
                top.0 = parent && !top.1;
                out.push_line("", path, n);
            } else if trimmed.starts_with("#endif") {
                conditions
                    .pop()
                    .ok_or_else(|| directive_error(n, "#endif without #if".into()))?;
                out.push_line("", path, n);
            } else if let Some(rest) = trimmed.strip_prefix("#include") {
                out.push_line("", path, n);
                if !active {
                    continue;
                }
                let rest = rest.trim();
                if depth >= MAX_INCLUDE_DEPTH {
                    return Err(directive_error(
                        n,
                        format!(
                            "#include {rest} is nested {} deep, over the limit of {MAX_INCLUDE_DEPTH} (an include cycle through generated code, or a chain too long)",
                            depth + 1
                        ),
                    ));
                }
                if let Some(name) = rest.strip_prefix('<').and_then(|r| r.strip_suffix('>')) {
                    let code = virtual_files.get(name).ok_or_else(|| {
                        directive_error(n, format!("no generated code named <{name}>"))
                    })?;
                    let vpath = PathBuf::from(format!("<{name}>"));
                    self.expand(&vpath, code, defines, virtual_files, out, depth + 1)?;
                } else if let Some(name) = rest.strip_prefix('"').and_then(|r| r.strip_suffix('"'))
                {
                    self.include(name, defines, virtual_files, out, depth + 1)?;
                } else {
                    return Err(directive_error(n, format!("malformed #include {rest}")));
                }
            } else if active && trimmed.starts_with("enable ") {
                // WGSL wants directives before every declaration, the defines' constants
                // included: moved to the top (its origin with it).
                out.hoist_line(line, path, n);
            } else if active {
                out.push_line(line, path, n);
            } else {
                out.push_line("", path, n);
            }
        }
        if !conditions.is_empty() {
            return Err(directive_error(
                text.lines().count(),
                "#if without #endif".into(),
            ));
        }
        Ok(())
    }
}

fn is_set(defines: &BTreeMap<String, String>, name: &str) -> bool {
    defines
        .get(name)
        .is_some_and(|v| !matches!(v.as_str(), "0" | "0u" | "false"))
}

impl Composed {
    fn hoist_line(&mut self, line: &str, file: &Path, n: usize) {
        self.text.insert_str(0, &format!("{line}\n"));
        self.origin.insert(0, (file.to_path_buf(), n));
    }

    fn push_line(&mut self, line: &str, file: &Path, n: usize) {
        self.text.push_str(line);
        self.text.push('\n');
        self.origin.push((file.to_path_buf(), n));
    }

    /// Maps a 1-based line of the composed text to (file, line).
    pub fn origin_of(&self, line: usize) -> (PathBuf, usize) {
        match (self.origin.get(line.saturating_sub(1)), self.origin.last()) {
            (Some(o), _) => o.clone(),
            // Past the end (naga points after the last line for an unclosed item): the
            // last file, past its last line.
            (None, Some((file, last))) => (file.clone(), last + line - self.origin.len()),
            (None, None) => (PathBuf::from("<composed>"), line),
        }
    }

    /// Parses and validates with naga; errors name the original file and line.
    pub fn validate(&self) -> Result<naga::Module, ShaderError> {
        if let Some(line) = longest_statement_over_limit(&self.text) {
            return Err(self.invalid(
                Some(naga::SourceLocation {
                    line_number: line as u32,
                    line_position: 1,
                    offset: 0,
                    length: 0,
                }),
                format!("this statement has over {MAX_OPERATORS_PER_STATEMENT} operators, the limit (naga nests one expression per operator): split it"),
            ));
        }
        on_naga_stack(|| self.validate_with_naga())
    }

    fn validate_with_naga(&self) -> Result<naga::Module, ShaderError> {
        let module = naga::front::wgsl::parse_str(&self.text).map_err(|e| {
            let loc = e.location(&self.text);
            self.invalid(loc, e.message().to_string())
        })?;
        let mut validator = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        );
        validator.validate(&module).map_err(|e| {
            let loc = e.location(&self.text);
            let mut message = e.as_inner().to_string();
            let mut source = std::error::Error::source(e.as_inner());
            while let Some(s) = source {
                message.push_str(": ");
                message.push_str(&s.to_string());
                source = s.source();
            }
            self.invalid(loc, message)
        })?;
        Ok(module)
    }

    fn invalid(&self, loc: Option<naga::SourceLocation>, message: String) -> ShaderError {
        let (line, col) = loc.map_or((0, 0), |l| {
            (l.line_number as usize, l.line_position as usize)
        });
        let (file, file_line) = self.origin_of(line);
        let source_line = self
            .text
            .lines()
            .nth(line.saturating_sub(1))
            .unwrap_or("")
            .trim();
        // A generated line can be megabytes long: quote its start.
        let source_line = match source_line.char_indices().nth(160) {
            Some((i, _)) => format!("{} …", &source_line[..i]),
            None => source_line.to_string(),
        };
        ShaderError::Invalid {
            file,
            line: file_line,
            col,
            message,
            source_line,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn library(files: &[(&str, &str)]) -> (tempdir::Dir, ShaderLibrary) {
        let dir = tempdir::Dir::new();
        for (name, text) in files {
            std::fs::write(dir.path.join(name), text).unwrap();
        }
        let lib = ShaderLibrary::new(&dir.path);
        (dir, lib)
    }

    mod tempdir {
        pub struct Dir {
            pub path: std::path::PathBuf,
        }
        impl Dir {
            pub fn new() -> Self {
                use std::sync::atomic::{AtomicU32, Ordering};
                static N: AtomicU32 = AtomicU32::new(0);
                let path = std::env::temp_dir().join(format!(
                    "lightgraph-shader-{}-{}",
                    std::process::id(),
                    N.fetch_add(1, Ordering::Relaxed)
                ));
                std::fs::create_dir_all(&path).unwrap();
                Self { path }
            }
        }
        impl Drop for Dir {
            fn drop(&mut self) {
                let _ = std::fs::remove_dir_all(&self.path);
            }
        }
    }

    #[test]
    fn includes_defines_and_conditionals() {
        let (_d, lib) = library(&[
            (
                "a.wgsl",
                "#include \"b.wgsl\"\n#if FAST\nconst X = 1;\n#else\nconst X = 2;\n#endif\n",
            ),
            ("b.wgsl", "const B = 3;\n"),
        ]);
        let defines = BTreeMap::from([("FAST".to_string(), "1".to_string())]);
        let c = lib.compose("a.wgsl", &defines, &BTreeMap::new()).unwrap();
        assert!(c.text.contains("const FAST = 1;"));
        assert!(c.text.contains("const B = 3;"));
        assert!(c.text.contains("const X = 1;"));
        assert!(!c.text.contains("const X = 2;"));
        c.validate().unwrap();
    }

    #[test]
    fn errors_map_back_to_the_included_file_and_line() {
        let (_d, lib) = library(&[
            ("a.wgsl", "const A = 1;\n#include \"b.wgsl\"\n"),
            (
                "b.wgsl",
                "const B = 3;\n\nfn f() -> f32 { return undefined_name; }\n",
            ),
        ]);
        let c = lib
            .compose("a.wgsl", &BTreeMap::new(), &BTreeMap::new())
            .unwrap();
        match c.validate().unwrap_err() {
            ShaderError::Invalid { file, line, .. } => {
                assert!(file.ends_with("b.wgsl"), "{file:?}");
                assert_eq!(line, 3);
            }
            e => panic!("unexpected {e}"),
        }
    }

    #[test]
    fn an_error_at_the_end_names_the_last_file() {
        let (_d, lib) = library(&[
            ("a.wgsl", "#include \"b.wgsl\"\nconst A = 1;\n"),
            ("b.wgsl", "const B = 3;\n"),
        ]);
        let c = lib
            .compose("a.wgsl", &BTreeMap::new(), &BTreeMap::new())
            .unwrap();
        let (file, line) = c.origin_of(c.origin.len() + 1);
        assert!(file.ends_with("a.wgsl"), "{file:?}");
        assert_eq!(line, 3);
        let (_d, lib) = library(&[("a.wgsl", "fn f() {\n")]);
        let c = lib
            .compose("a.wgsl", &BTreeMap::new(), &BTreeMap::new())
            .unwrap();
        match c.validate().unwrap_err() {
            ShaderError::Invalid { file, .. } => assert!(file.ends_with("a.wgsl"), "{file:?}"),
            e => panic!("unexpected {e}"),
        }
    }

    #[test]
    fn unbalanced_if_is_reported() {
        let (_d, lib) = library(&[("a.wgsl", "#if X\nconst A = 1;\n")]);
        let e = lib
            .compose("a.wgsl", &BTreeMap::new(), &BTreeMap::new())
            .unwrap_err();
        assert!(e.to_string().contains("#if without #endif"), "{e}");
    }
}
