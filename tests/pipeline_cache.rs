//! The driver's pipeline cache on disk (src/gpu/pipeline_cache.rs), across process starts:
//! the first start saves it, the second loads it and wgpu and the driver accept it; a
//! damaged, foreign or refused file is ignored with a warning (never a panic) and
//! replaced. Every pipeline descriptor the renderer builds is handed the cache.
//!
//! lavapipe offers `PIPELINE_CACHE` but keeps nothing in it (its data is the 32-byte
//! Vulkan header in wgpu's), so what is tested here is the round trip and the fallbacks,
//! not a faster start.

use lightgraph::gpu::pipeline_cache::{encode, read_envelope};
use std::path::{Path, PathBuf};
use std::process::Command;

/// `reload-bench` at a tiny size with one edit of each kind, the pipeline cache in
/// `cache`: its stdout (the run must succeed).
fn start(work: &Path, cache: &Path) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_lightgraph"))
        .current_dir(work)
        .args([
            "reload-bench",
            "--out",
            "out",
            "--width",
            "32",
            "--height",
            "18",
        ])
        .args(["--lights", "8", "--repeats", "1"])
        .env_remove("LIGHTGRAPH_ROOT")
        .env("LIGHTGRAPH_PIPELINE_CACHE_DIR", cache)
        .output()
        .expect("the binary runs");
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    );
    assert!(o.status.success(), "{out}\n{err}");
    out
}

fn status(out: &str) -> &str {
    out.lines()
        .find(|l| l.starts_with("pipeline cache: "))
        .expect("the bench names its pipeline cache")
}

/// The one cache file in `dir`.
fn file_in(dir: &Path) -> PathBuf {
    let files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(files.len(), 1, "{files:?}");
    files[0].clone()
}

/// Whether the adapter has no pipeline cache (then there is nothing to test).
fn off(out: &str) -> bool {
    let off = status(out).contains(": off");
    if off {
        eprintln!("skipped: {}", status(out));
    }
    off
}

#[test]
fn a_second_start_loads_the_cache_the_first_saved() {
    let work = tempfile::tempdir().unwrap();
    let cache = work.path().join("cache");
    let first = start(work.path(), &cache);
    if off(&first) {
        return;
    }
    assert!(status(&first).contains("no file yet"), "{first}");
    let file = file_in(&cache);
    assert!(file.extension().is_some_and(|e| e == "bin"), "{file:?}");
    let bytes = std::fs::read(&file).unwrap();
    let (key, data) = read_envelope(&bytes).expect("a whole file");
    assert!(key.starts_with("wgpu_pipeline_cache_vulkan_"), "{key}");
    assert!(!data.is_empty());

    let second = start(work.path(), &cache);
    let line = status(&second);
    assert!(
        line.contains(&format!("loaded {} bytes, accepted", data.len())),
        "{line}"
    );
}

#[test]
fn damaged_foreign_and_refused_files_are_ignored_and_replaced() {
    let work = tempfile::tempdir().unwrap();
    let cache = work.path().join("cache");
    let first = start(work.path(), &cache);
    if off(&first) {
        return;
    }
    let file = file_in(&cache);
    let good = std::fs::read(&file).unwrap();
    let (key, data) = read_envelope(&good).unwrap();
    let mut cut = good.clone();
    cut.truncate(good.len() - 3);
    let cases: [(&str, Vec<u8>, &str); 4] = [
        ("garbage", b"\x89PNG not a cache".to_vec(), "ignored: "),
        ("truncated", cut, "ignored: "),
        (
            "another adapter",
            encode("wgpu_pipeline_cache_vulkan_4318_8963|NVIDIA H200", data),
            "made for another adapter or driver",
        ),
        // Whole and ours, but not wgpu's data: wgpu refuses it.
        (
            "not wgpu's data",
            encode(&key, &[7u8; 200]),
            "refused by wgpu or the driver",
        ),
    ];
    for (what, bytes, expected) in cases {
        std::fs::write(&file, &bytes).unwrap();
        let out = start(work.path(), &cache);
        assert!(status(&out).contains(expected), "{what}: {}", status(&out));
        // Replaced by a whole file for this adapter.
        let now = std::fs::read(file_in(&cache)).unwrap();
        let (now_key, _) = read_envelope(&now).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!(now_key, key, "{what}");
    }
}

/// Every render and compute pipeline descriptor under src/render takes the driver's
/// cache (`cache: ...driver_cache()`), none `cache: None`.
#[test]
fn every_renderer_pipeline_is_built_with_the_cache() {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|e| e == "rs") {
                out.push(p);
            }
        }
    }
    let mut files = Vec::new();
    walk(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("src/render"),
        &mut files,
    );
    let mut descriptors = 0;
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        assert!(
            !text.contains("cache: None"),
            "{}: cache: None",
            f.display()
        );
        descriptors += text.matches("cache: ").count();
    }
    assert!(descriptors >= 4, "{descriptors}");
}
