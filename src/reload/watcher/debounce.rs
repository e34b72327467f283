//! The watcher's debounce thread: events in, [`ChangeBatch`]es out.

use super::settle::Progress;
use super::{is_editor_temp_file, ChangeBatch, ChangeKind, WatchConfig};
use notify::event::{AccessKind, AccessMode, EventKind};
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
}

impl Shared {
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
            self.evaluate(Instant::now());
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
        // Opening, reading and closing without writing change nothing.
        let ignored = match event.kind {
            EventKind::Access(AccessKind::Close(AccessMode::Write)) => false,
            EventKind::Access(_) | EventKind::Other => true,
            _ => false,
        };
        if !ignored {
            // Editors' temp files and unwatched siblings of watched files neither reach a
            // batch nor hold one back (a swap file kept open must not).
            for path in event.paths {
                if shared.is_relevant(&path) {
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
