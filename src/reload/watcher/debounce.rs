//! The watcher's debounce thread: events in, [`ChangeBatch`]es out.

use super::settle::Progress;
use super::{is_editor_temp_file, ChangeBatch, ChangeKind, WatchConfig};
use notify::event::{AccessKind, AccessMode, EventKind, ModifyKind, RenameMode};
use std::collections::{BTreeSet, HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// What is watched, and which files are known to exist (shared with the debounce thread).
#[derive(Debug, Default)]
pub(super) struct Shared {
    /// Recursively watched directories (canonical).
    pub(super) dirs: BTreeSet<PathBuf>,
    /// Individually watched files (canonical parent + name).
    pub(super) files: BTreeSet<PathBuf>,
    /// Directories registered with notify non-recursively (parents of watched files).
    pub(super) parent_dirs: BTreeSet<PathBuf>,
    /// Files under the watch known to exist (so a vanished one can be reported as removed).
    pub(super) known: HashSet<PathBuf>,
    /// Every directory registered with notify (`dirs` and `parent_dirs`), with how, and
    /// which directory was at that path when it was registered. The kernel watches a
    /// directory, not its path: one replaced, or moved away and back, is watched again.
    pub(super) identities: HashMap<PathBuf, (Option<DirId>, notify::RecursiveMode)>,
}

/// Which directory is at a path (device and inode), if any.
pub(super) type DirId = (u64, u64);

/// The directory at `path` now, if there is one.
pub(super) fn dir_id(path: &Path) -> Option<DirId> {
    let m = std::fs::metadata(path).ok().filter(|m| m.is_dir())?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        Some((m.dev(), m.ino()))
    }
    #[cfg(not(unix))]
    {
        let _ = m;
        Some((0, 0))
    }
}

impl Shared {
    /// Whether the directory registered for `path` (its root, or a watched file's parent)
    /// is still the one at that path: events from a directory moved away still carry the
    /// path it was registered under, and are not the live files'.
    fn still_registered(&self, path: &Path) -> bool {
        self.identities
            .iter()
            .filter(|(dir, (_, mode))| match mode {
                notify::RecursiveMode::Recursive => path.starts_with(dir),
                notify::RecursiveMode::NonRecursive => path.parent() == Some(dir.as_path()),
            })
            .all(|(dir, (id, _))| id.is_some() && dir_id(dir) == *id)
    }

    fn is_relevant(&self, path: &Path) -> bool {
        !is_editor_temp_file(path)
            && (self.files.contains(path) || self.dirs.iter().any(|d| path.starts_with(d)))
    }
}

pub(super) fn scan_dir(dir: &Path, out: &mut HashSet<PathBuf>) {
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

/// The debounce thread's state.
pub(super) struct Debouncer {
    pub(super) config: WatchConfig,
    pub(super) shared: Arc<Mutex<Shared>>,
    pub(super) shutdown: Arc<AtomicBool>,
    pub(super) events: Receiver<notify::Result<notify::Event>>,
    pub(super) batches: Sender<ChangeBatch>,
    /// Watched paths with events since the last batch, and whether they are saved.
    pub(super) pending: HashMap<PathBuf, Progress>,
    /// (first, last) event time of the current burst.
    pub(super) burst: Option<(Instant, Instant)>,
    /// Empty or vanished files held back, with their deadline.
    pub(super) held: HashMap<PathBuf, Instant>,
    /// The notify watcher, to register a watched directory again where it was replaced
    /// (`None` once the [`super::FileWatcher`] is dropped).
    pub(super) watcher: Arc<Mutex<Option<notify::RecommendedWatcher>>>,
}

/// Longest the thread sleeps before checking for shutdown.
const SHUTDOWN_POLL: Duration = Duration::from_millis(100);

impl Debouncer {
    /// When the current burst's batch is cut: [`WatchConfig::settle`] after the last
    /// event if every path in it is saved, else [`WatchConfig::debounce`] after it; at
    /// the latest `max_latency` after the first.
    fn burst_deadline(&self) -> Option<Instant> {
        let (first, last) = self.burst?;
        let quiet = if self.pending.values().all(Progress::is_complete) {
            self.config.settle.min(self.config.debounce)
        } else {
            self.config.debounce
        };
        Some((last + quiet).min(first + self.config.max_latency))
    }

    pub(super) fn run(mut self) {
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
            self.follow_paths();
            self.evaluate(Instant::now());
        }
    }

    /// Registers again every watched directory whose path now holds another directory (or
    /// none): the old registration followed the directory, not the path. Every file under
    /// it, known before or found now, is re-checked as after lost events.
    pub(super) fn follow_paths(&mut self) {
        let stale: Vec<(PathBuf, notify::RecursiveMode)> = {
            let shared = self.shared.lock().unwrap();
            shared
                .identities
                .iter()
                .filter(|(dir, (id, _))| dir_id(dir) != *id)
                .map(|(dir, (_, mode))| (dir.clone(), *mode))
                .collect()
        };
        if stale.is_empty() {
            return;
        }
        let mut watcher = self.watcher.lock().unwrap();
        let mut shared = self.shared.lock().unwrap();
        for (dir, mode) in stale {
            let mut id = None;
            if let Some(w) = watcher.as_mut() {
                use notify::Watcher;
                // The old directory's watch, wherever it went (an error where the kernel
                // already dropped it with the directory).
                let _ = w.unwatch(&dir);
                id = dir_id(&dir);
                if id.is_some() {
                    if let Err(e) = w.watch(&dir, mode) {
                        log::warn!("file watcher: {}: {e}", dir.display());
                        id = None;
                    }
                }
                // Registered while it changed again: checked once more on the next round.
                if id != dir_id(&dir) {
                    id = None;
                }
            }
            shared.identities.insert(dir.clone(), (id, mode));
            let mut found = HashSet::new();
            match mode {
                notify::RecursiveMode::Recursive => scan_dir(&dir, &mut found),
                notify::RecursiveMode::NonRecursive => found.extend(
                    shared
                        .files
                        .iter()
                        .filter(|f| f.parent() == Some(&dir))
                        .cloned(),
                ),
            }
            let under = |p: &PathBuf| match mode {
                notify::RecursiveMode::Recursive => p.starts_with(&dir),
                notify::RecursiveMode::NonRecursive => p.parent() == Some(dir.as_path()),
            };
            found.extend(shared.known.iter().filter(|p| under(p)).cloned());
            let now = Instant::now();
            for path in found {
                if shared.is_relevant(&path) {
                    self.pending.insert(path, Progress::UNKNOWN);
                    self.burst = Some(match self.burst {
                        Some((first, _)) => (first, now),
                        None => (now, now),
                    });
                }
            }
        }
    }

    fn on_event(&mut self, event: notify::Event) {
        let now = Instant::now();
        let shared = self.shared.lock().unwrap();
        let mut touched = false;
        if event.need_rescan() {
            // Events were lost: every file may have changed, and how far its writer got
            // is unknown, so the batch waits for the debounce.
            let mut found = HashSet::new();
            for d in &shared.dirs {
                scan_dir(d, &mut found);
            }
            let all = found
                .into_iter()
                .chain(shared.known.iter().cloned())
                .chain(shared.files.iter().cloned());
            for path in all {
                self.pending.insert(path, Progress::UNKNOWN);
                touched = true;
            }
        }
        let ignored = match event.kind {
            EventKind::Access(AccessKind::Close(AccessMode::Write)) => false,
            // Opening, reading and closing without writing change nothing.
            EventKind::Access(_) | EventKind::Other => true,
            // inotify's rename pair, after the From and To events that say the same: when
            // it arrives after the batch was cut (the notify thread losing its core between
            // the two), it would name the renamed file again in a batch of its own.
            EventKind::Modify(ModifyKind::Name(RenameMode::Both)) => true,
            _ => false,
        };
        if !ignored {
            // Editors' temp files and unwatched siblings of watched files neither reach a
            // batch nor hold one back (a swap file kept open must not).
            for path in event.paths {
                if shared.is_relevant(&path) && shared.still_registered(&path) {
                    let known = shared.known.contains(&path);
                    self.pending.entry(path).or_default().on(&event.kind, known);
                    touched = true;
                }
            }
        }
        drop(shared);
        if touched {
            self.burst = Some(match self.burst {
                Some((first, _)) => (first, now),
                None => (now, now),
            });
        }
    }

    /// Cut a batch if the burst is over, and release held files whose grace ran out.
    fn evaluate(&mut self, now: Instant) {
        let burst_over = self.burst_deadline().is_some_and(|d| now >= d);
        let mut candidates: Vec<PathBuf> = Vec::new();
        if burst_over {
            candidates.extend(self.pending.drain().map(|(path, _)| path));
            self.burst = None;
        }
        let expired: Vec<PathBuf> = self
            .held
            .iter()
            .filter(|(p, d)| now >= **d && !self.pending.contains_key(*p))
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
    use notify::event::DataChange;
    use std::sync::mpsc::{self, Receiver};

    /// A debounce thread's state over a temp dir holding `lit.wgsl`, driven by hand.
    fn debouncer() -> (tempfile::TempDir, PathBuf, Debouncer, Receiver<ChangeBatch>) {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().canonicalize().unwrap();
        std::fs::write(root.join("lit.wgsl"), "// v1\n").unwrap();
        let mut shared = Shared::default();
        shared.dirs.insert(root.clone());
        scan_dir(&root, &mut shared.known);
        let (batch_tx, batches) = mpsc::channel();
        let d = Debouncer {
            config: WatchConfig::default(),
            shared: Arc::new(Mutex::new(shared)),
            shutdown: Arc::new(AtomicBool::new(false)),
            events: mpsc::channel().1,
            batches: batch_tx,
            pending: HashMap::new(),
            burst: None,
            held: HashMap::new(),
            watcher: Arc::new(Mutex::new(None)),
        };
        (dir, root, d, batches)
    }

    fn event(kind: EventKind, paths: &[&Path]) -> notify::Event {
        paths
            .iter()
            .fold(notify::Event::new(kind), |e, p| e.add_path(p.to_path_buf()))
    }

    /// Evaluates as the thread would once `after` has passed since now.
    fn evaluate_after(d: &mut Debouncer, after: Duration) {
        d.evaluate(Instant::now() + after);
    }

    #[test]
    fn a_saved_file_is_cut_after_the_settle_time_a_written_one_after_the_debounce() {
        let (_dir, root, mut d, batches) = debouncer();
        let lit = root.join("lit.wgsl");
        let WatchConfig {
            settle, debounce, ..
        } = d.config;
        let write = EventKind::Modify(ModifyKind::Data(DataChange::Any));
        d.on_event(event(write, &[&lit]));
        evaluate_after(&mut d, settle * 2);
        assert!(batches.try_recv().is_err(), "cut while open for writing");
        evaluate_after(&mut d, debounce * 2);
        assert!(batches.try_recv().unwrap().contains(&lit), "the debounce");
        d.on_event(event(write, &[&lit]));
        d.on_event(event(
            EventKind::Access(AccessKind::Close(AccessMode::Write)),
            &[&lit],
        ));
        evaluate_after(&mut d, settle / 2);
        assert!(batches.try_recv().is_err(), "cut within the settle time");
        evaluate_after(&mut d, settle * 2);
        assert!(
            batches.try_recv().unwrap().contains(&lit),
            "the settle time"
        );
    }

    #[test]
    fn a_late_rename_pair_does_not_name_the_file_again() {
        let (_dir, root, mut d, batches) = debouncer();
        let lit = root.join("lit.wgsl");
        let tmp = root.join("xq7z");
        let WatchConfig {
            settle, debounce, ..
        } = d.config;
        let name = |mode| EventKind::Modify(ModifyKind::Name(mode));
        d.on_event(event(name(RenameMode::From), &[&tmp]));
        d.on_event(event(name(RenameMode::To), &[&lit]));
        evaluate_after(&mut d, settle * 2);
        let b = batches.try_recv().unwrap();
        assert_eq!(b.paths().collect::<Vec<_>>(), vec![lit.as_path()]);
        d.on_event(event(name(RenameMode::Both), &[&tmp, &lit]));
        evaluate_after(&mut d, debounce * 2);
        assert!(
            batches.try_recv().is_err(),
            "the rename pair named it again"
        );
    }
}
