//! Every file in tests/bad/graphs/ must fail validation with the message fragment on its
//! first line (`// expect: ...`), and nothing may panic. The shipped graphs must pass.

use lightgraph::graph;
use lightgraph::shader::ShaderLibrary;
use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn every_bad_graph_gives_its_message() {
    let dir = root().join("tests/bad/graphs");
    let mut checked = 0;
    let mut failures = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        let expect = text
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("// expect: "))
            .unwrap_or_else(|| panic!("{} lacks an expect line", path.display()))
            .to_string();
        let result =
            std::panic::catch_unwind(|| graph::check_file(&path, &ShaderLibrary::builtin()));
        match result {
            Err(_) => failures.push(format!("{}: panicked", path.display())),
            Ok(Ok(_)) => failures.push(format!("{}: was accepted", path.display())),
            Ok(Err(e)) => {
                let message = e.to_string();
                if !message.contains(&expect) {
                    failures.push(format!(
                        "{}:\n  expected: {expect}\n  got: {message}",
                        path.display()
                    ));
                }
                // Every message names the file, a line of it and a column.
                let name = path.file_name().unwrap().to_str().unwrap();
                if !names_line_and_column(&message, name, text.lines().count()) {
                    failures.push(format!(
                        "{}: message does not name file:line:col: {message}",
                        path.display()
                    ));
                }
            }
        }
        checked += 1;
    }
    assert!(checked >= 14, "only {checked} bad graphs");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Whether `message` has `name:LINE:COL` with LINE inside the file's `lines` and COL >= 1.
fn names_line_and_column(message: &str, name: &str, lines: usize) -> bool {
    let at = format!("{name}:");
    message.match_indices(&at).any(|(i, _)| {
        let mut parts = message[i + at.len()..].splitn(3, ':');
        let line = parts.next().and_then(|l| l.parse::<usize>().ok());
        let col = parts.next().and_then(|c| c.parse::<usize>().ok());
        matches!((line, col), (Some(l), Some(c)) if (1..=lines).contains(&l) && c >= 1)
    })
}

#[test]
fn the_location_check_needs_a_line_and_column() {
    assert!(names_line_and_column("x.ron:3:7: bad", "x.ron", 5));
    assert!(!names_line_and_column("x.ron: bad", "x.ron", 5));
    assert!(!names_line_and_column("x.ron:9:1: bad", "x.ron", 5));
    assert!(!names_line_and_column("x.ron:3: bad", "x.ron", 5));
}

#[test]
fn shipped_graphs_validate() {
    let mut checked = 0;
    for entry in std::fs::read_dir(root().join("graphs")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "ron") {
            continue;
        }
        if let Err(e) = graph::check_file(&path, &ShaderLibrary::builtin()) {
            panic!("{}: {e}", path.display());
        }
        checked += 1;
    }
    // An empty or misplaced graphs/ must not pass: the README lists these.
    for name in [
        "forward_plus.ron",
        "brute_force.ron",
        "tiled_deferred.ron",
        "raycast_shadows.ron",
    ] {
        assert!(
            root().join("graphs").join(name).is_file(),
            "graphs/{name} is missing"
        );
    }
    assert!(checked >= 15, "only {checked} shipped graphs");
}

#[test]
fn a_cycle_names_every_pass_on_it() {
    let e = graph::check_file(
        &root().join("tests/bad/graphs/cycle.ron"),
        &ShaderLibrary::builtin(),
    )
    .unwrap_err();
    let cycles: Vec<_> =
        e.0.iter()
            .filter_map(|e| match e {
                graph::GraphError::Cycle { passes, at } => Some((passes.clone(), at.line)),
                _ => None,
            })
            .collect();
    assert_eq!(cycles, vec![(vec!["a".to_string(), "b".to_string()], 16)]);
}

#[test]
fn broken_wgsl_names_the_shader_line() {
    let e = graph::check_file(
        &root().join("tests/bad/graphs/broken_wgsl.ron"),
        &ShaderLibrary::builtin(),
    )
    .unwrap_err();
    let text = e.to_string();
    assert!(text.contains("pass 'fill'"), "{text}");
    assert!(text.contains("broken.wgsl:6:"), "{text}");
    assert!(
        text.contains("scratch[0] = 1.5 + vec2<f32>(1.0);"),
        "{text}"
    );
}
