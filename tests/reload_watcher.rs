//! The file watcher against every way editors save. Bounded waits only: presence is awaited up to
//! `PRESENT`, absence is checked by waiting a few debounce periods for a batch that must not come.

use lightgraph::reload::{ChangeBatch, ChangeKind, FileWatcher, WatchConfig};
use std::collections::HashSet;
use std::fs::{self, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The default debounce: the save styles below must work with what sessions use.
const DEBOUNCE: Duration = WatchConfig::DEFAULT_DEBOUNCE;
const GRACE: Duration = Duration::from_millis(1000);
/// Upper bound for an expected batch to arrive (generous: CI machines are slow).
const PRESENT: Duration = Duration::from_secs(10);
/// How long to wait to be confident no (further) batch is coming: several debounce periods,
/// still well inside the grace period.
const ABSENT: Duration = Duration::from_millis(400);

fn config() -> WatchConfig {
    WatchConfig {
        debounce: DEBOUNCE,
        settle: WatchConfig::DEFAULT_SETTLE,
        max_latency: Duration::from_secs(1),
        grace: GRACE,
    }
}

struct Fixture {
    _dir: tempfile::TempDir,
    root: PathBuf,
    watcher: FileWatcher,
}

/// A temp dir holding `shaders/lit.wgsl` and `shaders/common.wgsl`, watched recursively.
fn fixture() -> Fixture {
    fixture_with(config())
}

/// [`fixture`] with the watcher's timing given.
fn fixture_with(config: WatchConfig) -> Fixture {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().canonicalize().unwrap();
    fs::create_dir(root.join("shaders")).unwrap();
    fs::write(root.join("shaders/lit.wgsl"), "// v1\n").unwrap();
    fs::write(root.join("shaders/common.wgsl"), "// common\n").unwrap();
    let mut watcher = FileWatcher::new(config).unwrap();
    let watched = watcher.watch(root.join("shaders")).unwrap();
    assert_eq!(watched, root.join("shaders"));
    Fixture {
        _dir: dir,
        root,
        watcher,
    }
}

/// Wait (bounded) until batches have named every path in `expected`, and assert that each is
/// named in exactly one batch, that no other path is named, and that `path` ends as `kind`;
/// then that no further batch comes. Usually all arrive in one batch; a slow (loaded) machine may
/// split a burst, which is still correct as long as no path is reported twice.
fn expect_once(w: &FileWatcher, path: &Path, kind: ChangeKind, expected: &[&Path]) -> ChangeBatch {
    let deadline = Instant::now() + PRESENT;
    let mut merged = ChangeBatch::default();
    let mut batches = Vec::new();
    while !expected.iter().all(|p| merged.contains(p)) {
        let left = deadline.saturating_duration_since(Instant::now());
        let Some(b) = w.wait_for_change(left) else {
            panic!("not all of {expected:?} named within {PRESENT:?}; saw {batches:?}",);
        };
        for p in b.paths() {
            assert!(
                expected.contains(&p),
                "unexpected path {} in {b:?}",
                p.display()
            );
            assert!(
                !merged.contains(p),
                "{} named twice: {batches:?} then {b:?}",
                p.display()
            );
        }
        merged.merge(b.clone());
        batches.push(b);
    }
    assert_eq!(merged.kind(path), Some(kind), "{batches:?}");
    expect_quiet(w);
    merged
}

fn expect_quiet(w: &FileWatcher) {
    if let Some(b) = w.wait_for_change(ABSENT) {
        panic!("unexpected batch {b:?}");
    }
}

fn read(p: &Path) -> String {
    fs::read_to_string(p).unwrap()
}

#[test]
fn in_place_write() {
    let f = fixture();
    let lit = f.root.join("shaders/lit.wgsl");
    let mut file = OpenOptions::new().write(true).open(&lit).unwrap();
    file.write_all(b"// v2\n").unwrap();
    file.write_all(b"fn main() {}\n").unwrap();
    drop(file);
    expect_once(&f.watcher, &lit, ChangeKind::Modified, &[&lit]);
    assert_eq!(read(&lit), "// v2\nfn main() {}\n");
}

#[test]
fn reading_does_not_trigger() {
    let f = fixture();
    let _ = read(&f.root.join("shaders/lit.wgsl"));
    expect_quiet(&f.watcher);
}

#[test]
fn temp_file_then_rename_over() {
    let f = fixture();
    let lit = f.root.join("shaders/lit.wgsl");
    for tmp in [
        "lit.wgsl.tmp",
        ".tmpA1b2C3",
        "lit.wgsl___jb_tmp___",
        ".goutputstream-XYZ123",
    ] {
        let tmp = f.root.join("shaders").join(tmp);
        fs::write(&tmp, format!("// via {}\n", tmp.display())).unwrap();
        fs::rename(&tmp, &lit).unwrap();
        expect_once(&f.watcher, &lit, ChangeKind::Modified, &[&lit]);
    }
}

#[test]
fn temp_file_with_plain_name_then_rename() {
    // An atomic-write library with an unrecognisable temp name: the temp file appears and is
    // renamed away within one debounce window, so it was never a known file and is dropped.
    let f = fixture();
    let lit = f.root.join("shaders/lit.wgsl");
    let tmp = f.root.join("shaders/xq7z");
    fs::write(&tmp, "// v3\n").unwrap();
    fs::rename(&tmp, &lit).unwrap();
    expect_once(&f.watcher, &lit, ChangeKind::Modified, &[&lit]);
}

#[test]
fn vim_style_backup_rename_and_rewrite() {
    // Vim with `backupcopy=no`: probe file 4913, rename the original to `name~`, write a new
    // file, delete the backup. Also leaves a swap file around.
    let f = fixture();
    let dir = f.root.join("shaders");
    let lit = dir.join("lit.wgsl");
    fs::write(dir.join(".lit.wgsl.swp"), "swap").unwrap();
    fs::write(dir.join("4913"), "").unwrap();
    fs::remove_file(dir.join("4913")).unwrap();
    fs::rename(&lit, dir.join("lit.wgsl~")).unwrap();
    fs::write(&lit, "// vim\n").unwrap();
    fs::remove_file(dir.join("lit.wgsl~")).unwrap();
    fs::write(dir.join(".#lit.wgsl"), "emacs lock").unwrap();
    expect_once(&f.watcher, &lit, ChangeKind::Modified, &[&lit]);
    assert_eq!(read(&lit), "// vim\n");
}

#[test]
fn truncate_then_write_quickly() {
    let f = fixture();
    let lit = f.root.join("shaders/lit.wgsl");
    let mut file = OpenOptions::new()
        .write(true)
        .truncate(true)
        .open(&lit)
        .unwrap();
    file.flush().unwrap();
    file.write_all(b"// rewritten\n").unwrap();
    drop(file);
    expect_once(&f.watcher, &lit, ChangeKind::Modified, &[&lit]);
}

#[test]
fn truncate_then_slow_write_holds_the_empty_file_back() {
    let f = fixture();
    let lit = f.root.join("shaders/lit.wgsl");
    let mut file = OpenOptions::new()
        .write(true)
        .truncate(true)
        .open(&lit)
        .unwrap();
    file.flush().unwrap();
    // Several debounce periods pass with an empty file: no batch may name it.
    expect_quiet(&f.watcher);
    file.write_all(b"// finally\n").unwrap();
    drop(file);
    expect_once(&f.watcher, &lit, ChangeKind::Modified, &[&lit]);
}

#[test]
fn file_left_empty_is_reported_after_the_grace_period() {
    let f = fixture();
    let lit = f.root.join("shaders/lit.wgsl");
    let start = Instant::now();
    fs::write(&lit, "").unwrap();
    expect_once(&f.watcher, &lit, ChangeKind::Modified, &[&lit]);
    assert!(start.elapsed() >= GRACE, "reported before the grace period");
    assert_eq!(fs::metadata(&lit).unwrap().len(), 0);
}

#[test]
fn delete_then_recreate() {
    let f = fixture();
    let lit = f.root.join("shaders/lit.wgsl");
    for round in 0..3 {
        fs::remove_file(&lit).unwrap();
        fs::write(&lit, format!("// round {round}\n")).unwrap();
        expect_once(&f.watcher, &lit, ChangeKind::Modified, &[&lit]);
    }
}

#[test]
fn delete_then_slow_recreate() {
    let f = fixture();
    let lit = f.root.join("shaders/lit.wgsl");
    fs::remove_file(&lit).unwrap();
    expect_quiet(&f.watcher);
    fs::write(&lit, "// back\n").unwrap();
    expect_once(&f.watcher, &lit, ChangeKind::Modified, &[&lit]);
}

#[test]
fn delete_for_good_is_reported_as_removed() {
    let f = fixture();
    let lit = f.root.join("shaders/lit.wgsl");
    fs::remove_file(&lit).unwrap();
    let b = expect_once(&f.watcher, &lit, ChangeKind::Removed, &[&lit]);
    assert_eq!(b.removed().count(), 1);
}

#[test]
fn editor_temp_files_alone_are_ignored() {
    let f = fixture();
    let dir = f.root.join("shaders");
    for name in [
        "lit.wgsl.swp",
        ".lit.wgsl.swx",
        "lit.wgsl~",
        ".#lit.wgsl",
        "#lit.wgsl#",
        "4913",
        "sedAb12Cd",
        "x.bak",
    ] {
        fs::write(dir.join(name), "junk").unwrap();
    }
    fs::remove_file(dir.join("4913")).unwrap();
    expect_quiet(&f.watcher);
}

#[test]
fn several_files_in_one_batch_each_once() {
    // A tool rewriting files in a burst is coalesced by the debounce. With the default
    // settle time such a burst is cut wherever the writer pauses longer than that between
    // two complete saves (on a loaded 2-core machine it does, see `event_traces`), so
    // this test gives the settle time the debounce's length;
    // `a_burst_of_saves_may_split_but_loses_nothing` runs the same burst with the default.
    let f = fixture_with(WatchConfig {
        settle: DEBOUNCE,
        ..config()
    });
    let lit = f.root.join("shaders/lit.wgsl");
    let common = f.root.join("shaders/common.wgsl");
    fs::create_dir(f.root.join("shaders/inc")).unwrap();
    let nested = f.root.join("shaders/inc/brdf.wgsl");
    // A burst of repeated writes to the same files.
    for i in 0..5 {
        fs::write(&lit, format!("// {i}\n")).unwrap();
        fs::write(&common, format!("// {i}\n")).unwrap();
    }
    let b = expect_once(&f.watcher, &lit, ChangeKind::Modified, &[&lit, &common]);
    assert!(b.contains(&common));
    // A new file in a new subdirectory is picked up too.
    fs::write(&nested, "// brdf\n").unwrap();
    expect_once(&f.watcher, &nested, ChangeKind::Modified, &[&nested]);
}

#[test]
fn a_burst_of_saves_may_split_but_loses_nothing() {
    let f = fixture();
    let lit = f.root.join("shaders/lit.wgsl");
    let common = f.root.join("shaders/common.wgsl");
    for i in 0..5 {
        fs::write(&lit, format!("// {i}\n")).unwrap();
        fs::write(&common, format!("// {i}\n")).unwrap();
    }
    // Every batch names only files of the burst, together they name both, and then
    // nothing more comes (a split burst names a file again, never leaves one out).
    let mut named = HashSet::new();
    let mut batches = Vec::new();
    loop {
        let wait = if named.len() < 2 { PRESENT } else { ABSENT };
        let Some(b) = f.watcher.wait_for_change(wait) else {
            assert_eq!(
                named.len(),
                2,
                "not both named within {PRESENT:?}: {batches:?}"
            );
            break;
        };
        for p in b.paths() {
            assert!(p == lit || p == common, "unexpected {}", p.display());
            named.insert(p.to_path_buf());
        }
        batches.push(b);
    }
    assert_eq!(read(&lit), "// 4\n");
    assert_eq!(read(&common), "// 4\n");
}

#[test]
fn single_file_watch_survives_replacement() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().canonicalize().unwrap();
    let graph = root.join("forward.ron");
    let other = root.join("other.ron");
    fs::write(&graph, "(passes: [])").unwrap();
    fs::write(&other, "()").unwrap();
    let mut w = FileWatcher::new(config()).unwrap();
    assert_eq!(w.watch(&graph).unwrap(), graph);

    // A sibling that is not watched is not reported.
    fs::write(&other, "(changed)").unwrap();
    expect_quiet(&w);

    // Rename over, delete + recreate, in place: the watch survives each.
    let tmp = root.join("forward.ron.tmp");
    fs::write(&tmp, "(passes: [a])").unwrap();
    fs::rename(&tmp, &graph).unwrap();
    expect_once(&w, &graph, ChangeKind::Modified, &[&graph]);
    fs::remove_file(&graph).unwrap();
    fs::write(&graph, "(passes: [b])").unwrap();
    expect_once(&w, &graph, ChangeKind::Modified, &[&graph]);
    fs::write(&graph, "(passes: [c])").unwrap();
    expect_once(&w, &graph, ChangeKind::Modified, &[&graph]);
}

#[test]
fn watching_a_file_that_does_not_exist_yet() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().canonicalize().unwrap();
    let scene = root.join("scene.ron");
    let mut w = FileWatcher::new(config()).unwrap();
    assert_eq!(w.watch(&scene).unwrap(), scene);
    fs::write(&scene, "()").unwrap();
    expect_once(&w, &scene, ChangeKind::Modified, &[&scene]);
    assert!(w.watch(root.join("missing/dir/x.ron")).is_err());
}

#[test]
fn drain_and_try_next_never_block() {
    let f = fixture();
    assert!(f.watcher.drain().is_none());
    assert!(f.watcher.try_next().is_none());
    let lit = f.root.join("shaders/lit.wgsl");
    fs::write(&lit, "// a\n").unwrap();
    let batch = f.watcher.wait_for_change(PRESENT).expect("a batch");
    assert!(batch.contains(&lit));
    assert!(f.watcher.drain().is_none());
}

// The fast path: a batch whose files are all saved (closed after writing, renamed into
// place) is cut `settle` after the last event instead of `debounce`. These tests use a
// debounce far longer than any scheduling hiccup, so "fast" and "waited for the debounce"
// cannot be confused.

const SLOW_DEBOUNCE: Duration = Duration::from_millis(500);
/// A saved file's batch must arrive this soon after the save returned: a fifth of
/// `SLOW_DEBOUNCE`, leaving ~95 ms over the 5 ms settle time for a loaded machine.
const FAST: Duration = Duration::from_millis(100);

fn slow_fixture() -> Fixture {
    fixture_with(WatchConfig {
        debounce: SLOW_DEBOUNCE,
        ..config()
    })
}

/// The next batch and how long after `since` it came (panics after `PRESENT`).
fn next_batch(w: &FileWatcher, since: Instant) -> (ChangeBatch, Duration) {
    let b = w.wait_for_change(PRESENT).expect("a batch");
    (b, since.elapsed())
}

#[test]
fn saved_files_arrive_without_waiting_for_the_debounce() {
    let f = slow_fixture();
    let dir = f.root.join("shaders");
    let lit = dir.join("lit.wgsl");
    type Save = fn(&Path, &str);
    let saves: [(&str, Save); 5] = [
        ("std::fs::write", |lit, text| fs::write(lit, text).unwrap()),
        ("in place, two writes", |lit, text| {
            let mut file = OpenOptions::new().write(true).open(lit).unwrap();
            file.write_all(b"// ").unwrap();
            file.write_all(&text.as_bytes()[3..]).unwrap();
        }),
        ("temp file renamed over", |lit, text| {
            let tmp = lit.with_extension("wgsl.tmp");
            fs::write(&tmp, text).unwrap();
            fs::rename(&tmp, lit).unwrap();
        }),
        ("plain-named temp file renamed over", |lit, text| {
            let tmp = lit.with_file_name("xq7z");
            fs::write(&tmp, text).unwrap();
            fs::rename(&tmp, lit).unwrap();
        }),
        ("truncated, then written in a second open", |lit, text| {
            drop(
                OpenOptions::new()
                    .write(true)
                    .truncate(true)
                    .open(lit)
                    .unwrap(),
            );
            fs::write(lit, text).unwrap();
        }),
    ];
    for (i, (name, save)) in saves.into_iter().enumerate() {
        let text = format!("// save {i}\n");
        save(&lit, &text);
        let saved = Instant::now();
        let (b, after) = next_batch(&f.watcher, saved);
        assert_eq!(b.paths().collect::<Vec<_>>(), vec![lit.as_path()], "{name}");
        assert_eq!(read(&lit), text, "{name}");
        assert!(after < FAST, "{name}: batch {after:?} after the save");
        expect_quiet(&f.watcher);
    }
}

#[test]
fn a_file_still_open_for_writing_waits_for_its_close() {
    let f = slow_fixture();
    let lit = f.root.join("shaders/lit.wgsl");
    let mut file = OpenOptions::new()
        .write(true)
        .truncate(true)
        .open(&lit)
        .unwrap();
    file.write_all(b"// first half\n").unwrap();
    // Well past the settle time, inside the debounce: a half-written file is not saved.
    if let Some(b) = f.watcher.wait_for_change(SLOW_DEBOUNCE / 2) {
        panic!("a file still open for writing was delivered: {b:?}");
    }
    file.write_all(b"// second half\n").unwrap();
    drop(file);
    let closed = Instant::now();
    let (b, after) = next_batch(&f.watcher, closed);
    assert!(b.contains(&lit));
    assert!(after < FAST, "batch {after:?} after the close");
    assert_eq!(read(&lit), "// first half\n// second half\n");
    expect_quiet(&f.watcher);
}

#[test]
fn a_write_never_closed_waits_the_full_debounce() {
    // mmap writers and tools that keep files open never say they are done: the debounce.
    let f = slow_fixture();
    let lit = f.root.join("shaders/lit.wgsl");
    let mut file = OpenOptions::new().write(true).open(&lit).unwrap();
    file.write_all(b"// kept open\n").unwrap();
    let written = Instant::now();
    let (b, after) = next_batch(&f.watcher, written);
    assert!(b.contains(&lit));
    assert!(after >= SLOW_DEBOUNCE, "batch {after:?} after the write");
    drop(file);
}

#[test]
fn a_new_file_waits_the_full_debounce() {
    // It may be an atomic save's temp file about to be renamed: delivering it early would
    // report a file that is gone a moment later.
    let f = slow_fixture();
    let new = f.root.join("shaders/brdf.wgsl");
    fs::write(&new, "// brdf\n").unwrap();
    let written = Instant::now();
    let (b, after) = next_batch(&f.watcher, written);
    assert_eq!(b.paths().collect::<Vec<_>>(), vec![new.as_path()]);
    assert!(after >= SLOW_DEBOUNCE, "batch {after:?} after the write");
    // Once known, its next save is fast.
    fs::write(&new, "// brdf 2\n").unwrap();
    let (_, after) = next_batch(&f.watcher, Instant::now());
    assert!(after < FAST, "batch {after:?} after the second save");
}

#[test]
fn an_open_swap_file_does_not_hold_a_save_back() {
    // Vim keeps its swap file open and writes to it; it is no source file and must not
    // make a saved source file wait for the debounce.
    let f = slow_fixture();
    let lit = f.root.join("shaders/lit.wgsl");
    let mut swap = fs::File::create(f.root.join("shaders/.lit.wgsl.swp")).unwrap();
    swap.write_all(b"swap").unwrap();
    fs::write(&lit, "// saved\n").unwrap();
    swap.write_all(b"more swap").unwrap();
    let (b, after) = next_batch(&f.watcher, Instant::now());
    assert_eq!(b.paths().collect::<Vec<_>>(), vec![lit.as_path()]);
    assert!(after < FAST, "batch {after:?} after the save");
    drop(swap);
}

/// What inotify reports for each save style, and when: run with
/// `cargo test --release --test reload_watcher -- --ignored --nocapture event_traces`.
/// Prints one trace per style (event kinds and paths, microseconds after the save began)
/// and, over many rounds, the largest gap between two events of one save and when the
/// last event arrived after the save's last call returned. The measurement behind
/// `WatchConfig::DEFAULT_SETTLE`; it checks nothing.
#[test]
#[ignore = "a measurement: prints event traces"]
fn event_traces() {
    use notify::Watcher;
    type Save = fn(&Path);
    let styles: [(&str, Save); 6] = [
        ("std::fs::write", |dir| {
            fs::write(dir.join("lit.wgsl"), "// new\n").unwrap()
        }),
        ("write temp, rename over (atomic save)", |dir| {
            fs::write(dir.join("lit.wgsl.tmp"), "// new\n").unwrap();
            fs::rename(dir.join("lit.wgsl.tmp"), dir.join("lit.wgsl")).unwrap();
        }),
        (
            "atomic save, then chmod (vim, VS Code keep the mode)",
            |dir| {
                let tmp = dir.join("xq7z");
                fs::write(&tmp, "// new\n").unwrap();
                fs::rename(&tmp, dir.join("lit.wgsl")).unwrap();
                let perm = fs::metadata(dir.join("lit.wgsl")).unwrap().permissions();
                fs::set_permissions(dir.join("lit.wgsl"), perm).unwrap();
            },
        ),
        ("truncate, then write in a second open", |dir| {
            let lit = dir.join("lit.wgsl");
            drop(
                OpenOptions::new()
                    .write(true)
                    .truncate(true)
                    .open(&lit)
                    .unwrap(),
            );
            let mut f = OpenOptions::new().write(true).open(&lit).unwrap();
            f.write_all(b"// new\n").unwrap();
        }),
        ("slow writer: 3 chunks, 5 ms apart, then close", |dir| {
            let mut f = OpenOptions::new()
                .write(true)
                .truncate(true)
                .open(dir.join("lit.wgsl"))
                .unwrap();
            for chunk in ["// a\n", "// b\n", "// c\n"] {
                f.write_all(chunk.as_bytes()).unwrap();
                std::thread::sleep(Duration::from_millis(5));
            }
        }),
        ("save all: two files written one after the other", |dir| {
            fs::write(dir.join("lit.wgsl"), "// new\n").unwrap();
            fs::write(dir.join("common.wgsl"), "// new\n").unwrap();
        }),
    ];
    const ROUNDS: usize = 500;
    for (name, save) in styles {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().canonicalize().unwrap();
        fs::write(root.join("lit.wgsl"), "// v1\n").unwrap();
        fs::write(root.join("common.wgsl"), "// v1\n").unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        let mut w = notify::recommended_watcher(move |e: notify::Result<notify::Event>| {
            let _ = tx.send((Instant::now(), e.unwrap()));
        })
        .unwrap();
        w.watch(&root, notify::RecursiveMode::Recursive).unwrap();
        let (mut splits, mut tails) = (Vec::new(), Vec::new());
        let before: HashSet<PathBuf> = [root.join("lit.wgsl"), root.join("common.wgsl")].into();
        for round in 0..ROUNDS {
            let start = Instant::now();
            save(&root);
            let returned = Instant::now();
            let mut events = Vec::new();
            while let Ok(e) = rx.recv_timeout(Duration::from_millis(50)) {
                events.push(e);
            }
            let since = |t: Instant| t.saturating_duration_since(start).as_micros();
            if round == 0 {
                println!("== {name}");
                for (t, e) in &events {
                    let names: Vec<_> = e.paths.iter().filter_map(|p| p.file_name()).collect();
                    println!("  {:>6} us  {:?} {names:?}", since(*t), e.kind);
                }
            }
            // The gaps that would cut a batch early: those after an event that left every
            // file looking saved (as `settle.rs` judges: no write since a close-after-write,
            // rename or removal; no new file still there), and the last event's arrival.
            // Opens, reads and rename pairs are no events to the watcher.
            use notify::event::{AccessKind, AccessMode, EventKind, ModifyKind, RenameMode};
            events.retain(|(_, e)| match e.kind {
                EventKind::Access(AccessKind::Close(AccessMode::Write)) => true,
                EventKind::Access(_) | EventKind::Other => false,
                EventKind::Modify(ModifyKind::Name(RenameMode::Both)) => false,
                _ => true,
            });
            let (mut open, mut fresh) = (HashSet::new(), HashSet::new());
            let mut split = Duration::ZERO;
            for (i, (t, e)) in events.iter().enumerate() {
                for p in &e.paths {
                    match e.kind {
                        EventKind::Access(AccessKind::Close(AccessMode::Write)) => {
                            open.remove(p);
                        }
                        EventKind::Modify(ModifyKind::Name(_)) | EventKind::Remove(_) => {
                            open.remove(p);
                            fresh.remove(p);
                        }
                        EventKind::Create(_) => {
                            open.insert(p.clone());
                            if !before.contains(p) {
                                fresh.insert(p.clone());
                            }
                        }
                        EventKind::Modify(ModifyKind::Data(_)) => {
                            open.insert(p.clone());
                        }
                        _ => {}
                    }
                }
                let saved = open.is_empty() && fresh.iter().all(|p| !p.exists());
                if let (true, Some((next, _))) = (saved, events.get(i + 1)) {
                    split = split.max(*next - *t);
                }
            }
            splits.push(split.as_micros());
            tails.push(events.last().map_or(0, |(t, _)| {
                t.saturating_duration_since(returned).as_micros()
            }));
        }
        splits.sort_unstable();
        tails.sort_unstable();
        let pct = |v: &[u128], q: f64| v[((v.len() - 1) as f64 * q) as usize];
        let over = |ms: u128| splits.iter().filter(|&&g| g > ms * 1000).count();
        println!(
            "  {ROUNDS} rounds: longest pause with every file saved: median {} us, p99 {} us, max {} us \
             (over 2 / 5 / 10 / 20 ms: {} / {} / {} / {}); last event after the save returned: \
             median {} us, max {} us",
            pct(&splits, 0.5), pct(&splits, 0.99), pct(&splits, 1.0),
            over(2), over(5), over(10), over(20),
            pct(&tails, 0.5), pct(&tails, 1.0)
        );
    }
}

fn copy_dir(from: &Path, to: &Path) {
    fs::create_dir(to).unwrap();
    for e in fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &to.join(e.file_name()));
        } else {
            fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

/// Every batch until none comes for longer than the grace period (what a folder's swap
/// reports, held-back removals included), merged.
fn drain_until_quiet(w: &FileWatcher) -> ChangeBatch {
    let mut merged = ChangeBatch::default();
    while let Some(b) = w.wait_for_change(GRACE + ABSENT) {
        merged.merge(b);
    }
    merged
}

/// Waits (bounded) for a batch naming `path` as modified.
fn expect_modified(w: &FileWatcher, path: &Path) {
    let deadline = Instant::now() + PRESENT;
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let Some(b) = w.wait_for_change(left) else {
            panic!("{} not reported within {PRESENT:?}", path.display());
        };
        if b.contains(path) {
            assert_eq!(b.changes.get(path), Some(&ChangeKind::Modified), "{b:?}");
            return;
        }
    }
}

/// A watched folder replaced by a copy (`cp -r shaders x; rm -rf shaders; mv x shaders`)
/// is watched again by its path: later edits are reported.
#[test]
fn a_watched_folder_replaced_is_watched_again() {
    let f = fixture();
    let shaders = f.root.join("shaders");
    let copy = f.root.join("x");
    copy_dir(&shaders, &copy);
    fs::remove_dir_all(&shaders).unwrap();
    fs::rename(&copy, &shaders).unwrap();
    let swap = drain_until_quiet(&f.watcher);
    let lit = shaders.join("lit.wgsl");
    assert_ne!(
        swap.changes.get(&lit),
        Some(&ChangeKind::Removed),
        "{swap:?}"
    );
    fs::write(&lit, "// after the swap\n").unwrap();
    expect_modified(&f.watcher, &lit);
    // And once more: the new folder's watch is not a one-off.
    fs::write(shaders.join("common.wgsl"), "// common 2\n").unwrap();
    expect_modified(&f.watcher, &shaders.join("common.wgsl"));
}

/// A watched folder moved away and copied back: edits of the moved-away copy are not
/// reported as the live file, edits of the copy at the watched path are.
#[test]
fn a_watched_folder_moved_away_and_back_follows_the_path() {
    let f = fixture();
    let shaders = f.root.join("shaders");
    let away = f.root.join("away");
    fs::rename(&shaders, &away).unwrap();
    drain_until_quiet(&f.watcher);
    copy_dir(&away, &shaders);
    drain_until_quiet(&f.watcher);
    fs::write(away.join("lit.wgsl"), "// the moved-away copy\n").unwrap();
    expect_quiet(&f.watcher);
    let lit = shaders.join("lit.wgsl");
    fs::write(&lit, "// the live file\n").unwrap();
    expect_modified(&f.watcher, &lit);
}
