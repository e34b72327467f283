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
//! # When a batch is cut
//! A burst whose every file is known to be saved (closed after writing, renamed into place,
//! removed, or only its metadata changed) is cut [`WatchConfig::settle`] (5 ms) after its
//! last event: a save delivers in a few milliseconds. Otherwise the batch waits until no
//! event arrived for [`WatchConfig::debounce`] (20 ms): a write without a close yet (a slow
//! writer between chunks, an mmap writer, a tool that keeps the file open), a file created
//! in the burst that the watcher did not know (maybe an atomic save's temp file with a plain
//! name, about to be renamed), and events the watcher cannot read (an overflow's rescan;
//! platforms without close events, where every batch waits for the debounce). At the latest
//! a batch is cut `max_latency` after the first event of a burst. Access events (open, read,
//! close without writing) are ignored, so the engine reading a file does not trigger a
//! reload; editors' temp files and unwatched siblings of watched files neither reach a
//! batch nor hold one back.
//!
//! Saves separated by a pause longer than `settle` are separate batches: a tool rewriting
//! several files with such pauses between them has its burst split (each batch still
//! names files whose writers have closed them), where the debounce alone would have
//! joined them.
//!
//! # Folders followed by path
//! The kernel watches a directory, not its path. A watched directory (a root, or a
//! watched file's parent) that is replaced, recreated, or moved away and back is found by
//! its path again: the debounce thread checks each one's device and inode on every round
//! (at least every 100 ms) and registers the directory now at the path, re-checking every
//! file under it. Events from a directory no longer at its path (a moved-away copy, whose
//! events still carry the old path) are dropped, so they are never reported as the live
//! file.
//!
//! # Limits
//! - A directory moved or copied into a watched tree reports files created in it after the move;
//!   files that came inside it are reported only when they are next touched (inotify cannot add
//!   the new directory's watch atomically).
//! - On a kernel event-queue overflow every known file under the roots is re-checked and reported.
//!
//! The parts: [`ChangeBatch`] and errors (`batch`), path helpers (`paths`), what a burst's
//! events say about a file being saved (`settle`), the debounce thread (`debounce`);
//! [`FileWatcher`] here ties them together.

mod batch;
mod debounce;
mod paths;
mod settle;

pub use batch::{ChangeBatch, ChangeKind, WatchError};
pub use paths::{is_editor_temp_file, normalize_path};

use debounce::{scan_dir, Debouncer, Shared};
use notify::{RecursiveMode, Watcher};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

/// Timing of a [`FileWatcher`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WatchConfig {
    /// Quiet time after the last event before a batch is cut. Default 20 ms: every
    /// editor save style in `tests/reload_watcher.rs` passes down to 5 ms on a loaded
    /// 2-core machine (at 2 ms a burst of writes is split and a file named twice);
    /// 20 ms leaves room for a writer descheduled mid-save and is a small part of the
    /// edit-to-frame latency (see `lightgraph reload-bench`).
    pub debounce: Duration,
    /// Quiet time after the last event before a batch is cut when every file in it is
    /// known to be saved (closed after writing, renamed into place, removed). Default
    /// [`DEFAULT_SETTLE`](Self::DEFAULT_SETTLE); `debounce` if that is shorter.
    pub settle: Duration,
    /// Longest a burst of events can delay a batch. Default 1 s.
    pub max_latency: Duration,
    /// How long an empty or vanished file is held back waiting for content / to reappear.
    /// Default 1 s.
    pub grace: Duration,
}

impl WatchConfig {
    /// The default [`debounce`](Self::debounce).
    pub const DEFAULT_DEBOUNCE: Duration = Duration::from_millis(20);
    /// The default [`settle`](Self::settle), 5 ms: long enough to join the steps of one
    /// save that each look complete (an atomic save's rename, then the chmod that keeps
    /// the file's mode; "save all" writing one file after another), a quarter of the
    /// debounce. `event_traces` in `tests/reload_watcher.rs` measured those pauses on a
    /// 2-core Linux machine, 500 saves each: with load ~1-4 a median of 0.27 ms (rename, chmod;
    /// at most 0.7 ms) and 0.13 ms (two files; 1 over 5 ms); loaded ~8 deep, 0.4 ms and
    /// 2.4 ms (the writer loses its core when its close wakes the watcher), 6% and 13%
    /// over 5 ms, none over 20 ms. A split burst costs one more batch, whose files are
    /// still whole.
    pub const DEFAULT_SETTLE: Duration = Duration::from_millis(5);
}

impl Default for WatchConfig {
    fn default() -> Self {
        Self {
            debounce: Self::DEFAULT_DEBOUNCE,
            settle: Self::DEFAULT_SETTLE,
            max_latency: Duration::from_secs(1),
            grace: Duration::from_secs(1),
        }
    }
}

/// Watches files and directories and delivers debounced [`ChangeBatch`]es.
/// See the [module documentation](self) for the save styles it handles.
pub struct FileWatcher {
    /// Shared with the debounce thread, which registers replaced directories again.
    watcher: Arc<Mutex<Option<notify::RecommendedWatcher>>>,
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
        let watcher = Arc::new(Mutex::new(Some(watcher)));
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
                pending: HashMap::new(),
                burst: None,
                held: HashMap::new(),
                watcher: watcher.clone(),
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
            watcher,
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
        let mut watcher = self.watcher.lock().unwrap();
        let watcher = watcher.as_mut().expect("watcher lives until drop");
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
                    // Roots now inside this one are covered by its watch.
                    shared.identities.retain(|d, _| !d.starts_with(&dir));
                    shared.identities.insert(
                        dir.clone(),
                        (debounce::dir_id(&dir), RecursiveMode::Recursive),
                    );
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
                    shared.identities.insert(
                        parent.clone(),
                        (debounce::dir_id(&parent), RecursiveMode::NonRecursive),
                    );
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
        drop(self.watcher.lock().unwrap().take());
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
