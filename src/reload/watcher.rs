//! A debounced, editor-proof file watcher on top of `notify`.
//!
//! # What it reports
//! [`FileWatcher`] watches directories (recursively) and individual files, and delivers
//! [`ChangeBatch`]es: each names a changed file at most once, with its final state
//! ([`ChangeKind::Modified`] or [`ChangeKind::Removed`]). Paths are absolute with symlinks resolved
//! (see [`normalize_path`]), based on the canonical form of the watched path.
//!
//! # How editors save, and how each is handled
//! - **In place** (write + close): ordinary modify events, debounced into one batch.
//! - **Write a temp file, rename it over the target** (vim `backupcopy=no`, JetBrains, gedit,
//!   most atomic-write libraries): the temp file is ignored (see [`is_editor_temp_file`], and a
//!   path that appears and vanishes within one debounce window is dropped because it was never a
//!   known file); the rename's destination is reported as modified.
//! - **Truncate, then write**: a file that is *empty* when a batch is evaluated is **held back**
//!   until an event shows it has content, or until [`WatchConfig::grace`] passes with no further
//!   event, after which the empty file is reported (emptying a file on purpose is an edit too).
//!   So the engine never sees a half-saved empty shader as a breaking edit.
//! - **Delete, then recreate**: the same hold-back applies to a known file that has vanished:
//!   if it reappears within the grace period it is reported once as modified, otherwise as
//!   removed. Files are watched through their parent directory, never by inode, so the watch
//!   survives the file being replaced.
//!
//! Batches are cut when no event arrived for [`WatchConfig::debounce`] (or at the latest
//! `max_latency` after the first event of a burst). Access events (open, read, close without
//! writing) are ignored, so the engine reading a file does not trigger a reload.
//!
//! # Limits
//! - Deleting and recreating a *watched directory root* ends its watch (inotify watches
//!   directories by inode); watch its parent instead.
//! - A directory moved or copied into a watched tree reports files created in it after the move;
//!   files that came inside it are reported only when they are next touched (inotify cannot add
//!   the new directory's watch atomically).
//! - On a kernel event-queue overflow every known file under the roots is re-checked and reported.

use notify::event::{AccessKind, AccessMode, EventKind};
use notify::{RecursiveMode, Watcher};
use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Timing of a [`FileWatcher`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WatchConfig {
    /// Quiet time after the last event before a batch is cut. Default 20 ms: every
    /// editor save style in `tests/reload_watcher.rs` passes down to 5 ms on a loaded
    /// 2-core machine (at 2 ms a burst of writes is split and a file named twice);
    /// 20 ms leaves room for a writer descheduled mid-save and is a small part of the
    /// edit-to-frame latency (see `lightgraph reload-bench`).
    pub debounce: Duration,
    /// Longest a burst of events can delay a batch. Default 1 s.
    pub max_latency: Duration,
    /// How long an empty or vanished file is held back waiting for content / to reappear.
    /// Default 1 s.
    pub grace: Duration,
}

impl WatchConfig {
    /// The default [`debounce`](Self::debounce).
    pub const DEFAULT_DEBOUNCE: Duration = Duration::from_millis(20);
}

impl Default for WatchConfig {
    fn default() -> Self {
        Self {
            debounce: Self::DEFAULT_DEBOUNCE,
            max_latency: Duration::from_secs(1),
            grace: Duration::from_secs(1),
        }
    }
}

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

/// What is watched, and which files are known to exist (shared with the debounce thread).
#[derive(Debug, Default)]
struct Shared {
    /// Recursively watched directories (canonical).
    dirs: BTreeSet<PathBuf>,
    /// Individually watched files (canonical parent + name).
    files: BTreeSet<PathBuf>,
    /// Directories registered with notify non-recursively (parents of watched files).
    parent_dirs: BTreeSet<PathBuf>,
    /// Files under the watch known to exist (so a vanished one can be reported as removed).
    known: HashSet<PathBuf>,
}

impl Shared {
    fn is_relevant(&self, path: &Path) -> bool {
        !is_editor_temp_file(path)
            && (self.files.contains(path) || self.dirs.iter().any(|d| path.starts_with(d)))
    }
}

fn scan_dir(dir: &Path, out: &mut HashSet<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        match e.file_type() {
            Ok(t) if t.is_dir() => scan_dir(&p, out),
            Ok(_) => {
                if !is_editor_temp_file(&p) {
                    out.insert(p);
                }
            }
            Err(_) => {}
        }
    }
}

/// Watches files and directories and delivers debounced [`ChangeBatch`]es.
/// See the [module documentation](self) for the save styles it handles.
pub struct FileWatcher {
    watcher: Option<notify::RecommendedWatcher>,
    shared: Arc<Mutex<Shared>>,
    batches: Receiver<ChangeBatch>,
    shutdown: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl std::fmt::Debug for FileWatcher {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let shared = self.shared.lock().unwrap();
        f.debug_struct("FileWatcher")
            .field("dirs", &shared.dirs)
            .field("files", &shared.files)
            .finish_non_exhaustive()
    }
}

impl FileWatcher {
    /// Start a watcher (and its debounce thread) watching nothing yet.
    pub fn new(config: WatchConfig) -> Result<Self, WatchError> {
        let (event_tx, event_rx) = mpsc::channel();
        let watcher =
            notify::recommended_watcher(event_tx).map_err(|source| WatchError::Notify {
                path: PathBuf::new(),
                source,
            })?;
        let (batch_tx, batches) = mpsc::channel();
        let shared = Arc::new(Mutex::new(Shared::default()));
        let shutdown = Arc::new(AtomicBool::new(false));
        let thread = {
            let debouncer = Debouncer {
                config,
                shared: shared.clone(),
                shutdown: shutdown.clone(),
                events: event_rx,
                batches: batch_tx,
                pending: HashSet::new(),
                burst: None,
                held: HashMap::new(),
            };
            std::thread::Builder::new()
                .name("lightgraph-watch".into())
                .spawn(move || debouncer.run())
                .map_err(|source| WatchError::Io {
                    path: PathBuf::new(),
                    source,
                })?
        };
        Ok(Self {
            watcher: Some(watcher),
            shared,
            batches,
            shutdown,
            thread: Some(thread),
        })
    }

    /// Watch a directory (recursively) or a single file, and return the normalised path that
    /// batches will use for it. A file need not exist yet, but its parent directory must; a file
    /// is watched through its parent directory so replacing it never ends the watch.
    pub fn watch(&mut self, path: impl AsRef<Path>) -> Result<PathBuf, WatchError> {
        let path = path.as_ref();
        let io_err = |source| WatchError::Io {
            path: path.to_path_buf(),
            source,
        };
        let watcher = self.watcher.as_mut().expect("watcher lives until drop");
        let notify_err = |source| WatchError::Notify {
            path: path.to_path_buf(),
            source,
        };
        match path.canonicalize() {
            Ok(dir) if dir.is_dir() => {
                let mut shared = self.shared.lock().unwrap();
                if !shared.dirs.iter().any(|d| dir.starts_with(d)) {
                    watcher
                        .watch(&dir, RecursiveMode::Recursive)
                        .map_err(notify_err)?;
                    shared.dirs.retain(|d| !d.starts_with(&dir));
                    shared.dirs.insert(dir.clone());
                }
                let mut found = HashSet::new();
                scan_dir(&dir, &mut found);
                shared.known.extend(found);
                Ok(dir)
            }
            result => {
                let name = path.file_name().ok_or_else(|| {
                    io_err(std::io::Error::new(
                        std::io::ErrorKind::InvalidInput,
                        "not a file or directory name",
                    ))
                })?;
                let file = match result {
                    Ok(canonical) => canonical,
                    Err(_) => {
                        let parent = match path.parent() {
                            Some(p) if !p.as_os_str().is_empty() => p,
                            _ => Path::new("."),
                        };
                        parent.canonicalize().map_err(io_err)?.join(name)
                    }
                };
                let parent = file
                    .parent()
                    .expect("canonical file has a parent")
                    .to_path_buf();
                let mut shared = self.shared.lock().unwrap();
                let covered = shared.dirs.iter().any(|d| parent.starts_with(d));
                if !covered && !shared.parent_dirs.contains(&parent) {
                    watcher
                        .watch(&parent, RecursiveMode::NonRecursive)
                        .map_err(notify_err)?;
                    shared.parent_dirs.insert(parent);
                }
                if file.is_file() {
                    shared.known.insert(file.clone());
                }
                shared.files.insert(file.clone());
                Ok(file)
            }
        }
    }

    /// Wait at most `timeout` for the next batch.
    pub fn wait_for_change(&self, timeout: Duration) -> Option<ChangeBatch> {
        self.batches.recv_timeout(timeout).ok()
    }

    /// The next batch if one is ready.
    pub fn try_next(&self) -> Option<ChangeBatch> {
        self.batches.try_recv().ok()
    }

    /// All batches ready now, merged into one (`None` if there are none).
    pub fn drain(&self) -> Option<ChangeBatch> {
        let mut out: Option<ChangeBatch> = None;
        while let Ok(b) = self.batches.try_recv() {
            match &mut out {
                Some(o) => o.merge(b),
                None => out = Some(b),
            }
        }
        out
    }
}

impl Drop for FileWatcher {
    fn drop(&mut self) {
        self.shutdown.store(true, Ordering::Relaxed);
        drop(self.watcher.take());
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The debounce thread's state.
struct Debouncer {
    config: WatchConfig,
    shared: Arc<Mutex<Shared>>,
    shutdown: Arc<AtomicBool>,
    events: Receiver<notify::Result<notify::Event>>,
    batches: Sender<ChangeBatch>,
    /// Paths with events since the last batch.
    pending: HashSet<PathBuf>,
    /// (first, last) event time of the current burst.
    burst: Option<(Instant, Instant)>,
    /// Empty or vanished files held back, with their deadline.
    held: HashMap<PathBuf, Instant>,
}

/// Longest the thread sleeps before checking for shutdown.
const SHUTDOWN_POLL: Duration = Duration::from_millis(100);

impl Debouncer {
    fn burst_deadline(&self) -> Option<Instant> {
        self.burst
            .map(|(first, last)| (last + self.config.debounce).min(first + self.config.max_latency))
    }

    fn run(mut self) {
        while !self.shutdown.load(Ordering::Relaxed) {
            let now = Instant::now();
            let mut wake = now + SHUTDOWN_POLL;
            if let Some(d) = self.burst_deadline() {
                wake = wake.min(d);
            }
            if let Some(d) = self.held.values().min() {
                wake = wake.min(*d);
            }
            match self
                .events
                .recv_timeout(wake.saturating_duration_since(now))
            {
                Ok(Ok(event)) => self.on_event(event),
                Ok(Err(e)) => log::warn!("file watcher: {e}"),
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => break,
            }
            self.evaluate(Instant::now());
        }
    }

    fn on_event(&mut self, event: notify::Event) {
        let now = Instant::now();
        if event.need_rescan() {
            let shared = self.shared.lock().unwrap();
            let mut found = HashSet::new();
            for d in &shared.dirs {
                scan_dir(d, &mut found);
            }
            self.pending.extend(found);
            self.pending.extend(shared.known.iter().cloned());
            self.pending.extend(shared.files.iter().cloned());
        }
        match event.kind {
            EventKind::Access(AccessKind::Close(AccessMode::Write)) => {}
            EventKind::Access(_) | EventKind::Other => return,
            _ => {}
        }
        if event.paths.is_empty() {
            return;
        }
        self.pending.extend(event.paths);
        self.burst = Some(match self.burst {
            Some((first, _)) => (first, now),
            None => (now, now),
        });
    }

    /// Cut a batch if the burst is over, and release held files whose grace ran out.
    fn evaluate(&mut self, now: Instant) {
        let burst_over = self.burst_deadline().is_some_and(|d| now >= d);
        let mut candidates: Vec<PathBuf> = Vec::new();
        if burst_over {
            candidates.extend(self.pending.drain());
            self.burst = None;
        }
        let expired: Vec<PathBuf> = self
            .held
            .iter()
            .filter(|(p, d)| now >= **d && !self.pending.contains(*p))
            .map(|(p, _)| p.clone())
            .collect();
        candidates.extend(expired);
        if candidates.is_empty() {
            return;
        }
        let mut batch = ChangeBatch::default();
        let mut shared = self.shared.lock().unwrap();
        for path in candidates {
            if !shared.is_relevant(&path) {
                continue;
            }
            let grace_over = self.held.get(&path).is_some_and(|d| now >= *d);
            match std::fs::metadata(&path) {
                Ok(m) if m.is_dir() => {}
                Ok(m) if m.len() == 0 && !grace_over => {
                    // Truncated and not yet rewritten: wait for content (or the grace period).
                    shared.known.insert(path.clone());
                    self.held.entry(path).or_insert(now + self.config.grace);
                }
                Ok(_) => {
                    self.held.remove(&path);
                    shared.known.insert(path.clone());
                    batch.changes.insert(path, ChangeKind::Modified);
                }
                Err(_) if !shared.known.contains(&path) => {
                    // Never seen as a file (a temp file that came and went): nothing to report.
                    self.held.remove(&path);
                }
                Err(_) if !grace_over => {
                    // Deleted, maybe about to be recreated: wait for the grace period.
                    self.held.entry(path).or_insert(now + self.config.grace);
                }
                Err(_) => {
                    self.held.remove(&path);
                    shared.known.remove(&path);
                    batch.changes.insert(path, ChangeKind::Removed);
                }
            }
        }
        drop(shared);
        if !batch.is_empty() {
            let _ = self.batches.send(batch);
        }
    }
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
