//! Hot reload: `watch` (headless) and `view` (a window).

use super::render::{load_scene, write_image};
use super::{project_path, ViewArgs};
use anyhow::{bail, Context, Result};
use lightgraph::render::Renderer;
use lightgraph::shader::assets;
use std::path::{Path, PathBuf};

pub fn watch(
    scene: Option<PathBuf>,
    graph: Option<PathBuf>,
    width: u32,
    height: u32,
    out: &Path,
    time: Option<f64>,
) -> Result<()> {
    use lightgraph::reload::{ReloadSession, SceneSource};
    if time.is_some_and(|t| !t.is_finite()) {
        bail!("--time must be a finite number of seconds");
    }
    // Moving lights are placed where `render --time` places them (time 0 by default), on
    // the first load and every reload.
    let time = time.unwrap_or(0.0);
    let project = assets::project();
    if project.root.is_none() && graph.is_none() && scene.is_none() {
        bail!(
            "nothing to watch: {} has no shaders/, graphs/ or materials/ and no --root or {} \
             was given, so only the built-in files would be used. Run `lightgraph watch` in a \
             folder that has them, or pass --root DIR (see `lightgraph --help`).",
            std::env::current_dir().unwrap_or_default().display(),
            assets::ROOT_ENV
        );
    }
    println!("{}", watched_root(&project));
    let graph = graph.unwrap_or_else(|| project_path("graphs/default.ron"));
    let source = match scene {
        Some(p) => SceneSource::FileAt(p, time),
        None => {
            let mut scene = load_scene(None)?;
            scene.place_lights_at(time);
            SceneSource::Fixed(Box::new(scene))
        }
    };
    let renderer = Renderer::headless()?;
    let materials: Vec<PathBuf> = project.disk_folder("materials").into_iter().collect();
    let mut session = ReloadSession::new(renderer, &graph, source, width, height, &materials)
        .map_err(anyhow::Error::msg)?;
    let write = |s: &ReloadSession| -> Result<()> {
        write_image(out, s.frame.as_ref().expect("a first frame"))
    };
    write(&session)?;
    println!(
        "watching; wrote {} (edit a shader, material, graph or the scene; Ctrl-C stops)",
        out.display()
    );
    loop {
        let Some(reload) = session.wait(std::time::Duration::from_secs(3600)) else {
            continue;
        };
        let names: Vec<String> = reload
            .changed
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        match &reload.outcome {
            Ok(_) if reload.rebuilt.is_empty() => {
                println!("not used by this frame: {}", names.join(", "));
            }
            Ok(latency) => {
                write(&session)?;
                println!(
                    "reloaded {} in {:.1} ms after the change was seen: {}",
                    reload.rebuilt.join(", "),
                    latency.as_secs_f64() * 1e3,
                    names.join(", ")
                );
            }
            Err(e) => eprintln!("error (still showing the last good frame):\n{e}"),
        }
    }
}

pub fn view(args: ViewArgs) -> Result<()> {
    use lightgraph::reload::SceneSource;
    use lightgraph::view::{self, ViewOptions};
    if !(args.scale > 0.0 && args.scale <= 4.0) {
        bail!("--scale must be in (0, 4], got {}", args.scale);
    }
    let project = assets::project();
    println!("{}", watched_root(&project));
    let (graph, variants) = match args.graph {
        // The project's graphs: the root's own and the built-in ones.
        None => (
            project_path("graphs/default.ron"),
            project.list("graphs", "ron"),
        ),
        Some(graph) => {
            let folder = graph.parent().unwrap_or(Path::new(".")).to_path_buf();
            let mut variants: Vec<PathBuf> = std::fs::read_dir(&folder)
                .with_context(|| format!("listing graph variants in {}", folder.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "ron"))
                .collect();
            variants.sort();
            (graph, variants)
        }
    };
    let (scene, scene_name) = match args.scene {
        Some(p) => {
            let name = p.display().to_string();
            (SceneSource::File(p), name)
        }
        None => (
            SceneSource::Fixed(Box::new(load_scene(None)?)),
            "atrium (built-in)".to_string(),
        ),
    };
    view::run(ViewOptions {
        scene,
        scene_name,
        graph,
        variants,
        watch: project.disk_folder("materials").into_iter().collect(),
        window_size: [args.width, args.height],
        render_scale: args.scale,
        exposure_ev: args.exposure,
        screenshot: args.screenshot.map(|p| (p, args.frames.max(1))),
    })?;
    Ok(())
}

/// What a hot-reload session watches of the project, in one line.
fn watched_root(project: &assets::Project) -> String {
    match &project.root {
        Some(_) => {
            let on_disk: Vec<&str> = assets::FOLDERS
                .into_iter()
                .filter(|f| project.disk_folder(f).is_some())
                .collect();
            format!(
                "root: {}; watching {} there",
                project.describe(),
                if on_disk.is_empty() {
                    "nothing".to_string()
                } else {
                    on_disk.join("/, ") + "/"
                }
            )
        }
        None => "root: none (built-in files only): only the files given on the command \
                 line are watched"
            .to_string(),
    }
}
