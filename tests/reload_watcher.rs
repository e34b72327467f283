//! The file watcher against every way editors save. Bounded waits only: presence is awaited up to
//! `PRESENT`, absence is checked by waiting a few debounce periods for a batch that must not come.

use lightgraph::reload::{ChangeBatch, ChangeKind, FileWatcher, WatchConfig};
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
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().canonicalize().unwrap();
    fs::create_dir(root.join("shaders")).unwrap();
    fs::write(root.join("shaders/lit.wgsl"), "// v1\n").unwrap();
    fs::write(root.join("shaders/common.wgsl"), "// common\n").unwrap();
    let mut watcher = FileWatcher::new(config()).unwrap();
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
    let f = fixture();
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
