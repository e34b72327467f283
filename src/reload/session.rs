//! A headless hot-reload session: renders a graph for a scene, watches the shader
//! folder, the graph file, the scene file and every material file the scene uses, and on
//! every change rebuilds only what depends on it:
//! - a shader edit drops the pipelines whose composed source used the file;
//! - a material edit reloads that material alone (other materials' pipelines are cache
//!   hits, and depth-only draws never depended on it);
//! - a graph edit recompiles the graph; pipelines whose key did not change are cache hits
//!   and physical textures and buffers whose descriptor did not change are taken over
//!   from the live frame;
//! - a scene edit reloads and uploads the scene.
//!
//! A broken edit never loses the frame: the last good [`PreparedFrame`] and image stay
//! and the error (with file:line) is kept beside it. What failed to load is retried on
//! every later change, so the error stays until that file is fixed.

use super::{normalize_path, ChangeBatch, DependencyIndex, FileWatcher, WatchConfig, WatchError};
use crate::graph::{self, CompiledGraph, FrameSize};
use crate::render::{
    FrameResult, GpuStateAtBuild, MaterialProgram, PipelineBuild, PreparedFrame, RenderTimings,
    Renderer, SceneGpu,
};
use crate::scene::{self, Scene};
use crate::shader::assets;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Where the scene comes from: a file that is watched and reloaded, or a fixed scene.
pub enum SceneSource {
    /// A scene file (RON or glTF), reloaded when it or what it references changes.
    File(PathBuf),
    /// A file watched and reloaded as with `File`, its moving lights placed at the given
    /// seconds on every load (`Scene::place_lights_at`: a still frame, as `render --time`).
    FileAt(PathBuf, f64),
    /// A scene given once, never reloaded.
    Fixed(Box<Scene>),
}

/// Where the time of one reload went. `shader_compose` and `pipeline_build` are part of
/// `prepare`; the parts of `render` are in `frame`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReloadTimings {
    /// Reading, validating and uploading changed scene and material files.
    pub assets: Duration,
    /// Parsing, validating and compiling the graph.
    pub graph: Duration,
    /// `Renderer::prepare` in total: pipelines, resources, bind groups.
    pub prepare: Duration,
    /// Composing shader sources and validating them with naga (pipeline-cache misses).
    pub shader_compose: Duration,
    /// Creating shader modules and pipelines (pipeline-cache misses).
    pub pipeline_build: Duration,
    /// Of `pipeline_build`: `create_shader_module`.
    pub shader_modules: Duration,
    /// Of `pipeline_build`: `create_render/compute_pipeline` (with layouts).
    pub pipeline_create: Duration,
    /// Wall time of `shader_compose` and `pipeline_build` together: less than their sum
    /// when pipelines were built in parallel.
    pub build_wall: Duration,
    /// Each pipeline built, named by pass and material.
    pub builds: Vec<PipelineBuild>,
    /// Whether the GPU was busy with earlier frames when the first build began.
    pub gpu_at_build: GpuStateAtBuild,
    /// Executing the new frame and reading it back.
    pub render: Duration,
    /// The parts of `render` (submit, GPU wait, GPU time, readbacks); `None` when the
    /// reload rendered nothing.
    pub frame: Option<RenderTimings>,
}

/// What one reload did.
#[derive(Debug)]
pub struct Reload {
    /// The files whose change started this reload.
    pub changed: Vec<PathBuf>,
    /// Time from the batch's arrival to the new frame, or the error that kept the last
    /// good frame. The watcher's debounce came before `received` and is not included:
    /// measure edit-to-frame from the file write to `finished`.
    pub outcome: Result<Duration, String>,
    /// When the watcher delivered the batch.
    pub received: Instant,
    /// When the new frame was ready and read back (or the reload gave up).
    pub finished: Instant,
    /// When the new frame's GPU work was done, before it was read back: what a viewer
    /// presents from then on (`None` if nothing rendered).
    pub frame_ready: Option<Instant>,
    /// What was reloaded: `graph`, `scene`, `material <name>`, `shaders`; empty when the
    /// batch touched nothing the frame uses.
    pub rebuilt: Vec<String>,
    /// Where the time went.
    pub timings: ReloadTimings,
}

/// Dependency-index keys of what a session loads from files.
const GRAPH: &str = "graph";
const SCENE: &str = "scene";
const MATERIAL: &str = "material ";

fn material_key(name: &str) -> String {
    format!("{MATERIAL}{name}")
}

/// A live frame that follows its files: watches the graph, scene, shaders and materials,
/// and rebuilds only what a change touches, keeping the last good frame while an edit is
/// broken.
pub struct ReloadSession {
    /// The renderer every rebuild uses.
    pub renderer: Renderer,
    graph_path: PathBuf,
    source: SceneSource,
    scene: Scene,
    gpu: SceneGpu,
    width: u32,
    height: u32,
    watcher: FileWatcher,
    shader_root: PathBuf,
    /// Files → what is loaded from them (graph, scene, each overridden material).
    deps: DependencyIndex,
    /// What changed on disk but has not loaded yet (retried on every reload).
    stale: BTreeSet<String>,
    /// The last frame that prepared and rendered, ready to execute again.
    prepared: Option<PreparedFrame>,
    /// Whether frames include the light statistics pass.
    light_stats: bool,
    /// Whether a reload reads its new frame back into `frame` (a viewer, which presents
    /// the output texture itself, does not wait for that).
    read_back: bool,
    /// The last frame that rendered.
    pub frame: Option<FrameResult>,
    /// The current error, if the last reload failed.
    pub error: Option<String>,
    /// The undrawn-content warnings already logged: a resize or a reload that recompiles
    /// the graph does not repeat them.
    reported: std::cell::RefCell<graph::coverage::Reported>,
}

/// [`normalize_path`], except for built-in files' names (`<built-in>/...`).
fn normalize(path: &Path) -> PathBuf {
    match assets::builtin_rel(path) {
        Some(_) => path.to_path_buf(),
        None => normalize_path(path),
    }
}

/// The scene and every file it was read from (models, their buffers and images).
fn load_scene(source: &SceneSource) -> Result<(Scene, Vec<PathBuf>), String> {
    match source {
        // A light-less model gets the headlight `render` gives it (the window shows what
        // `render --out` writes). It stays where the scene's camera was.
        SceneSource::File(p) => scene::load(p)
            .map(|mut l| {
                l.scene.add_headlight_if_unlit();
                (l.scene, l.files)
            })
            .map_err(|e| e.to_string()),
        SceneSource::FileAt(p, time) => {
            let (mut scene, files) = load_scene(&SceneSource::File(p.clone()))?;
            scene.place_lights_at(*time);
            Ok((scene, files))
        }
        SceneSource::Fixed(s) => Ok(((**s).clone(), Vec::new())),
    }
}

/// Each overridden material's name with the files it was read from.
type MaterialFiles = Vec<(String, Vec<PathBuf>)>;

/// Uploads a scene; also returns, for each material the scene overrides, the files it
/// was read from (the override RON and its textures).
fn upload_scene(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &Scene,
) -> Result<(SceneGpu, MaterialFiles), String> {
    if scene.materials.is_empty() {
        // The default material: nothing to override, nothing to watch.
        let gpu = SceneGpu::upload(device, queue, scene).map_err(|e| e.to_string())?;
        return Ok((gpu, Vec::new()));
    }
    let mut programs = Vec::new();
    let mut files = Vec::new();
    // Materials that read one image share its GPU copy.
    let mut uploads = crate::render::materials::TextureUploads::default();
    for surface in &scene.materials {
        let (program, used) =
            MaterialProgram::for_surface(device, queue, scene, surface, &mut uploads)
                .map_err(|e| e.to_string())?;
        if !used.is_empty() {
            files.push((surface.name.clone(), used));
        }
        programs.push(program);
    }
    Ok((SceneGpu::upload_with(device, scene, programs), files))
}

/// A candidate state, built beside the live one and swapped in only if it rendered.
struct Candidate {
    /// The stale dependents it loaded.
    resolved: BTreeSet<String>,
    /// A reloaded scene, its overridden materials' files and the files it was read from.
    scene: Option<(Scene, MaterialFiles, Vec<PathBuf>)>,
    /// New GPU data (a reloaded scene, or the live one with some materials replaced).
    gpu: Option<SceneGpu>,
    /// The files of materials reloaded alone.
    materials: MaterialFiles,
    prepared: PreparedFrame,
    /// The frame read back (`None` without readback).
    frame: Option<FrameResult>,
    prepare_time: Duration,
    render_time: Duration,
    render_timings: RenderTimings,
}

impl ReloadSession {
    /// Renders once and starts watching the renderer's shader folder (if it is on disk),
    /// the graph file (unless it is built in), the scene file, every material file the scene overrides a material with (wherever
    /// it lies, with its textures) and `extra` paths (material folders).
    pub fn new(
        renderer: Renderer,
        graph_path: &Path,
        source: SceneSource,
        width: u32,
        height: u32,
        extra: &[PathBuf],
    ) -> Result<Self, String> {
        let (scene, scene_files) = load_scene(&source)?;
        let (gpu, materials) = upload_scene(&renderer.ctx.device, &renderer.ctx.queue, &scene)?;
        let watch_err = |e: WatchError| e.to_string();
        let mut watcher = FileWatcher::new(WatchConfig::default()).map_err(watch_err)?;
        // With no shader folder on disk (built-in shaders only) there is none to watch.
        let shader_root = if renderer.shaders.root.is_dir() {
            watcher.watch(&renderer.shaders.root).map_err(watch_err)?
        } else {
            normalize(&renderer.shaders.root)
        };
        for p in extra {
            watcher.watch(p).map_err(watch_err)?;
        }
        let mut session = Self {
            renderer,
            graph_path: normalize(graph_path),
            source,
            scene,
            gpu,
            width,
            height,
            watcher,
            shader_root,
            deps: DependencyIndex::new(),
            stale: BTreeSet::new(),
            prepared: None,
            light_stats: false,
            read_back: true,
            frame: None,
            error: None,
            reported: Default::default(),
        };
        session.watch_dependency(GRAPH, vec![session.graph_path.clone()])?;
        if !scene_files.is_empty() {
            session.watch_dependency(SCENE, scene_files)?;
        }
        for (name, files) in materials {
            session.watch_dependency(&material_key(&name), files)?;
        }
        let graph = session.compile_graph(&session.scene)?;
        let candidate = session.prepare_and_render(graph, None, None)?;
        session.commit(candidate);
        Ok(session)
    }

    /// Whether reloads read the new frame back into [`frame`](Self::frame) (on by
    /// default). A viewer presents the output texture and turns it off: its reloads end
    /// when the frame's GPU work is done, and `frame` stays `None` from then on.
    pub fn set_image_readback(&mut self, on: bool) {
        self.read_back = on;
    }

    /// The last good prepared frame (what `frame` was rendered from), to execute again
    /// without readback, e.g. by a window viewer.
    pub fn prepared(&self) -> Option<&PreparedFrame> {
        self.prepared.as_ref()
    }

    /// The scene the live frame shows.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The live frame's scene upload (what `PreparedFrame::update_lights` writes).
    pub fn gpu(&self) -> &SceneGpu {
        &self.gpu
    }

    /// The graph file the session renders (normalised).
    pub fn graph_path(&self) -> &Path {
        &self.graph_path
    }

    /// Every file the session reloads something from, except shaders (watched as a
    /// folder): the graph, the scene file, material overrides and their textures.
    pub fn watched_files(&self) -> Vec<PathBuf> {
        self.deps.paths().map(Path::to_path_buf).collect()
    }

    /// Waits up to `timeout` for a change, then reloads what it touched. `None` if
    /// nothing changed in time.
    pub fn wait(&mut self, timeout: Duration) -> Option<Reload> {
        let mut batch = self.watcher.wait_for_change(timeout)?;
        let received = Instant::now();
        if let Some(more) = self.watcher.drain() {
            batch.merge(more);
        }
        Some(self.apply(batch, received))
    }

    /// Reloads what the changes ready now touched, without waiting; `None` if there are
    /// none.
    pub fn poll(&mut self) -> Option<Reload> {
        let batch = self.watcher.drain()?;
        Some(self.apply(batch, Instant::now()))
    }

    /// Switches to another graph file: watches it, compiles it and prepares it, taking
    /// over the live frame's resources where they fit. On error the old graph and frame
    /// stay and the error (with file:line) is returned.
    pub fn set_graph(&mut self, path: &Path) -> Result<(), String> {
        let path = normalize(path);
        if assets::builtin_rel(&path).is_none() {
            self.watcher.watch(&path).map_err(|e| e.to_string())?;
        }
        let old = std::mem::replace(&mut self.graph_path, path.clone());
        let candidate = self
            .compile_graph(&self.scene)
            .and_then(|graph| self.prepare_and_render(graph, None, None));
        match candidate {
            Ok(mut c) => {
                self.deps.set_dependencies(GRAPH, [path]);
                c.resolved.insert(GRAPH.to_string());
                self.commit(c);
                if self.stale.is_empty() {
                    self.error = None;
                }
                Ok(())
            }
            Err(e) => {
                self.graph_path = old;
                Err(e)
            }
        }
    }

    /// Renders at a new size (the viewer's window was resized). On error the old size
    /// and frame stay.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<(), String> {
        let old = (self.width, self.height);
        (self.width, self.height) = (width.max(1), height.max(1));
        let result = self.reprepare();
        if result.is_err() {
            (self.width, self.height) = old;
        }
        result
    }

    /// Adds or removes the per-pixel light statistics pass (listed against exact lights
    /// per pixel). It is a brute-force pass, so it is off unless asked for.
    pub fn set_light_stats(&mut self, on: bool) -> Result<(), String> {
        let old = std::mem::replace(&mut self.light_stats, on);
        let result = self.reprepare();
        if result.is_err() {
            self.light_stats = old;
        }
        result
    }

    /// Prepares the live graph again with the current settings.
    fn reprepare(&mut self) -> Result<(), String> {
        let candidate = self
            .compile_graph(&self.scene)
            .and_then(|graph| self.prepare_and_render(graph, None, None))?;
        self.commit(candidate);
        Ok(())
    }

    /// Reloads what `batch` touched (and whatever still failed to load before).
    fn apply(&mut self, batch: ChangeBatch, received: Instant) -> Reload {
        let changed: Vec<PathBuf> = batch.paths().map(Path::to_path_buf).collect();
        // Shader edits rebuild only the pipelines whose composed source used the file.
        self.renderer.pipelines.invalidate_files(&changed);
        let shaders = changed.iter().any(|p| p.starts_with(&self.shader_root));
        self.stale.extend(self.deps.affected(&changed));
        let mut rebuilt: Vec<String> = self.stale.iter().cloned().collect();
        if shaders {
            rebuilt.push("shaders".into());
        }
        let mut timings = ReloadTimings::default();
        let mut frame_ready = None;
        let outcome = if rebuilt.is_empty() {
            // Nothing the frame uses (another material in a watched folder, say).
            Ok(received.elapsed())
        } else {
            self.reload(shaders, &mut timings).map(|candidate| {
                frame_ready = Some(candidate.render_timings.gpu_done);
                self.commit(candidate);
                received.elapsed()
            })
        };
        self.error = outcome.as_ref().err().cloned();
        let finished = Instant::now();
        if !timings.builds.is_empty() {
            // After the frame, outside the latency: what the builds added to the driver's
            // pipeline cache goes to disk.
            self.renderer.pipelines.save_driver_cache();
        }
        Reload {
            changed,
            outcome,
            received,
            finished,
            frame_ready,
            rebuilt,
            timings,
        }
    }

    /// Builds the new state from the stale dependents and renders it, replacing nothing.
    fn reload(&mut self, shaders: bool, t: &mut ReloadTimings) -> Result<Candidate, String> {
        let start = Instant::now();
        let device = self.renderer.ctx.device.clone();
        let queue = self.renderer.ctx.queue.clone();
        let mut scene = None;
        let mut gpu = None;
        let mut materials = Vec::new();
        if self.stale.contains(SCENE) {
            let (s, scene_files) = load_scene(&self.source)?;
            let (g, files) = upload_scene(&device, &queue, &s)?;
            gpu = Some(g);
            scene = Some((s, files, scene_files));
        } else {
            // Materials alone: a copy of the live scene's GPU data with those replaced.
            for key in &self.stale {
                let Some(name) = key.strip_prefix(MATERIAL) else {
                    continue;
                };
                let mut files = Vec::new();
                for (i, surface) in self.scene.materials.iter().enumerate() {
                    if surface.name != name {
                        continue;
                    }
                    // A reloaded material uploads its textures afresh (its files may
                    // have changed).
                    let mut uploads = crate::render::materials::TextureUploads::default();
                    let (program, used) = MaterialProgram::for_surface(
                        &device,
                        &queue,
                        &self.scene,
                        surface,
                        &mut uploads,
                    )
                    .map_err(|e| e.to_string())?;
                    gpu.get_or_insert_with(|| self.gpu.clone())
                        .set_material(i, program);
                    files = used;
                }
                materials.push((name.to_string(), files));
            }
        }
        t.assets = start.elapsed();
        let start = Instant::now();
        let graph_unchanged = scene.is_none() && !shaders && !self.stale.contains(GRAPH);
        let graph = match (&self.prepared, graph_unchanged) {
            // A material edit changes neither the graph nor the scene's features.
            (Some(p), true) => p.graph.clone(),
            _ => self.compile_graph(scene.as_ref().map_or(&self.scene, |(s, _, _)| s))?,
        };
        t.graph = start.elapsed();
        let mut c =
            self.prepare_and_render(graph, scene.as_ref().map(|(s, _, _)| s), gpu.as_ref())?;
        t.prepare = c.prepare_time;
        t.render = c.render_time;
        t.frame = Some(c.render_timings);
        let stats = c.prepared.stats();
        t.shader_compose = stats.shader_compose;
        t.pipeline_build = stats.pipeline_build;
        t.shader_modules = stats.shader_modules;
        t.pipeline_create = stats.pipeline_create;
        t.build_wall = stats.build_wall;
        t.builds = stats.builds.clone();
        t.gpu_at_build = stats.gpu_at_build;
        c.resolved = self.stale.clone();
        c.scene = scene;
        c.gpu = gpu;
        c.materials = materials;
        Ok(c)
    }

    fn compile_graph(&self, scene: &Scene) -> Result<CompiledGraph, String> {
        let checked = assets::check_graph(&self.graph_path, &self.renderer.shaders)
            .map_err(|e| e.to_string())?;
        let features = scene.features();
        let compiled = graph::compile(checked, &features, self.frame_size(scene));
        for w in self
            .reported
            .borrow_mut()
            .new_warnings(&compiled, &features)
        {
            log::warn!("{w}");
        }
        Ok(compiled)
    }

    fn frame_size(&self, scene: &Scene) -> FrameSize {
        FrameSize {
            width: self.width,
            height: self.height,
            lights: scene.lights.len() as u32,
        }
    }

    /// Prepares `graph` for the given scene and GPU data (default: the live ones), taking
    /// resources from the live frame where they fit, and renders it.
    fn prepare_and_render(
        &mut self,
        graph: CompiledGraph,
        scene: Option<&Scene>,
        gpu: Option<&SceneGpu>,
    ) -> Result<Candidate, String> {
        let scene = scene.unwrap_or(&self.scene);
        let gpu = gpu.unwrap_or(&self.gpu);
        let size = self.frame_size(scene);
        let start = Instant::now();
        // Light statistics only when asked for: that brute-force pass would run on every
        // frame a viewer executes and is most of a reload's time on a CPU adapter.
        let stats = self.light_stats && graph.has_forward_shading();
        let prepared = self
            .renderer
            .prepare_reusing(graph, scene, gpu, size, stats, self.prepared.as_ref())
            .map_err(|e| e.to_string())?;
        let prepare_time = start.elapsed();
        let start = Instant::now();
        let (frame, render_timings) = if self.read_back {
            let (frame, t) = prepared
                .render_timed(&self.renderer)
                .map_err(|e| e.to_string())?;
            (Some(frame), t)
        } else {
            let (_, t) = prepared
                .execute_timed(&self.renderer)
                .map_err(|e| e.to_string())?;
            (None, t)
        };
        Ok(Candidate {
            resolved: BTreeSet::new(),
            scene: None,
            gpu: None,
            materials: Vec::new(),
            prepared,
            frame,
            prepare_time,
            render_time: start.elapsed(),
            render_timings,
        })
    }

    /// Swaps a candidate in and re-registers the files of what it reloaded.
    fn commit(&mut self, c: Candidate) {
        let generation = c.prepared.stats().cache_generation;
        let mut materials = c.materials;
        if let Some((scene, files, scene_files)) = c.scene {
            // A model the scene file now names is watched from here on.
            if let Err(e) = self.watch_dependency(SCENE, scene_files) {
                log::warn!("hot reload: {e}");
            }
            // A new scene may override other materials, from other files.
            let old: Vec<String> = self
                .deps
                .dependents()
                .filter(|d| d.starts_with(MATERIAL))
                .map(str::to_string)
                .collect();
            for d in old {
                self.deps.remove_dependent(&d);
            }
            self.scene = scene;
            materials = files;
        }
        if let Some(gpu) = c.gpu {
            self.gpu = gpu;
        }
        self.prepared = Some(c.prepared);
        self.frame = c.frame;
        self.stale.retain(|d| !c.resolved.contains(d));
        // Pipelines that only replaced frames used (old material versions) are dropped.
        self.renderer.pipelines.evict_unused_since(generation);
        for (name, files) in materials {
            // The frame is in; a file that cannot be watched only loses future reloads.
            if let Err(e) = self.watch_dependency(&material_key(&name), files) {
                log::warn!("hot reload: {e}");
            }
        }
    }

    fn watch_dependency(&mut self, key: &str, files: Vec<PathBuf>) -> Result<(), String> {
        // Built-in files (`<built-in>/...`) never change: nothing to watch.
        for f in files.iter().filter(|f| assets::builtin_rel(f).is_none()) {
            self.watcher.watch(f).map_err(|e| e.to_string())?;
        }
        self.deps.set_dependencies(key, files);
        Ok(())
    }
}
