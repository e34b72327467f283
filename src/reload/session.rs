//! A headless hot-reload session: renders a graph for a scene, watches the shader
//! folder, the graph file and the scene's files, and on every change rebuilds only what
//! depends on it. A broken edit never loses the frame: the last good result stays and
//! the error (with file:line) is kept beside it until the next good save.

use super::{FileWatcher, WatchConfig, WatchError};
use crate::graph::{self, FrameSize};
use crate::render::{FrameResult, PreparedFrame, Renderer, SceneGpu};
use crate::scene::{self, Scene};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Where the scene comes from: a file that is watched and reloaded, or a fixed scene.
pub enum SceneSource {
    File(PathBuf),
    Fixed(Box<Scene>),
}

/// What one reload did.
#[derive(Debug)]
pub struct Reload {
    pub changed: Vec<PathBuf>,
    /// Edit-to-new-frame latency, or the error that kept the last good frame.
    pub outcome: Result<Duration, String>,
}

pub struct ReloadSession {
    pub renderer: Renderer,
    graph_path: PathBuf,
    source: SceneSource,
    scene: Scene,
    gpu: SceneGpu,
    width: u32,
    height: u32,
    watcher: FileWatcher,
    /// The last frame that rendered.
    pub frame: Option<FrameResult>,
    /// The graph of the last good frame, ready to run again (the viewer executes it).
    prepared: Option<PreparedFrame>,
    /// The current error, if the last reload failed.
    pub error: Option<String>,
}

fn load_scene(source: &SceneSource) -> Result<Scene, String> {
    match source {
        SceneSource::File(p) => scene::load(p).map(|l| l.scene).map_err(|e| e.to_string()),
        SceneSource::Fixed(s) => Ok((**s).clone()),
    }
}

impl ReloadSession {
    /// Renders once and starts watching the renderer's shader folder, the graph file,
    /// the scene file and `extra` paths (material folders).
    pub fn new(
        renderer: Renderer,
        graph_path: &Path,
        source: SceneSource,
        width: u32,
        height: u32,
        extra: &[PathBuf],
    ) -> Result<Self, String> {
        let scene = load_scene(&source)?;
        let gpu = SceneGpu::upload(&renderer.ctx.device, &renderer.ctx.queue, &scene)
            .map_err(|e| e.to_string())?;
        let watch_err = |e: WatchError| e.to_string();
        let mut watcher = FileWatcher::new(WatchConfig::default()).map_err(watch_err)?;
        watcher.watch(&renderer.shaders.root).map_err(watch_err)?;
        watcher.watch(graph_path).map_err(watch_err)?;
        if let SceneSource::File(p) = &source {
            watcher.watch(p).map_err(watch_err)?;
        }
        for p in extra {
            watcher.watch(p).map_err(watch_err)?;
        }
        let mut session = Self {
            renderer,
            graph_path: graph_path.to_path_buf(),
            source,
            scene,
            gpu,
            width,
            height,
            watcher,
            frame: None,
            prepared: None,
            error: None,
        };
        let first = session.render()?;
        session.frame = Some(first);
        Ok(session)
    }

    fn render(&mut self) -> Result<FrameResult, String> {
        let checked = graph::check_file(&self.graph_path, &self.renderer.shaders)
            .map_err(|e| e.to_string())?;
        let size = FrameSize {
            width: self.width,
            height: self.height,
            lights: self.scene.lights.len() as u32,
        };
        let compiled = graph::compile(checked, &self.scene.features(), size);
        let stats = compiled.has_forward_shading();
        let prepared = self
            .renderer
            .prepare(compiled, &self.scene, &self.gpu, size, stats)
            .map_err(|e| e.to_string())?;
        let frame = prepared.render(&self.renderer).map_err(|e| e.to_string())?;
        self.prepared = Some(prepared);
        Ok(frame)
    }

    /// The last good graph, prepared: execute it to draw another frame.
    pub fn prepared(&self) -> Option<&PreparedFrame> {
        self.prepared.as_ref()
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    pub fn graph_path(&self) -> &Path {
        &self.graph_path
    }

    /// Reloads whatever changed since the last call, without waiting.
    pub fn poll(&mut self) -> Option<Reload> {
        self.wait(Duration::ZERO)
    }

    /// Switches to another graph file (a variant). On error the old graph keeps rendering.
    pub fn set_graph(&mut self, path: &Path) -> Result<(), String> {
        let old = std::mem::replace(&mut self.graph_path, path.to_path_buf());
        match self.render() {
            Ok(frame) => {
                self.frame = Some(frame);
                self.error = None;
                self.watcher
                    .watch(path)
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            }
            Err(e) => {
                self.graph_path = old;
                Err(e)
            }
        }
    }

    /// Renders at a new size (the viewer's window was resized).
    pub fn resize(&mut self, width: u32, height: u32) -> Result<(), String> {
        let old = (self.width, self.height);
        (self.width, self.height) = (width.max(1), height.max(1));
        match self.render() {
            Ok(frame) => {
                self.frame = Some(frame);
                Ok(())
            }
            Err(e) => {
                (self.width, self.height) = old;
                Err(e)
            }
        }
    }

    /// Waits up to `timeout` for a change, then reloads what it touched. `None` if
    /// nothing changed in time.
    pub fn wait(&mut self, timeout: Duration) -> Option<Reload> {
        let batch = self.watcher.wait_for_change(timeout)?;
        let start = Instant::now();
        let changed: Vec<PathBuf> = batch.paths().map(Path::to_path_buf).collect();
        // Shader edits rebuild only the pipelines whose composed source used the file.
        self.renderer.pipelines.invalidate_files(&changed);
        let shader_root = &self.renderer.shaders.root;
        let scene_touched = changed
            .iter()
            .any(|p| !p.starts_with(shader_root) && *p != self.graph_path);
        let outcome = self.reload(scene_touched).map(|frame| {
            self.frame = Some(frame);
            start.elapsed()
        });
        self.error = outcome.as_ref().err().cloned();
        Some(Reload { changed, outcome })
    }

    fn reload(&mut self, scene_touched: bool) -> Result<FrameResult, String> {
        if scene_touched {
            // Scenes and materials: load both before replacing anything.
            let scene = load_scene(&self.source)?;
            let gpu = SceneGpu::upload(&self.renderer.ctx.device, &self.renderer.ctx.queue, &scene)
                .map_err(|e| e.to_string())?;
            self.scene = scene;
            self.gpu = gpu;
        }
        self.render()
    }
}
