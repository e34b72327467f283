//! A pass of your own, without Rust: a generic `Compute` pass with its WGSL, added after
//! the compute-first frame. It reads the lit image and the depth (bound by name) and
//! draws an outline where the depth jumps: the silhouettes.
//!
//!     cargo run --release --example custom_pass -- [SCENE] [OUT.png]
use lightgraph::bench::image_io::write_png_tonemapped;
use lightgraph::bench::tonemap::Tonemap;
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{Renderer, SceneGpu};
use lightgraph::shader::ShaderLibrary;
use std::path::{Path, PathBuf};

/// Bindings are matched by name against the pass's reads and writes; `frame` is always
/// there.
const OUTLINE_WGSL: &str = r#"
#include "common/types.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var hdr: texture_2d<f32>;
@group(0) @binding(2) var depth: texture_2d<f32>;
@group(0) @binding(3) var outlined: texture_storage_2d<rgba32float, write>;

// Distance along the view axis of the surface under pixel `p`.
fn view_depth(p: vec2<i32>) -> f32 {
    let q = clamp(p, vec2<i32>(0), vec2<i32>(frame.size) - 1);
    let v = frame.inv_proj * vec4<f32>(0.0, 0.0, textureLoad(depth, q, 0).r, 1.0);
    return -v.z / v.w;
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= frame.size)) {
        return;
    }
    let p = vec2<i32>(id.xy);
    let z = view_depth(p);
    let step = max(abs(view_depth(p + vec2<i32>(1, 0)) - z), abs(view_depth(p + vec2<i32>(0, 1)) - z));
    // A jump of over 5% of the distance is a silhouette, not a slope.
    let edge = step > 0.05 * z;
    let c = textureLoad(hdr, p, 0);
    textureStore(outlined, p, select(c, vec4<f32>(4.0, 3.0, 0.5, 1.0), edge));
}
"#;

const GRAPH: &str = r#"
Graph(
    name: "outlined_frame",
    resources: [
        Texture(name: "depth", format: R32Float),
        Texture(name: "visibility", format: R32Uint),
        Texture(name: "hdr", format: Rgba32Float),
        Texture(name: "outlined", format: Rgba32Float),
        Buffer(name: "light_lists"),
        Import(name: "vertices", from: Vertices),
        Import(name: "triangles", from: Triangles),
        Import(name: "material_triangles", from: MaterialTriangles),
        Import(name: "light_geometry", from: LightGeometry),
        Import(name: "light_properties", from: LightProperties),
    ],
    passes: [
        Pass(name: "compute_raster", kind: ComputeRaster,
             reads: ["vertices", "triangles", "material_triangles"], writes: ["depth", "visibility"]),
        Pass(name: "light_culling", kind: LightCulling(tile: 16, lists: Compact(max_indices: 16777216)),
             reads: ["depth", "light_geometry"], writes: ["light_lists"]),
        Pass(name: "visibility_shading", kind: VisibilityShading(lights: Culled),
             reads: ["visibility", "vertices", "triangles", "material_triangles",
                     "light_geometry", "light_properties", "light_lists"],
             writes: ["hdr"]),
        Pass(name: "outline", kind: Compute(shader: "my/outline.wgsl", dispatch: PerPixel(workgroup: (8, 8))),
             reads: ["hdr", "depth"], writes: ["outlined"]),
    ],
    output: "outlined",
)
"#;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let scene_path = PathBuf::from(args.next().unwrap_or_else(|| "scenes/harada.ron".into()));
    let out = PathBuf::from(args.next().unwrap_or_else(|| "custom_pass.png".into()));

    // Your shaders in a folder of your own; `#include "common/..."` comes from the
    // built-in ones.
    let project =
        std::env::temp_dir().join(format!("lightgraph-custom-pass-{}", std::process::id()));
    std::fs::create_dir_all(project.join("shaders/my"))?;
    std::fs::write(project.join("shaders/my/outline.wgsl"), OUTLINE_WGSL)?;
    let mut renderer = Renderer::headless()?;
    renderer.shaders = ShaderLibrary::with_builtin(project.join("shaders"));

    let scene = lightgraph::scene::load(&scene_path)?.scene;
    let checked = graph::check_text(Path::new("outlined_frame.ron"), GRAPH, &renderer.shaders)?;
    let size = FrameSize {
        width: 640,
        height: 360,
        lights: scene.lights.len() as u32,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    let gpu = SceneGpu::upload(&renderer.ctx.device, &renderer.ctx.queue, &scene)?;
    let result = renderer
        .prepare(compiled, &scene, &gpu, size, false)?
        .render(&renderer)?;
    std::fs::remove_dir_all(&project)?;

    write_png_tonemapped(
        &out,
        &result.image,
        size.width,
        size.height,
        &Tonemap::default(),
    )?;
    println!("wrote {}", out.display());
    Ok(())
}
