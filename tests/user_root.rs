//! The binary finds the user's files, as a new user runs it: in a folder of their own
//! (a copy of shaders/, graphs/, materials/) it reads and watches that folder, not the
//! source tree it was built from; in an empty folder it renders the default scene from
//! the files built into it. Every wait is bounded; children are killed on any exit.

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

fn source_tree() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The built binary, run in `dir` with no root given through the environment.
fn lightgraph(dir: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_lightgraph"));
    c.current_dir(dir).env_remove("LIGHTGRAPH_ROOT");
    c
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

/// A child process killed when dropped, with its stdout and stderr lines on one channel.
struct Running {
    child: Child,
    lines: Receiver<String>,
    seen: Vec<String>,
}

impl Running {
    fn spawn(mut command: Command) -> Self {
        let mut child = command
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start lightgraph");
        let (tx, lines) = mpsc::channel();
        let out: Box<dyn Read + Send> = Box::new(child.stdout.take().unwrap());
        let err: Box<dyn Read + Send> = Box::new(child.stderr.take().unwrap());
        for (stream, tag) in [(out, "out"), (err, "err")] {
            let tx = tx.clone();
            std::thread::spawn(move || {
                for line in BufReader::new(stream).lines().map_while(Result::ok) {
                    if tx.send(format!("{tag}: {line}")).is_err() {
                        break;
                    }
                }
            });
        }
        Self {
            child,
            lines,
            seen: Vec::new(),
        }
    }

    /// Waits up to `limit` for a line that satisfies `want`; panics with everything the
    /// process printed if none comes or the process ends first.
    fn wait_for(&mut self, what: &str, limit: Duration, want: impl Fn(&str) -> bool) -> String {
        let end = Instant::now() + limit;
        loop {
            let left = end.saturating_duration_since(Instant::now());
            match self
                .lines
                .recv_timeout(left.min(Duration::from_millis(500)))
            {
                Ok(line) => {
                    self.seen.push(line.clone());
                    if want(&line) {
                        return line;
                    }
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if let Ok(Some(status)) = self.child.try_wait() {
                        // Let the reader threads deliver what is left.
                        while let Ok(line) = self.lines.recv_timeout(Duration::from_millis(200)) {
                            self.seen.push(line);
                        }
                        if let Some(line) = self.seen.iter().find(|l| want(l)) {
                            return line.clone();
                        }
                        panic!(
                            "lightgraph exited ({status}) before {what}:\n{}",
                            self.seen.join("\n")
                        );
                    }
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {}
            }
            if Instant::now() >= end {
                panic!(
                    "no {what} within {} s; lightgraph printed:\n{}",
                    limit.as_secs(),
                    self.seen.join("\n")
                );
            }
        }
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Runs `command` to completion (bounded); returns (success, stdout and stderr).
fn run_to_end(command: Command, limit: Duration) -> (bool, String) {
    let mut running = Running::spawn(command);
    let end = Instant::now() + limit;
    loop {
        if let Some(status) = running.child.try_wait().unwrap() {
            while let Ok(line) = running.lines.recv_timeout(Duration::from_millis(500)) {
                running.seen.push(line);
            }
            return (status.success(), running.seen.join("\n"));
        }
        while let Ok(line) = running.lines.try_recv() {
            running.seen.push(line);
        }
        if Instant::now() >= end {
            panic!(
                "lightgraph did not finish within {} s:\n{}",
                limit.as_secs(),
                running.seen.join("\n")
            );
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn watch_in_a_copy_reports_the_copys_file_line_then_recovers() {
    let dir = tempfile::tempdir().unwrap();
    let work = dir.path().canonicalize().unwrap();
    for folder in ["shaders", "graphs", "materials"] {
        copy_dir(&source_tree().join(folder), &work.join(folder));
    }
    let out = work.join("frame.png");
    let mut command = lightgraph(&work);
    command.args(["watch", "--width", "48", "--height", "32", "--out"]);
    command.arg(&out);
    let mut watch = Running::spawn(command);
    let root_line = watch.wait_for("the root line", Duration::from_secs(60), |l| {
        l.contains("root: ")
    });
    assert!(
        root_line.contains(&work.display().to_string()),
        "not this folder: {root_line}"
    );
    watch.wait_for("the first frame", Duration::from_secs(300), |l| {
        l.starts_with("out: watching;")
    });
    assert_eq!(image::image_dimensions(&out).unwrap(), (48, 32));

    // Break the copy's lighting (included by the default graph's shading) on line 9.
    let shader = work.join("shaders/common/lighting.wgsl");
    let original = std::fs::read_to_string(&shader).unwrap();
    let mut lines: Vec<&str> = original.lines().collect();
    assert!(
        lines[8].contains("return clamp(1.0 - r * r"),
        "{}",
        lines[8]
    );
    lines.insert(8, "    let broken = no_such_name_here;");
    std::fs::write(&shader, lines.join("\n") + "\n").unwrap();
    let at = format!("{}:9", shader.display());
    let error = watch.wait_for(
        &format!("an error at {at}"),
        Duration::from_secs(120),
        |l| l.contains(&at),
    );
    assert!(error.starts_with("err: "), "{error}");

    // Fix it: a new frame.
    let before = std::fs::metadata(&out).unwrap().modified().unwrap();
    std::fs::write(&shader, &original).unwrap();
    let reloaded = watch.wait_for("a new frame", Duration::from_secs(120), |l| {
        l.starts_with("out: reloaded ")
    });
    assert!(reloaded.contains("shaders"), "{reloaded}");
    assert!(std::fs::metadata(&out).unwrap().modified().unwrap() >= before);
    assert_eq!(image::image_dimensions(&out).unwrap(), (48, 32));
}

#[test]
fn renders_the_default_scene_in_an_empty_folder_from_built_in_files() {
    let dir = tempfile::tempdir().unwrap();
    let out: PathBuf = dir.path().join("default.png");
    let mut command = lightgraph(dir.path());
    command.args(["render", "--width", "40", "--height", "24", "--out"]);
    command.arg(&out);
    let (ok, printed) = run_to_end(command, Duration::from_secs(300));
    assert!(ok, "render failed:\n{printed}");
    assert!(
        printed.contains("graph: <built-in>/graphs/default.ron"),
        "not the built-in graph:\n{printed}"
    );
    assert_eq!(image::image_dimensions(&out).unwrap(), (40, 24));
}

#[test]
fn help_says_where_it_looks_and_watch_without_files_says_why_not() {
    let dir = tempfile::tempdir().unwrap();
    let (ok, help) = run_to_end(
        {
            let mut c = lightgraph(dir.path());
            c.arg("--help");
            c
        },
        Duration::from_secs(60),
    );
    assert!(ok, "{help}");
    for want in [
        "--root",
        "LIGHTGRAPH_ROOT",
        "current directory",
        "Root now: none",
    ] {
        assert!(help.contains(want), "--help lacks {want:?}:\n{help}");
    }
    let (ok, help) = run_to_end(
        {
            let mut c = lightgraph(dir.path());
            c.arg("--root").arg(source_tree()).arg("--help");
            c
        },
        Duration::from_secs(60),
    );
    assert!(ok, "{help}");
    let root = source_tree().canonicalize().unwrap();
    assert!(
        help.contains(&format!("Root now: {} (from --root)", root.display())),
        "{help}"
    );

    let (ok, printed) = run_to_end(
        {
            let mut c = lightgraph(dir.path());
            c.args(["watch", "--out", "x.png"]);
            c
        },
        Duration::from_secs(60),
    );
    assert!(!ok && printed.contains("nothing to watch"), "{printed}");
}
