//! The published package stays under crates.io's 10 MB limit: the files `cargo package
//! --list` would ship, summed uncompressed (the limit applies to the compressed .crate, so
//! this bound is conservative), and no benchmark scratch or fuzz corpus among them.

use std::path::Path;
use std::process::Command;

/// crates.io refuses a .crate over 10 MB.
const LIMIT: u64 = 10 * 1024 * 1024;

/// Files cargo writes into the package itself rather than copying from the tree.
const GENERATED: [&str; 3] = ["Cargo.toml.orig", ".cargo_vcs_info.json", "Cargo.lock"];

#[test]
fn the_package_is_under_the_registry_limit() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args(["package", "--list", "--allow-dirty"])
        .current_dir(root)
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo package --list failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let list = String::from_utf8(out.stdout).expect("the list is UTF-8");
    let mut total = 0;
    let mut biggest = Vec::new();
    for file in list.lines() {
        if GENERATED.contains(&file) {
            continue;
        }
        assert!(
            !file.starts_with("fuzz/"),
            "the fuzz corpus is not part of the package: {file}"
        );
        let len = std::fs::metadata(root.join(file))
            .unwrap_or_else(|e| panic!("{file} is listed but cannot be read: {e}"))
            .len();
        total += len;
        biggest.push((len, file.to_string()));
    }
    biggest.sort();
    biggest.reverse();
    biggest.truncate(5);
    assert!(
        total < LIMIT,
        "the package is {total} bytes, over {LIMIT}; largest files: {biggest:?}"
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
