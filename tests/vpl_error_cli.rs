//! `lightgraph vpl-error --variant`: several VPL frames against one reference, one CSV
//! row a variant and n, and a usage error for a variant without a label; `--no-noise`
//! skips the reference's second estimate. On lavapipe, at a tiny size.

use std::process::Command;

fn vpl_error(out: &std::path::Path, variants: &[&str]) -> std::process::Output {
    vpl_error_with(out, variants, &[])
}

fn vpl_error_with(
    out: &std::path::Path,
    variants: &[&str],
    extra: &[&str],
) -> std::process::Output {
    let root = env!("CARGO_MANIFEST_DIR");
    let mut args = vec![
        "vpl-error".to_string(),
        "--scene".into(),
        format!("{root}/scenes/cornell_indirect.ron"),
        "--width".into(),
        "16".into(),
        "--height".into(),
        "12".into(),
        "--samples".into(),
        "4".into(),
        "--n".into(),
        "4".into(),
        "--frames".into(),
        "1".into(),
        "--out".into(),
        out.display().to_string(),
    ];
    for v in variants {
        args.push("--variant".into());
        args.push(v.to_string());
    }
    args.extend(extra.iter().map(|a| a.to_string()));
    Command::new(env!("CARGO_BIN_EXE_lightgraph"))
        .current_dir(root)
        .args(&args)
        .env_remove("LIGHTGRAPH_ROOT")
        .output()
        .expect("the binary runs")
}

#[test]
fn variants_share_one_reference_and_fill_one_csv() {
    let out = std::env::temp_dir().join(format!("lightgraph_vpl_variants_{}", std::process::id()));
    let o = vpl_error(
        &out,
        &[
            "label=clamp",
            "label=merged disc;spawn=merge: 2, falloff: Disc",
        ],
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    // One reference for the scene, not one a variant.
    assert_eq!(
        stderr.matches("reference (4 samples)").count(),
        1,
        "{stderr}"
    );
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert!(rows[0].starts_with("scene,variant,n,vpls,"), "{csv}");
    assert_eq!(rows.len(), 3, "{csv}");
    assert!(rows[1].starts_with("cornell_indirect,clamp,4,"), "{csv}");
    assert!(
        rows[2].starts_with("cornell_indirect,merged disc,4,"),
        "{csv}"
    );
    // The merged variant spawned fewer VPLs and said so.
    let vpls = |row: &str| row.split(',').nth(3).unwrap().parse::<u32>().unwrap();
    assert!(vpls(rows[2]) < vpls(rows[1]), "{csv}");
    assert!(
        stdout.contains("VPLs merged into their neighbours"),
        "{stdout}"
    );
    assert!(out.join("time_vs_error.png").exists() || stdout.contains("no time plot"));
    let _ = std::fs::remove_dir_all(&out);

    let o = vpl_error(&out, &["spawn=merge: 2"]);
    assert!(!o.status.success());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("needs a label="), "{stderr}");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn no_noise_skips_the_second_reference() {
    let out = std::env::temp_dir().join(format!("lightgraph_vpl_noise_{}", std::process::id()));
    for (extra, noise) in [
        (&[][..], "its noise 0."),
        (&["--no-noise"][..], "its noise not estimated"),
    ] {
        let o = vpl_error_with(&out, &[], extra);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{stderr}");
        assert!(stderr.contains(noise), "{extra:?}: {stderr}");
        let md = std::fs::read_to_string(out.join("results.md")).unwrap();
        let table_says = noise.replace("its noise", "its own noise: relative MSE");
        assert!(md.contains(&table_says), "{extra:?}: {md}");
        let _ = std::fs::remove_dir_all(&out);
    }
}
