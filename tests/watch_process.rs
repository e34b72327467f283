//! `lightgraph watch` as a process, as a user runs it: every bad input of tests/bad saved
//! over its graph, its scene and a material the scene uses ends in the error the bad file
//! expects on stderr while the process keeps running, and the good files saved again are
//! rendered again. (tests/bad_inputs_watch.rs checks the same through the library's
//! `ReloadSession`; this one also covers the CLI around it: a panic or an `expect` there,
//! or an error returned from the watch loop, would end the process.)

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};
#[path = "common/watched_project.rs"]
mod watched_project;
use watched_project::{expected, ron_files, root, WatchedProject};

/// The running `watch` and what it has printed so far, both streams as lines.
struct Watch {
    child: Child,
    lines: Receiver<(bool, String)>,
    stdout: String,
    stderr: String,
}

impl Watch {
    fn start(dir: &Path, args: &[&str]) -> Watch {
        let mut child = Command::new(env!("CARGO_BIN_EXE_lightgraph"))
            .current_dir(dir)
            .arg("watch")
            .args(args)
            // The repository as the root: bad graphs name shaders in tests/bad/shaders
            // relative to its shaders/.
            .env("LIGHTGRAPH_ROOT", root())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("the binary runs");
        let (tx, lines) = channel();
        let out = child.stdout.take().unwrap();
        let err = child.stderr.take().unwrap();
        for (is_err, stream) in [
            (false, Box::new(out) as Box<dyn std::io::Read + Send>),
            (true, Box::new(err)),
        ] {
            let tx = tx.clone();
            std::thread::spawn(move || {
                for line in BufReader::new(stream).lines().map_while(Result::ok) {
                    if tx.send((is_err, line)).is_err() {
                        break;
                    }
                }
            });
        }
        Watch {
            child,
            lines,
            stdout: String::new(),
            stderr: String::new(),
        }
    }

    /// Moves what the process printed (within `d`) into `stdout` and `stderr`.
    fn pump(&mut self, d: Duration) {
        let mut next = self.lines.recv_timeout(d).ok();
        while let Some((is_err, line)) = next {
            let text = if is_err {
                &mut self.stderr
            } else {
                &mut self.stdout
            };
            text.push_str(&line);
            text.push('\n');
            next = self.lines.try_recv().ok();
        }
    }

    /// Waits (at most `limit`) until the text printed from `since` on satisfies `done`;
    /// false if it did not. Panics if the process ends.
    fn wait_for(
        &mut self,
        since: (usize, usize),
        what: &str,
        limit: Duration,
        done: impl Fn(&str, &str) -> bool,
    ) -> bool {
        let deadline = Instant::now() + limit;
        loop {
            if done(&self.stdout[since.0..], &self.stderr[since.1..]) {
                return true;
            }
            if let Some(status) = self.child.try_wait().unwrap() {
                self.pump(Duration::from_millis(500));
                panic!(
                    "watch ended ({status}) while waiting for {what}\nstdout:\n{}\nstderr:\n{}",
                    self.stdout, self.stderr
                );
            }
            if Instant::now() >= deadline {
                return false;
            }
            self.pump(Duration::from_millis(100));
        }
    }

    /// [`Self::wait_for`] that must succeed within 60 s.
    fn expect(&mut self, since: (usize, usize), what: &str, done: impl Fn(&str, &str) -> bool) {
        if !self.wait_for(since, what, Duration::from_secs(60), done) {
            panic!(
                "no {what} within 60 s\nstdout since:\n{}\nstderr since:\n{}",
                &self.stdout[since.0..],
                &self.stderr[since.1..]
            );
        }
    }

    fn mark(&self) -> (usize, usize) {
        (self.stdout.len(), self.stderr.len())
    }
}

impl Drop for Watch {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

#[test]
fn the_watch_process_survives_every_bad_save() {
    let project = WatchedProject::new();
    let t = project.dir.path();
    let (graph, material, scene) = (&project.graph, &project.material, &project.scene);
    let (good_graph, good_material, good_scene) = (
        &project.good_graph,
        &project.good_material,
        &project.good_scene,
    );
    let hostile = root().join("tests/bad/hostile");
    let out = t.join("out.png");

    let mut w = Watch::start(
        t,
        &[
            "--scene",
            "scene.ron",
            "--graph",
            "graph.ron",
            "--width",
            "64",
            "--height",
            "36",
            "--out",
            "out.png",
        ],
    );
    w.expect((0, 0), "the first frame", |o, _| {
        o.contains("watching; wrote")
    });
    assert_eq!(image::image_dimensions(&out).unwrap(), (64, 36));

    let mut failures = Vec::new();
    let mut checked = 0;
    // Saves `text` over `file` and waits for the error naming `want` (the saved file's
    // name in place of the bad file's).
    let mut save_bad = |w: &mut Watch, file: &Path, bad: &Path| {
        let text = std::fs::read(bad).unwrap();
        let Some(want) = expected(&String::from_utf8_lossy(&text)).map(str::to_string) else {
            return;
        };
        let name = |p: &Path| p.file_name().unwrap().to_string_lossy().into_owned();
        let want = want.replace(&name(bad), &name(file));
        let since = w.mark();
        std::fs::write(file, &text).unwrap();
        w.expect(
            since,
            &format!("the outcome of {}", bad.display()),
            |o, e| {
                e.contains("error (still showing the last good frame)") || o.contains("reloaded ")
            },
        );
        // The error's lines may still be arriving.
        w.wait_for(since, &want, Duration::from_secs(5), |_, e| {
            e.contains(&want)
        });
        if !w.stderr[since.1..].contains(&want) {
            failures.push(format!(
                "{}: want {want:?}, got:\n{}{}",
                bad.display(),
                &w.stdout[since.0..],
                &w.stderr[since.1..]
            ));
        }
        checked += 1;
    };
    // Saves a good file again and waits until it is rendered and written.
    let save_good = |w: &mut Watch, file: &Path, text: &[u8]| {
        let since = w.mark();
        std::fs::remove_file(&out).unwrap();
        std::fs::write(file, text).unwrap();
        w.expect(
            since,
            &format!("{} rendered again", file.display()),
            |o, _| o.contains("reloaded "),
        );
        assert_eq!(image::image_dimensions(&out).unwrap(), (64, 36));
    };
    for bad in ron_files(&root().join("tests/bad/graphs")) {
        save_bad(&mut w, graph, &bad);
    }
    save_good(&mut w, graph, good_graph);
    for bad in ron_files(&hostile) {
        save_bad(&mut w, scene, &bad);
    }
    save_good(&mut w, scene, good_scene);
    // 38 when written (27 graphs, 11 hostile scenes): a test that checks nothing fails.
    assert!(
        checked >= 30,
        "only {checked} bad files have an expected message"
    );

    // A material saved with a texture wider than the device is scaled down, not fatal.
    let wide = std::fs::read_to_string(hostile.join("wide_texture_material.ron")).unwrap();
    let since = w.mark();
    std::fs::write(material, wide).unwrap();
    w.expect(since, "the wide texture's reload", |o, e| {
        o.contains("reloaded ") || e.contains("error (still showing")
    });
    let since = w.mark();
    std::fs::write(material, good_material).unwrap();
    w.expect(since, "the good material rendered again", |o, _| {
        o.contains("reloaded ")
    });
    assert!(
        w.child.try_wait().unwrap().is_none(),
        "watch is still running"
    );
    assert!(failures.is_empty(), "\n{}", failures.join("\n\n"));
}
