//! The window loop: input → camera, reloads, one graph frame, present, overlay.

use super::camera::{CameraController, CameraMode, Movement};
use super::overlay::{FrameInfo, Overlay, OverlayAction};
use super::{ViewError, ViewOptions};
use crate::gpu::readback::read_texture;
use crate::gpu::GpuContext;
use crate::reload::ReloadSession;
use crate::render::Presenter;
use crate::render::Renderer;
use crate::shader::ShaderLibrary;
use std::collections::HashSet;
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// Opens the window and runs until it is closed (or the screenshot is taken).
pub fn run(options: ViewOptions) -> Result<(), ViewError> {
    let event_loop = EventLoop::new().map_err(|e| ViewError::Window(e.to_string()))?;
    let mut app = App {
        options: Some(options),
        viewer: None,
        outcome: Ok(()),
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| ViewError::Window(e.to_string()))?;
    app.outcome
}

struct App {
    options: Option<ViewOptions>,
    viewer: Option<Viewer>,
    outcome: Result<(), ViewError>,
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: ViewError) {
        self.outcome = Err(e);
        event_loop.exit();
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        let Some(options) = self.options.take() else {
            return; // resumed again after a suspend: the viewer is still there
        };
        match Viewer::new(event_loop, options) {
            Ok(v) => self.viewer = Some(v),
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(viewer) = self.viewer.as_mut() else {
            return;
        };
        match viewer.handle(&event) {
            Ok(Flow::Continue) => {}
            Ok(Flow::Exit) => event_loop.exit(),
            Err(e) => self.fail(event_loop, e),
        }
    }
}

enum Flow {
    Continue,
    Exit,
}

/// Mouse and key state between events.
#[derive(Default)]
struct Input {
    held: HashSet<KeyCode>,
    dragging: bool,
    cursor: Option<(f64, f64)>,
}

impl Input {
    fn movement(&self) -> Movement {
        let axis = |plus, minus| {
            (self.held.contains(&plus) as i32 - self.held.contains(&minus) as i32) as f32
        };
        Movement {
            right: axis(KeyCode::KeyD, KeyCode::KeyA),
            up: axis(KeyCode::KeyE, KeyCode::KeyQ),
            forward: axis(KeyCode::KeyW, KeyCode::KeyS),
            fast: self.held.contains(&KeyCode::ShiftLeft)
                || self.held.contains(&KeyCode::ShiftRight),
        }
    }
}

struct Viewer {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    session: ReloadSession,
    presenter: Presenter,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    camera: CameraController,
    overlay: Overlay,
    info: FrameInfo,
    input: Input,
    render_scale: f32,
    screenshot: Option<(std::path::PathBuf, u32)>,
    frames: u32,
    last_frame: Instant,
    light_clock: super::animation::LightClock,
}

/// Weight of the newest sample in the overlay's running averages (about 20 frames).
const SMOOTHING: f64 = 0.05;
/// Light statistics are read back every this many frames (a readback stalls the GPU).
const REPORT_EVERY: u32 = 15;

fn render_size(window: [u32; 2], scale: f32) -> [u32; 2] {
    window.map(|v| ((v as f32 * scale).round() as u32).max(1))
}

impl Viewer {
    fn new(event_loop: &ActiveEventLoop, options: ViewOptions) -> Result<Self, ViewError> {
        let [w, h] = options.window_size;
        let attributes = Window::default_attributes()
            .with_title(format!("lightgraph — {}", options.scene_name))
            .with_inner_size(winit::dpi::PhysicalSize::new(w, h));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| ViewError::Window(e.to_string()))?,
        );
        let mut desc = wgpu::InstanceDescriptor::new_with_display_handle(Box::new(
            event_loop.owned_display_handle(),
        ));
        desc.backends = wgpu::Backends::VULKAN;
        let instance = wgpu::Instance::new(desc);
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| ViewError::Surface(e.to_string()))?;
        let ctx = GpuContext::for_surface(&instance, &surface)?;
        let config = surface_config(&surface, &ctx.adapter, window.inner_size().into())?;
        surface.configure(&ctx.device, &config);
        if options.screenshot.is_some() && !config.usage.contains(wgpu::TextureUsages::COPY_SRC) {
            return Err(ViewError::Surface(
                "this window surface cannot be copied, so no screenshot can be taken".into(),
            ));
        }

        let renderer = Renderer::new(ctx, ShaderLibrary::builtin());
        let presenter = Presenter::new(&renderer, config.format)?;
        let egui_renderer =
            egui_wgpu::Renderer::new(&renderer.ctx.device, config.format, Default::default());
        let adapter = renderer.ctx.adapter_name();
        let [rw, rh] = render_size([config.width, config.height], options.render_scale);
        let session = ReloadSession::new(
            renderer,
            &options.graph,
            options.scene,
            rw,
            rh,
            &options.watch,
        )
        .map_err(ViewError::Session)?;
        // The window presents the output texture: reloads need not read it back.
        let mut session = session;
        session.set_image_readback(false);
        let camera = CameraController::new(&session.scene().camera);
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            event_loop,
            Some(window.scale_factor() as f32),
            None,
            None,
        );
        let info = FrameInfo {
            adapter,
            scene: options.scene_name,
            lights: session.scene().lights.len(),
            render_size: [rw, rh],
            ..Default::default()
        };
        let overlay = Overlay {
            graphs: options.variants,
            current_graph: options.graph,
            camera_mode: camera.mode,
            exposure_ev: options.exposure_ev,
            visible: true,
            light_stats: false,
        };
        window.request_redraw();
        Ok(Self {
            window,
            surface,
            config,
            session,
            presenter,
            egui_ctx,
            egui_state,
            egui_renderer,
            camera,
            overlay,
            info,
            input: Input::default(),
            render_scale: options.render_scale,
            screenshot: options.screenshot,
            frames: 0,
            last_frame: Instant::now(),
            light_clock: Default::default(),
        })
    }

    fn handle(&mut self, event: &WindowEvent) -> Result<Flow, ViewError> {
        let egui_wants = self
            .egui_state
            .on_window_event(&self.window, event)
            .consumed;
        match event {
            WindowEvent::CloseRequested => return Ok(Flow::Exit),
            WindowEvent::Resized(size) => {
                self.config.width = size.width.max(1);
                self.config.height = size.height.max(1);
                self.surface
                    .configure(&self.session.renderer.ctx.device, &self.config);
            }
            WindowEvent::KeyboardInput { event: key, .. } if !egui_wants => {
                if let PhysicalKey::Code(code) = key.physical_key {
                    match key.state {
                        ElementState::Pressed => {
                            if !key.repeat {
                                if let Some(flow) = self.key_pressed(code) {
                                    return Ok(flow);
                                }
                            }
                            self.input.held.insert(code);
                        }
                        ElementState::Released => {
                            self.input.held.remove(&code);
                        }
                    }
                }
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Left,
                ..
            } => self.input.dragging = *state == ElementState::Pressed && !egui_wants,
            WindowEvent::CursorMoved { position, .. } => {
                if let (true, Some((x, y))) = (self.input.dragging, self.input.cursor) {
                    self.camera
                        .drag((position.x - x) as f32, (position.y - y) as f32);
                }
                self.input.cursor = Some((position.x, position.y));
            }
            WindowEvent::MouseWheel { delta, .. } if !egui_wants => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => *y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                };
                self.camera.scroll(lines);
            }
            WindowEvent::RedrawRequested => return self.redraw(),
            _ => {}
        }
        Ok(Flow::Continue)
    }

    fn key_pressed(&mut self, code: KeyCode) -> Option<Flow> {
        match code {
            KeyCode::Escape => return Some(Flow::Exit),
            KeyCode::Tab => {
                let mode = match self.camera.mode {
                    CameraMode::Orbit => CameraMode::Fly,
                    CameraMode::Fly => CameraMode::Orbit,
                };
                self.set_camera_mode(mode);
            }
            KeyCode::F1 => self.overlay.visible = !self.overlay.visible,
            KeyCode::Space => self.light_clock.paused = !self.light_clock.paused,
            _ => {}
        }
        None
    }

    fn set_camera_mode(&mut self, mode: CameraMode) {
        self.camera.mode = mode;
        self.overlay.camera_mode = mode;
    }

    /// Reloads what changed, renders the graph, presents it with the overlay.
    fn redraw(&mut self) -> Result<Flow, ViewError> {
        let now = Instant::now();
        let dt = now.duration_since(self.last_frame).as_secs_f32().min(0.25);
        self.last_frame = now;
        let ms = dt as f64 * 1e3;
        if self.frames <= 1 {
            self.info.frame_ms = ms; // the first frames include startup
        } else {
            self.info.frame_ms += (ms - self.info.frame_ms) * SMOOTHING;
        }
        self.camera.travel(self.input.movement(), dt);

        self.reload_if_changed();
        self.follow_window_size();
        if let Err(e) = self.light_clock.advance(&self.session, dt as f64) {
            // Said once: the lights stay where they are until Space is pressed again.
            eprintln!("moving lights stopped: {e}");
            self.info.error = Some(e);
            self.light_clock.paused = true;
        }
        let pass_ms = self.render_graph();
        if let Some(ms) = pass_ms {
            smooth_pass_times(&mut self.info.pass_ms, ms);
        }

        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f)
            | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                self.window.request_redraw();
                return Ok(Flow::Continue);
            }
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface
                    .configure(&self.session.renderer.ctx.device, &self.config);
                self.window.request_redraw();
                return Ok(Flow::Continue);
            }
            wgpu::CurrentSurfaceTexture::Validation => {
                return Err(ViewError::Surface(
                    "acquiring the next window image failed validation".into(),
                ))
            }
        };
        self.draw(&frame.texture);
        self.frames += 1;
        let mut flow = Flow::Continue;
        if let Some((path, after)) = &self.screenshot {
            if self.frames >= *after {
                self.save_screenshot(&frame.texture, path)?;
                flow = Flow::Exit;
            }
        }
        self.window.pre_present_notify();
        self.session.renderer.ctx.queue.present(frame);
        self.window.request_redraw();
        Ok(flow)
    }

    fn reload_if_changed(&mut self) {
        if let Some(reload) = self.session.poll().filter(|r| !r.rebuilt.is_empty()) {
            let names: Vec<String> = reload
                .changed
                .iter()
                .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
                .collect();
            match &reload.outcome {
                Ok(latency) => {
                    let line = format!(
                        "{}: {:.0} ms",
                        names.join(", "),
                        latency.as_secs_f64() * 1e3
                    );
                    eprintln!("reloaded {line}");
                    self.info.last_reload = Some(line);
                }
                Err(e) => eprintln!("reload failed, keeping the last good frame:\n{e}"),
            }
            self.info.error = self.session.error.clone();
            self.info.lights = self.session.scene().lights.len();
        }
    }

    /// Re-prepares the graph when the window's render size changed.
    fn follow_window_size(&mut self) {
        let wanted = render_size([self.config.width, self.config.height], self.render_scale);
        if wanted != self.info.render_size {
            match self.session.resize(wanted[0], wanted[1]) {
                Ok(()) => self.info.render_size = wanted,
                Err(e) => self.info.error = Some(e),
            }
        }
    }

    /// Runs the graph once from the current camera; GPU times per pass if available.
    fn render_graph(&mut self) -> Option<Vec<(String, f64)>> {
        let camera = self.camera.camera();
        let session = &self.session;
        let prepared = session.prepared()?;
        let scene = session.scene();
        prepared.set_view(&session.renderer, &camera, scene.ambient);
        let result = prepared.execute(&session.renderer);
        if self.frames.is_multiple_of(REPORT_EVERY) {
            if let Ok((culling, stats)) = prepared.read_reports(&session.renderer) {
                self.info.culling = culling;
                self.info.light_stats = stats;
            }
        }
        match result {
            Ok(ms) => ms,
            Err(e) => {
                self.info.error = Some(e.to_string());
                None
            }
        }
    }

    /// Presents the graph's output and draws the overlay on top.
    fn draw(&mut self, target: &wgpu::Texture) {
        let device = &self.session.renderer.ctx.device;
        let queue = &self.session.renderer.ctx.queue;
        let view = target.create_view(&Default::default());
        let mut encoder = device.create_command_encoder(&Default::default());
        if let Some(prepared) = self.session.prepared() {
            self.presenter.draw(
                device,
                queue,
                &mut encoder,
                prepared.output_texture(),
                &view,
                [self.config.width, self.config.height],
                self.overlay.exposure_ev,
            );
        }

        let raw = self.egui_state.take_egui_input(&self.window);
        let mut actions = Vec::new();
        let output = self.egui_ctx.run_pass(raw, |ctx| {
            actions = self.overlay.ui(ctx, &self.info);
        });
        self.egui_state
            .handle_platform_output(&self.window, output.platform_output);
        let primitives = self
            .egui_ctx
            .tessellate(output.shapes, output.pixels_per_point);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.config.width, self.config.height],
            pixels_per_point: output.pixels_per_point,
        };
        for (id, deltas) in &output.textures_delta.set {
            for delta in deltas {
                self.egui_renderer.update_texture(device, queue, *id, delta);
            }
        }
        let user_buffers =
            self.egui_renderer
                .update_buffers(device, queue, &mut encoder, &primitives, &screen);
        {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("overlay"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            self.egui_renderer.render(&mut pass, &primitives, &screen);
        }
        queue.submit(user_buffers.into_iter().chain([encoder.finish()]));
        for id in &output.textures_delta.free {
            self.egui_renderer.free_texture(id);
        }
        for action in actions {
            self.apply(action);
        }
    }

    fn apply(&mut self, action: OverlayAction) {
        match action {
            OverlayAction::SelectGraph(path) => match self.session.set_graph(&path) {
                Ok(()) => {
                    eprintln!("graph: {}", path.display());
                    self.overlay.current_graph = path;
                    self.info.error = None;
                    self.info.pass_ms = None;
                    self.info.culling.clear();
                }
                Err(e) => self.info.error = Some(e),
            },
            OverlayAction::CameraMode(mode) => self.set_camera_mode(mode),
            OverlayAction::LightStats(on) => {
                if let Err(e) = self.session.set_light_stats(on) {
                    self.info.error = Some(e);
                }
                self.info.light_stats = None;
            }
        }
    }

    /// Copies what the window shows (scene and overlay) to a PNG.
    fn save_screenshot(
        &self,
        texture: &wgpu::Texture,
        path: &std::path::Path,
    ) -> Result<(), ViewError> {
        let err = |message: String| ViewError::Screenshot {
            path: path.to_path_buf(),
            message,
        };
        let ctx = &self.session.renderer.ctx;
        let bytes =
            read_texture(&ctx.device, &ctx.queue, texture, 4).map_err(|e| err(e.to_string()))?;
        let bgra = matches!(
            texture.format(),
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        );
        let rgb: Vec<u8> = bytes
            .chunks_exact(4)
            .flat_map(|p| {
                if bgra {
                    [p[2], p[1], p[0]]
                } else {
                    [p[0], p[1], p[2]]
                }
            })
            .collect();
        // The image crate directly, not bench::image_io: the viewer builds without `bench`.
        let (w, h) = (texture.width(), texture.height());
        let image = image::RgbImage::from_raw(w, h, rgb)
            .ok_or_else(|| err(format!("{w}×{h} pixels read back short")))?;
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| err(e.to_string()))?;
        }
        image
            .save_with_format(path, image::ImageFormat::Png)
            .map_err(|e| err(e.to_string()))?;
        eprintln!(
            "screenshot after {} frames: {} ({}×{}, {:?})",
            self.frames,
            path.display(),
            texture.width(),
            texture.height(),
            texture.format()
        );
        Ok(())
    }
}

/// Running average of per-pass times; starts over when the passes change.
fn smooth_pass_times(smoothed: &mut Option<Vec<(String, f64)>>, new: Vec<(String, f64)>) {
    match smoothed {
        Some(old) if old.len() == new.len() && old.iter().zip(&new).all(|(a, b)| a.0 == b.0) => {
            for (o, n) in old.iter_mut().zip(new) {
                o.1 += (n.1 - o.1) * SMOOTHING;
            }
        }
        _ => *smoothed = Some(new),
    }
}

/// An 8-bit format the window supports, copyable where possible. A non-sRGB format is
/// preferred: egui blends in gamma space, and the present shader encodes sRGB itself.
fn surface_config(
    surface: &wgpu::Surface<'_>,
    adapter: &wgpu::Adapter,
    size: (u32, u32),
) -> Result<wgpu::SurfaceConfiguration, ViewError> {
    let caps = surface.get_capabilities(adapter);
    let format = caps
        .formats
        .iter()
        .copied()
        .filter(|f| {
            matches!(
                f.remove_srgb_suffix(),
                wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
            )
        })
        .max_by_key(|f| !f.is_srgb())
        .ok_or_else(|| {
            ViewError::Surface(format!(
                "no 8-bit RGBA/BGRA format among the window's formats {:?}",
                caps.formats
            ))
        })?;
    let mut config = surface
        .get_default_config(adapter, size.0.max(1), size.1.max(1))
        .ok_or_else(|| ViewError::Surface("the adapter cannot present to this window".into()))?;
    config.format = format;
    // Screenshots copy the window image itself.
    config.usage |= caps.usages & wgpu::TextureUsages::COPY_SRC;
    Ok(config)
}
