//! Path helpers of the watcher: editors' temporary files, normalised paths.

use std::path::{Component, Path, PathBuf};

/// Whether `path`'s file name is an editor's or tool's temporary / backup / lock file, never a
/// source file: `*~`, `.#*`, `#*#` (Emacs), `*.swp`/`*.swo`/`*.swx`/`*.swpx` and `4913` (Vim),
/// `*.tmp`, `*.temp`, `*.bak`, `*.kate-swp`, `*___jb_tmp___`/`*___jb_old___` (JetBrains),
/// `.goutputstream-*` (GIO), `.tmp*` (Rust `tempfile`), `sedXXXXXX` (`sed -i`).
pub fn is_editor_temp_file(path: &Path) -> bool {
    let Some(name) = path.file_name().and_then(|n| n.to_str()) else {
        return false;
    };
    let lower = name.to_ascii_lowercase();
    name.ends_with('~')
        || name.starts_with(".#")
        || (name.len() > 1 && name.starts_with('#') && name.ends_with('#'))
        || name == "4913"
        || [
            ".swp",
            ".swo",
            ".swx",
            ".swpx",
            ".tmp",
            ".temp",
            ".bak",
            ".kate-swp",
        ]
        .iter()
        .any(|ext| lower.ends_with(ext))
        || name.ends_with("___jb_tmp___")
        || name.ends_with("___jb_old___")
        || name.starts_with(".goutputstream-")
        || name.starts_with(".tmp")
        || (name.len() == 9
            && name.starts_with("sed")
            && name[3..].chars().all(|c| c.is_ascii_alphanumeric()))
}

/// Absolute form of `path` with symlinks resolved where possible: the canonical path if it
/// exists; else the canonical parent joined with the file name; else `path` made absolute
/// against the current directory with `.` and `..` removed lexically.
pub fn normalize_path(path: &Path) -> PathBuf {
    if let Ok(p) = path.canonicalize() {
        return p;
    }
    if let (Some(parent), Some(name)) = (path.parent(), path.file_name()) {
        let parent = if parent.as_os_str().is_empty() {
            Path::new(".")
        } else {
            parent
        };
        if let Ok(p) = parent.canonicalize() {
            return p.join(name);
        }
    }
    let abs = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir()
            .unwrap_or_else(|_| PathBuf::from("/"))
            .join(path)
    };
    let mut out = PathBuf::new();
    for c in abs.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn editor_temp_files() {
        for name in [
            "a.wgsl~",
            ".#a.wgsl",
            "#a.wgsl#",
            ".a.wgsl.swp",
            "a.wgsl.SWO",
            "4913",
            "a.wgsl.tmp",
            "a.bak",
            "a.wgsl___jb_tmp___",
            "a.wgsl___jb_old___",
            ".goutputstream-ABC123",
            ".tmpXyZ123",
            "sedA1b2C3",
            ".a.wgsl.kate-swp",
        ] {
            assert!(is_editor_temp_file(Path::new(name)), "{name}");
        }
        for name in [
            "a.wgsl",
            "forward_plus.ron",
            "#include.wgsl",
            "sed.wgsl",
            "4914",
            "tmp.wgsl",
        ] {
            assert!(!is_editor_temp_file(Path::new(name)), "{name}");
        }
    }

    #[test]
    fn normalize_is_lexical_for_missing_paths() {
        let cwd = std::env::current_dir().unwrap().canonicalize().unwrap();
        assert_eq!(
            normalize_path(Path::new("no/such/./dir/../file.wgsl")),
            cwd.join("no/such/file.wgsl")
        );
        assert_eq!(
            normalize_path(Path::new("Cargo.toml")),
            cwd.join("Cargo.toml")
        );
    }
}
