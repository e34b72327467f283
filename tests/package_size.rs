//! The published package stays under crates.io's 10 MB limit on the compressed `.crate`:
//! the crate `cargo package` writes (into a temporary folder, so it needs no lock on the
//! build folder) is measured, and the files it lists hold no benchmark scratch or fuzz
//! corpus and do hold the library's sources.

use std::path::Path;
use std::process::Command;

/// crates.io refuses a .crate over 10 MB.
const LIMIT: u64 = 10 * 1024 * 1024;

/// `cargo` with `args` (then `extra`) in the project root; its stdout, once it succeeded.
fn cargo(root: &Path, args: &[&str], extra: &[&Path]) -> Vec<u8> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args(args)
        .args(extra)
        .current_dir(root)
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

#[test]
fn the_package_is_under_the_registry_limit() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let target = tempfile::tempdir().unwrap();
    // The crate as crates.io would receive it (not built: that is what the suite does).
    cargo(
        root,
        &[
            "package",
            "--no-verify",
            "--allow-dirty",
            "--offline",
            "--target-dir",
        ],
        &[target.path()],
    );
    let name = format!(
        "{}-{}.crate",
        env!("CARGO_PKG_NAME"),
        env!("CARGO_PKG_VERSION")
    );
    let size = std::fs::metadata(target.path().join("package").join(&name))
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .len();
    let list = String::from_utf8(cargo(root, &["package", "--list", "--allow-dirty"], &[]))
        .expect("the list is UTF-8");
    let mut biggest = Vec::new();
    for file in list.lines() {
        assert!(
            !file.starts_with("fuzz/"),
            "the fuzz corpus is not part of the package: {file}"
        );
        if let Ok(m) = std::fs::metadata(root.join(file)) {
            biggest.push((m.len(), file.to_string()));
        }
    }
    biggest.sort();
    biggest.reverse();
    biggest.truncate(5);
    eprintln!("{name}: {size} bytes");
    assert!(
        size < LIMIT,
        "the package is {size} bytes compressed, over {LIMIT}; largest files: {biggest:?}"
    );
    // The library's own sources and shaders must be in it (a list filtered to nothing
    // would pass the size check).
    for needed in [
        "src/lib.rs",
        "shaders/common/lighting.wgsl",
        "graphs/forward_plus.ron",
    ] {
        assert!(
            list.lines().any(|f| f == needed),
            "{needed} is missing from the package"
        );
    }
}
