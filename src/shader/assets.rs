//! Where the project's files are found: shaders/, graphs/ and materials/ under a root
//! folder on disk first, then the copies built into the binary (`include_dir`), file by
//! file. A folder that has only `shaders/common/lighting.wgsl` renders with that one file
//! changed and everything else built in.
//!
//! The root is, in this order: the folder the CLI was given with `--root` (see
//! [`set_root`]), `LIGHTGRAPH_ROOT`, the current directory if it has any of shaders/,
//! graphs/ or materials/, and otherwise none (built-in files only). Never the source tree
//! the binary was built from.
//!
//! Built-in files are named `<built-in>/shaders/x.wgsl` in messages and paths; every
//! reader here ([`read_path`], [`crate::shader::ShaderLibrary`]) understands that name.

use include_dir::{include_dir, Dir};
use std::path::{Path, PathBuf};
use std::sync::RwLock;

static SHADERS: Dir<'static> = include_dir!("$CARGO_MANIFEST_DIR/shaders");
static GRAPHS: Dir<'static> = include_dir!("$CARGO_MANIFEST_DIR/graphs");
static MATERIALS: Dir<'static> = include_dir!("$CARGO_MANIFEST_DIR/materials");

/// The folders a root may have, each with a built-in copy.
pub const FOLDERS: [&str; 3] = ["shaders", "graphs", "materials"];

/// The prefix of a built-in file's path: `<built-in>/graphs/forward_plus.ron`.
pub(crate) const BUILTIN_PREFIX: &str = "<built-in>";

/// The environment variable that names the root when `--root` is not given.
pub const ROOT_ENV: &str = "LIGHTGRAPH_ROOT";

fn folder(name: &str) -> Option<&'static Dir<'static>> {
    match name {
        "shaders" => Some(&SHADERS),
        "graphs" => Some(&GRAPHS),
        "materials" => Some(&MATERIALS),
        _ => None,
    }
}

/// `rel` ("shaders/common/types.wgsl") split into its top folder and the rest, with
/// `\` read as `/` and `./` dropped.
fn split(rel: &str) -> Option<(&'static Dir<'static>, String)> {
    let rel = rel.replace('\\', "/");
    let rel = rel.trim_start_matches("./");
    let (top, rest) = rel.split_once('/')?;
    Some((folder(top)?, rest.to_string()))
}

/// The built-in copy of project file `rel` (relative to a root, e.g.
/// `shaders/common/types.wgsl`), if there is one.
pub fn builtin(rel: &str) -> Option<&'static str> {
    let (dir, rest) = split(rel)?;
    dir.get_file(rest)?.contents_utf8()
}

/// Every built-in file under folder `dir` (`"shaders"`, `"graphs"` or `"materials"`), as
/// paths relative to a root (`graphs/forward_plus.ron`), sorted.
pub(crate) fn builtin_files(dir: &str) -> Vec<String> {
    fn walk(d: &Dir<'static>, top: &str, out: &mut Vec<String>) {
        for f in d.files() {
            out.push(format!(
                "{top}/{}",
                f.path().to_string_lossy().replace('\\', "/")
            ));
        }
        for sub in d.dirs() {
            walk(sub, top, out);
        }
    }
    let mut out = Vec::new();
    if let Some(d) = folder(dir) {
        walk(d, dir, &mut out);
    }
    out.sort();
    out
}

/// The name a built-in file goes by: `<built-in>/<rel>`.
pub(crate) fn builtin_path(rel: &str) -> PathBuf {
    PathBuf::from(format!("{BUILTIN_PREFIX}/{}", rel.replace('\\', "/")))
}

/// If `path` is a built-in file's name (`<built-in>/<rel>`), `rel`.
pub(crate) fn builtin_rel(path: &Path) -> Option<String> {
    let rest = path.strip_prefix(BUILTIN_PREFIX).ok()?;
    Some(rest.to_string_lossy().replace('\\', "/"))
}

/// Reads a file by the name [`Project::locate`] gives: `<built-in>/<rel>` from the
/// binary, any other path from disk.
pub fn read_path(path: &Path) -> std::io::Result<String> {
    match builtin_rel(path) {
        Some(rel) => builtin(&rel).map(str::to_string).ok_or_else(|| {
            std::io::Error::new(
                std::io::ErrorKind::NotFound,
                format!("no built-in file {rel}"),
            )
        }),
        None => crate::files::read_text(path, crate::files::caps::SHADER),
    }
}

/// Parses and validates a graph file by the name [`Project::locate`] gives (a built-in
/// graph or a file on disk), as [`crate::graph::check_file`] does for files on disk.
pub fn check_graph(
    path: &Path,
    shaders: &crate::shader::ShaderLibrary,
) -> Result<crate::graph::CheckedGraph, crate::graph::GraphErrors> {
    match builtin_rel(path).and_then(|rel| builtin(&rel)) {
        Some(text) => crate::graph::check_text(path, text, shaders),
        None => crate::graph::check_file(path, shaders),
    }
}

/// How a root was chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RootSource {
    /// `--root DIR`.
    Flag,
    /// `LIGHTGRAPH_ROOT`.
    Env,
    /// The current directory has shaders/, graphs/ or materials/.
    CurrentDir,
    /// No folder: built-in files only.
    BuiltIn,
}

/// The folder project files are looked for in first, if any, and why it was chosen.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Project {
    /// The folder, or `None` when only the built-in files are used.
    pub root: Option<PathBuf>,
    /// How the folder was chosen.
    pub source: RootSource,
}

/// Whether `dir` has any of shaders/, graphs/, materials/.
pub(crate) fn has_project_folders(dir: &Path) -> bool {
    FOLDERS.iter().any(|f| dir.join(f).is_dir())
}

/// An absolute form of `dir` (canonical where it exists), for messages.
fn absolute(dir: &Path) -> PathBuf {
    dir.canonicalize().unwrap_or_else(|_| {
        std::env::current_dir()
            .map(|c| c.join(dir))
            .unwrap_or_else(|_| dir.to_path_buf())
    })
}

impl Project {
    /// Built-in files only.
    pub(crate) fn builtin_only() -> Self {
        Self {
            root: None,
            source: RootSource::BuiltIn,
        }
    }

    /// Files under `root` first, then the built-in ones.
    pub fn at(root: impl Into<PathBuf>, source: RootSource) -> Self {
        Self {
            root: Some(root.into()),
            source,
        }
    }

    /// Resolves the root: `flag` (`--root`), else `LIGHTGRAPH_ROOT`, else the current
    /// directory if it has any of shaders/, graphs/, materials/, else none. Does not
    /// check that a given folder exists (see [`Project::check`]).
    pub fn resolve(flag: Option<&Path>) -> Self {
        if let Some(dir) = flag {
            return Self::at(absolute(dir), RootSource::Flag);
        }
        if let Some(dir) = std::env::var_os(ROOT_ENV).filter(|v| !v.is_empty()) {
            return Self::at(absolute(Path::new(&dir)), RootSource::Env);
        }
        match std::env::current_dir() {
            Ok(cwd) if has_project_folders(&cwd) => Self::at(cwd, RootSource::CurrentDir),
            _ => Self::builtin_only(),
        }
    }

    /// An error if the root was given (flag or environment) but is not a folder.
    pub fn check(&self) -> Result<(), String> {
        match (&self.root, self.source) {
            (Some(dir), RootSource::Flag | RootSource::Env) if !dir.is_dir() => Err(format!(
                "{}: the project root ({}) is not a folder",
                dir.display(),
                self.describe_source()
            )),
            _ => Ok(()),
        }
    }

    fn describe_source(&self) -> &'static str {
        match self.source {
            RootSource::Flag => "from --root",
            RootSource::Env => "from LIGHTGRAPH_ROOT",
            RootSource::CurrentDir => "the current directory",
            RootSource::BuiltIn => "none",
        }
    }

    /// One line: the root and why, or that only built-in files are used.
    pub fn describe(&self) -> String {
        match &self.root {
            Some(dir) => format!(
                "{} ({}); files not there are built in",
                dir.display(),
                self.describe_source()
            ),
            None => "none: the built-in shaders, graphs and materials".to_string(),
        }
    }

    /// Where project file `rel` (`graphs/forward_plus.ron`) is: `<root>/<rel>` if that
    /// file exists, else `<built-in>/<rel>` if built in, else `<root>/<rel>` (or `rel`
    /// with no root), which then fails to read with a message naming it.
    pub fn locate(&self, rel: &str) -> PathBuf {
        let on_disk = self.root.as_ref().map(|r| r.join(rel));
        match on_disk {
            Some(p) if p.is_file() => p,
            _ if builtin(rel).is_some() => builtin_path(rel),
            Some(p) => p,
            None => PathBuf::from(rel),
        }
    }

    /// Reads project file `rel`; returns the name it was read by (see [`Self::locate`]).
    pub fn read(&self, rel: &str) -> std::io::Result<(PathBuf, String)> {
        let path = self.locate(rel);
        read_path(&path).map(|text| (path, text))
    }

    /// The on-disk folder `name` ("shaders") under the root, if it exists.
    pub fn disk_folder(&self, name: &str) -> Option<PathBuf> {
        self.root
            .as_ref()
            .map(|r| r.join(name))
            .filter(|p| p.is_dir())
    }

    /// Where shader files are looked for first: `<root>/shaders`, or
    /// `<built-in>/shaders` with no root.
    pub(crate) fn shader_dir(&self) -> PathBuf {
        match &self.root {
            Some(r) => r.join("shaders"),
            None => builtin_path("shaders"),
        }
    }

    /// The files directly in folder `dir` ("graphs") with extension `ext`, on disk and
    /// built in, each by the name [`Self::locate`] gives, sorted by file name.
    pub fn list(&self, dir: &str, ext: &str) -> Vec<PathBuf> {
        let mut names: std::collections::BTreeSet<String> = builtin_files(dir)
            .into_iter()
            .filter(|r| r.matches('/').count() == 1)
            .filter_map(|r| r.rsplit('/').next().map(str::to_string))
            .collect();
        if let Some(folder) = self.disk_folder(dir) {
            if let Ok(entries) = std::fs::read_dir(folder) {
                for e in entries.flatten() {
                    if e.path().is_file() {
                        names.insert(e.file_name().to_string_lossy().into_owned());
                    }
                }
            }
        }
        names
            .into_iter()
            .filter(|n| Path::new(n).extension().is_some_and(|e| e == ext))
            .map(|n| self.locate(&format!("{dir}/{n}")))
            .collect()
    }

    /// Writes every file of folder `dir` ("shaders") to `dest`: the root's own files
    /// where it has them, the built-in ones for the rest.
    pub fn extract(&self, dir: &str, dest: &Path) -> std::io::Result<()> {
        let mut rels = builtin_files(dir);
        if let Some(folder) = self.disk_folder(dir) {
            disk_files(&folder, dir, &mut rels);
        }
        rels.sort();
        rels.dedup();
        for rel in rels {
            let (from, text) = self.read(&rel)?;
            let to = dest.join(rel.strip_prefix(&format!("{dir}/")).unwrap_or(&rel));
            if let Some(parent) = to.parent() {
                std::fs::create_dir_all(parent)?;
            }
            std::fs::write(&to, text).map_err(|e| {
                std::io::Error::new(
                    e.kind(),
                    format!("{} -> {}: {e}", from.display(), to.display()),
                )
            })?;
        }
        Ok(())
    }
}

/// Every file under `folder` as `prefix/relative/path`.
fn disk_files(folder: &Path, prefix: &str, out: &mut Vec<String>) {
    let Ok(entries) = std::fs::read_dir(folder) else {
        return;
    };
    for e in entries.flatten() {
        let name = format!("{prefix}/{}", e.file_name().to_string_lossy());
        if e.path().is_dir() {
            disk_files(&e.path(), &name, out);
        } else {
            out.push(name);
        }
    }
}

static CHOSEN: RwLock<Option<Project>> = RwLock::new(None);

/// Fixes the process's project (the CLI calls this once with what `--root` resolved to).
pub fn set_project(project: Project) {
    *CHOSEN.write().unwrap_or_else(|e| e.into_inner()) = Some(project);
}

/// Shorthand for `set_project(Project::resolve(flag))`.
pub fn set_root(flag: Option<&Path>) -> Project {
    let p = Project::resolve(flag);
    set_project(p.clone());
    p
}

/// The process's project: the one [`set_project`] fixed, else [`Project::resolve`]`(None)`.
pub fn project() -> Project {
    CHOSEN
        .read()
        .unwrap_or_else(|e| e.into_inner())
        .clone()
        .unwrap_or_else(|| Project::resolve(None))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_files_are_embedded() {
        assert!(builtin("shaders/common/types.wgsl").is_some());
        assert!(builtin("graphs/forward_plus.ron").is_some());
        assert!(builtin("materials/car_paint.ron").is_some());
        assert!(builtin("shaders/nope.wgsl").is_none());
        assert!(builtin("elsewhere/x").is_none());
        assert!(builtin_files("graphs").contains(&"graphs/forward_plus.ron".to_string()));
        assert!(builtin_files("shaders").contains(&"shaders/common/types.wgsl".to_string()));
    }

    #[test]
    fn disk_overrides_builtin_file_by_file() {
        let dir = std::env::temp_dir().join(format!("lightgraph-assets-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("graphs")).unwrap();
        std::fs::write(dir.join("graphs/forward_plus.ron"), "mine").unwrap();
        std::fs::write(dir.join("graphs/extra.ron"), "extra").unwrap();
        let p = Project::at(&dir, RootSource::Flag);
        let (path, text) = p.read("graphs/forward_plus.ron").unwrap();
        assert_eq!(
            (path, text.as_str()),
            (dir.join("graphs/forward_plus.ron"), "mine")
        );
        let (path, text) = p.read("graphs/brute_force.ron").unwrap();
        assert_eq!(path, builtin_path("graphs/brute_force.ron"));
        assert_eq!(Some(text.as_str()), builtin("graphs/brute_force.ron"));
        let listed = p.list("graphs", "ron");
        assert!(listed.contains(&dir.join("graphs/extra.ron")));
        assert!(listed.contains(&builtin_path("graphs/brute_force.ron")));
        assert!(p.read("graphs/missing.ron").is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
