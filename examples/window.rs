//! lightgraph's frame in an application's own window, followed by the application's own
//! pass into the same surface image: one encoder, one submit per frame. The own pass
//! here is a translucent bar along the bottom (a stand-in for a UI).
//!
//!     cargo run --release --example window -- [SCENE] [GRAPH]
use lightgraph::gpu::GpuContext;
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{PreparedFrame, Presenter, Renderer, SceneGpu};
use std::path::PathBuf;
use std::sync::Arc;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::{Window, WindowId};

const BAR_WGSL: &str = r#"
@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let x = select(-1.0, 1.0, (i & 1u) == 1u);
    let y = select(-1.0, -0.85, i >= 2u);
    return vec4<f32>(x, y, 0.0, 1.0);
}
@fragment
fn fs() -> @location(0) vec4<f32> {
    return vec4<f32>(0.05, 0.05, 0.08, 0.75);
}
"#;

struct Running {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    renderer: Renderer,
    scene: lightgraph::scene::Scene,
    gpu: SceneGpu,
    frame: PreparedFrame,
    presenter: Presenter,
    bar: wgpu::RenderPipeline,
}

struct App {
    scene: PathBuf,
    graph: PathBuf,
    running: Option<Running>,
}

fn prepare(
    r: &mut Renderer,
    graph: &std::path::Path,
    scene: &lightgraph::scene::Scene,
    gpu: &SceneGpu,
    (width, height): (u32, u32),
) -> PreparedFrame {
    let checked = graph::check_file(graph, &r.shaders).unwrap_or_else(|e| panic!("{e}"));
    let size = FrameSize {
        width,
        height,
        lights: scene.lights.len() as u32,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    r.prepare(compiled, scene, gpu, size, false)
        .unwrap_or_else(|e| panic!("{e}"))
}

impl App {
    fn start(&self, event_loop: &ActiveEventLoop) -> Running {
        let window = Arc::new(
            event_loop
                .create_window(Window::default_attributes().with_title("lightgraph in a window"))
                .unwrap(),
        );
        let mut desc = wgpu::InstanceDescriptor::new_with_display_handle(Box::new(
            event_loop.owned_display_handle(),
        ));
        desc.backends = wgpu::Backends::VULKAN;
        let instance = wgpu::Instance::new(desc);
        let surface = instance.create_surface(window.clone()).unwrap();
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .unwrap();
        // The application's device, asking for what lightgraph's fast paths use.
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            required_features: adapter.features() & GpuContext::wanted_features(),
            required_limits: GpuContext::wanted_limits(&adapter),
            ..Default::default()
        }))
        .unwrap();
        let size = window.inner_size();
        let config = surface
            .get_default_config(&adapter, size.width.max(1), size.height.max(1))
            .unwrap();
        surface.configure(&device, &config);

        let mut renderer = Renderer::from_device(adapter, device.clone(), queue.clone());
        let scene = lightgraph::scene::load(&self.scene)
            .unwrap_or_else(|e| panic!("{e}"))
            .scene;
        let gpu = SceneGpu::upload(&device, &queue, &scene).unwrap_or_else(|e| panic!("{e}"));
        let frame = prepare(
            &mut renderer,
            &self.graph,
            &scene,
            &gpu,
            (config.width, config.height),
        );
        let presenter = Presenter::new(&renderer, config.format).unwrap_or_else(|e| panic!("{e}"));
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("bar"),
            source: wgpu::ShaderSource::Wgsl(BAR_WGSL.into()),
        });
        let bar = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("bar"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleStrip,
                ..Default::default()
            },
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: config.format,
                    blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        Running {
            window,
            surface,
            config,
            renderer,
            scene,
            gpu,
            frame,
            presenter,
            bar,
        }
    }
}

impl Running {
    fn resize(&mut self, graph: &std::path::Path, width: u32, height: u32) {
        self.config.width = width.max(1);
        self.config.height = height.max(1);
        self.surface
            .configure(&self.renderer.ctx.device, &self.config);
        self.frame = prepare(
            &mut self.renderer,
            graph,
            &self.scene,
            &self.gpu,
            (self.config.width, self.config.height),
        );
    }

    fn draw(&mut self) {
        let image = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f)
            | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            _ => return self.window.request_redraw(),
        };
        let view = image.texture.create_view(&Default::default());
        let (device, queue) = (&self.renderer.ctx.device, &self.renderer.ctx.queue);
        let mut encoder = device.create_command_encoder(&Default::default());
        // lightgraph's passes, then its HDR output tonemapped into the window's image...
        self.frame.record(&mut encoder);
        let size = [self.config.width, self.config.height];
        self.presenter.draw(
            device,
            queue,
            &mut encoder,
            self.frame.output_texture(),
            &view,
            size,
            0.0,
        );
        // ...then the application's own pass over it.
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("bar"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        pass.set_pipeline(&self.bar);
        pass.draw(0..4, 0..1);
        drop(pass);
        queue.submit([encoder.finish()]);
        queue.present(image);
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_none() {
            self.running = Some(self.start(event_loop));
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(running) = self.running.as_mut() else {
            return;
        };
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => running.resize(&self.graph, size.width, size.height),
            WindowEvent::RedrawRequested => {
                running.draw();
                running.window.request_redraw();
            }
            _ => {}
        }
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let mut app = App {
        scene: args
            .next()
            .unwrap_or_else(|| "scenes/harada.ron".into())
            .into(),
        graph: args
            .next()
            .unwrap_or_else(|| "graphs/visibility_compute_raster.ron".into())
            .into(),
        running: None,
    };
    EventLoop::new().unwrap().run_app(&mut app).unwrap();
}
