//! What a [`FileWatcher`](super::FileWatcher) delivers, and how setting up a watch fails.

use super::normalize_path;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The final state of a changed file in a batch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ChangeKind {
    /// Created or modified; the file exists.
    Modified,
    /// The file is gone (and did not come back within the grace period).
    Removed,
}

/// A debounced, de-duplicated set of changed files.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ChangeBatch {
    /// Each changed file once, with its final state.
    pub changes: BTreeMap<PathBuf, ChangeKind>,
}

impl ChangeBatch {
    /// All changed paths, sorted.
    pub fn paths(&self) -> impl Iterator<Item = &Path> {
        self.changes.keys().map(PathBuf::as_path)
    }

    /// Paths that exist (created or modified).
    pub fn modified(&self) -> impl Iterator<Item = &Path> {
        self.of_kind(ChangeKind::Modified)
    }

    /// Paths that were removed.
    pub fn removed(&self) -> impl Iterator<Item = &Path> {
        self.of_kind(ChangeKind::Removed)
    }

    fn of_kind(&self, kind: ChangeKind) -> impl Iterator<Item = &Path> {
        self.changes
            .iter()
            .filter(move |(_, k)| **k == kind)
            .map(|(p, _)| p.as_path())
    }

    /// Whether `path` (normalised with [`normalize_path`]) is in the batch.
    pub fn contains(&self, path: impl AsRef<Path>) -> bool {
        let path = path.as_ref();
        self.changes.contains_key(path) || self.changes.contains_key(&normalize_path(path))
    }

    /// The state of `path` in this batch.
    pub fn kind(&self, path: impl AsRef<Path>) -> Option<ChangeKind> {
        let path = path.as_ref();
        self.changes
            .get(path)
            .or_else(|| self.changes.get(&normalize_path(path)))
            .copied()
    }

    /// Number of changed files.
    pub fn len(&self) -> usize {
        self.changes.len()
    }

    /// Whether the batch is empty.
    pub fn is_empty(&self) -> bool {
        self.changes.is_empty()
    }

    /// Fold a later batch into this one (the later state of a path wins).
    pub fn merge(&mut self, later: ChangeBatch) {
        self.changes.extend(later.changes);
    }
}

/// A watch could not be set up; names the path.
#[derive(Debug, thiserror::Error)]
pub enum WatchError {
    /// The path (or a file's parent directory) does not exist or cannot be resolved.
    #[error("{}: {source}", path.display())]
    Io {
        /// The path.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The OS watch failed (e.g. the inotify watch limit).
    #[error("{}: {source}", path.display())]
    Notify {
        /// The path.
        path: PathBuf,
        /// The notify error.
        #[source]
        source: notify::Error,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn batch_merge_later_wins() {
        let mut a = ChangeBatch::default();
        a.changes.insert("/x/a".into(), ChangeKind::Removed);
        a.changes.insert("/x/b".into(), ChangeKind::Modified);
        let mut b = ChangeBatch::default();
        b.changes.insert("/x/a".into(), ChangeKind::Modified);
        b.changes.insert("/x/c".into(), ChangeKind::Removed);
        a.merge(b);
        assert_eq!(a.len(), 3);
        assert_eq!(a.kind("/x/a"), Some(ChangeKind::Modified));
        assert_eq!(a.modified().count(), 2);
        assert_eq!(a.removed().collect::<Vec<_>>(), vec![Path::new("/x/c")]);
        assert!(a.contains("/x/b") && !a.contains("/x/d"));
    }
}
