//! glTF material features as the Khronos Sample Viewer shows them: samplers (wrap per axis,
//! filters), KHR_texture_transform, KHR_materials_unlit, KHR_materials_emissive_strength,
//! tangents (w honoured on mirrored UVs; MikkTSpace where a normal-mapped primitive has
//! none). Models are written here with `gltf_writer`; renders on lavapipe are compared with
//! images computed on the CPU (a sampler written here, not the renderer's).

mod common;
use common::*;
use glam::{Vec2, Vec3, Vec4};
use lightgraph::material::model::{Filter, MipmapFilter, SamplerDesc, UvTransform, Wrap};
use lightgraph::scene::gltf_writer::{GltfWriter, ImageStorage, MaterialDesc, PrimitiveDesc};
use lightgraph::scene::{self, Camera, Light, Loaded, Mesh, Scene};
use std::path::PathBuf;

/// A fresh folder per call: tests run in parallel and write models of the same name.
fn tmp(name: &str) -> PathBuf {
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let d = std::env::temp_dir().join(format!(
        "lg_gltf_materials_{}_{name}_{n}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn load(w: &GltfWriter, name: &str) -> Loaded {
    let d = tmp(name);
    let path = d.join(format!("{name}.glb"));
    w.write_glb(&path).unwrap();
    scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

const GL_NEAREST: u32 = 9728;
const GL_LINEAR: u32 = 9729;
const GL_NEAREST_MIPMAP_LINEAR: u32 = 9986;
const GL_REPEAT: u32 = 10497;
const GL_CLAMP: u32 = 33071;
const GL_MIRRORED: u32 = 33648;

/// A 4×4 sRGB texture whose every texel differs (so each wrap mode reads other texels).
fn texels() -> image::RgbaImage {
    image::RgbaImage::from_fn(4, 4, |x, y| {
        image::Rgba([
            (30 + 60 * x) as u8,
            (20 + 70 * y) as u8,
            (230 - 25 * x - 30 * y) as u8,
            255,
        ])
    })
}

fn srgb_to_linear(b: u8) -> f32 {
    let c = b as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A texel index after the wrap mode (Vulkan's integer texel wrapping).
fn wrap(i: i64, n: i64, w: Wrap) -> i64 {
    match w {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::MirroredRepeat => {
            let m = i.rem_euclid(2 * n);
            if m < n {
                m
            } else {
                2 * n - 1 - m
            }
        }
    }
}

/// The CPU sampler: `img` (sRGB) at `uv`, magnified (level 0), with `s`'s wrap and
/// magnification filter; linear RGB.
fn sample(img: &image::RgbaImage, uv: [f32; 2], s: &SamplerDesc) -> [f32; 3] {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let texel = |x: i64, y: i64| {
        let p = img.get_pixel(wrap(x, w, s.wrap_u) as u32, wrap(y, h, s.wrap_v) as u32);
        [0, 1, 2].map(|c| srgb_to_linear(p[c]))
    };
    let (x, y) = (uv[0] as f64 * w as f64, uv[1] as f64 * h as f64);
    match s.mag_filter {
        Filter::Nearest => texel(x.floor() as i64, y.floor() as i64),
        Filter::Linear => {
            let (sx, sy) = (x - 0.5, y - 0.5);
            let (x0, y0) = (sx.floor() as i64, sy.floor() as i64);
            let (a, b) = ((sx - sx.floor()) as f32, (sy - sy.floor()) as f32);
            let (t00, t10, t01, t11) = (
                texel(x0, y0),
                texel(x0 + 1, y0),
                texel(x0, y0 + 1),
                texel(x0 + 1, y0 + 1),
            );
            [0, 1, 2].map(|c| {
                (t00[c] * (1.0 - a) + t10[c] * a) * (1.0 - b)
                    + (t01[c] * (1.0 - a) + t11[c] * a) * b
            })
        }
    }
}

const W: u32 = 48;
const H: u32 = 48;
/// The uv at the left (top) edge of the view, and its span across the view.
const UV0: f32 = -1.0;
const UV_SPAN: f32 = 3.0;

/// The uv at the centre of pixel (x, y): UV0 + span · (pixel centre / size), v down.
fn pixel_uv(x: u32, y: u32) -> [f32; 2] {
    [
        UV0 + UV_SPAN * (x as f32 + 0.5) / W as f32,
        UV0 + UV_SPAN * (y as f32 + 0.5) / H as f32,
    ]
}

/// A quad facing the camera, past the view's edges on every side, whose uv maps the view
/// onto [UV0, UV0 + UV_SPAN]² (v down the screen). Parallel to the image plane, so its
/// perspective-correct uv is affine in screen space and `pixel_uv` is exact.
fn view_filling_quad(w: &mut GltfWriter, material: usize) {
    view_filling_quad_coloured(w, material, None);
}

/// The second uv set of `view_filling_quad_second_uv`: the first, turned a quarter and
/// scaled, so any texel read through the wrong set differs.
fn second_uv(uv: [f32; 2]) -> [f32; 2] {
    [0.6 * uv[1] + 0.3, 1.4 - 0.8 * uv[0]]
}

/// `view_filling_quad` with TEXCOORD_1 = second_uv(TEXCOORD_0) at its corners (affine, so
/// second_uv(pixel_uv) is exact at every pixel).
fn view_filling_quad_second_uv(w: &mut GltfWriter, material: usize) {
    let half = (FOV_Y / 2.0).tan();
    let ndc = [-2.0f32, 2.0];
    let (mut p, mut uv, mut uv1) = (Vec::new(), Vec::new(), Vec::new());
    for (sx, sy) in [(0, 0), (1, 0), (1, 1), (0, 1)] {
        let (nx, ny) = (ndc[sx], ndc[sy]);
        p.push(Vec3::new(nx * half, ny * half, -1.0));
        let u = [
            UV0 + UV_SPAN * (nx + 1.0) / 2.0,
            UV0 + UV_SPAN * (1.0 - ny) / 2.0,
        ];
        uv.push(Vec2::from(u));
        uv1.push(Vec2::from(second_uv(u)));
    }
    let prim = PrimitiveDesc {
        positions: w.add_positions(&p),
        normals: Some(w.add_vec3(&[Vec3::Z; 4])),
        uvs: Some(w.add_vec2(&uv)),
        uvs1: Some(w.add_vec2(&uv1)),
        indices: Some(w.add_indices(&[0, 1, 2, 0, 2, 3])),
        material: Some(material),
        ..Default::default()
    };
    let mesh = w.add_mesh("quad", &[prim]);
    let node = w.add_node(&lightgraph::scene::gltf_writer::NodeDesc {
        mesh: Some(mesh),
        ..Default::default()
    });
    w.add_root(node);
}

/// `view_filling_quad`, with a vertex colour (COLOR_0) at each corner when `colour` is
/// given: `colour(tx, ty)` at the corner's place across the quad, 0..1 left to right and
/// bottom to top.
fn view_filling_quad_coloured(
    w: &mut GltfWriter,
    material: usize,
    colour: Option<&dyn Fn(f32, f32) -> Vec4>,
) {
    let half = (FOV_Y / 2.0).tan(); // at z = −1
                                    // NDC ±2: the quad overhangs the view by half its width on each side.
    let ndc = [-2.0f32, 2.0];
    let mut p = Vec::new();
    let mut uv = Vec::new();
    for (sx, sy) in [(0, 0), (1, 0), (1, 1), (0, 1)] {
        let (nx, ny) = (ndc[sx], ndc[sy]);
        p.push(Vec3::new(nx * half, ny * half, -1.0));
        // NDC x −1..1 is u UV0..UV0+span; NDC y up is v down.
        uv.push(Vec2::new(
            UV0 + UV_SPAN * (nx + 1.0) / 2.0,
            UV0 + UV_SPAN * (1.0 - ny) / 2.0,
        ));
    }
    let pos = w.add_positions(&p);
    let nrm = w.add_vec3(&[Vec3::Z; 4]);
    let uvs = w.add_vec2(&uv);
    let colors = colour.map(|f| {
        let corners: Vec<Vec4> = [(0, 0), (1, 0), (1, 1), (0, 1)]
            .iter()
            .map(|&(sx, sy)| f(sx as f32, sy as f32))
            .collect();
        w.add_vec4(&corners)
    });
    let idx = w.add_indices(&[0, 1, 2, 0, 2, 3]);
    let mesh = w.add_mesh(
        "quad",
        &[PrimitiveDesc {
            positions: pos,
            normals: Some(nrm),
            uvs: Some(uvs),
            colors,
            indices: Some(idx),
            material: Some(material),
            ..Default::default()
        }],
    );
    let node = w.add_node(&lightgraph::scene::gltf_writer::NodeDesc {
        mesh: Some(mesh),
        ..Default::default()
    });
    w.add_root(node);
}

const FOV_Y: f32 = std::f32::consts::FRAC_PI_3;

/// The camera at the origin looking down −z, and lights that would light a lit material
/// strongly (ambient and a point light in front): an unlit one must ignore both.
fn stage(scene: &mut Scene) {
    scene.camera = Camera {
        eye: Vec3::ZERO,
        target: -Vec3::Z,
        up: Vec3::Y,
        fov_y: FOV_Y,
        near: 0.1,
        far: 10.0,
    };
    scene.ambient = Vec3::splat(0.5);
    scene.lights = vec![Light::point(Vec3::new(0.3, 0.2, -0.5), 5.0, Vec3::ONE, 5.0)];
}

/// An unlit textured quad filling the view, through the glTF file (sampler, transform,
/// KHR_materials_unlit required).
fn unlit_quad(sampler_json: &str, transform: Option<&str>) -> Scene {
    let mut w = GltfWriter::new();
    let tex = w.add_texture_png("texels", &texels(), ImageStorage::BufferView);
    let smp = w.add_sampler(sampler_json);
    w.set_texture_sampler(tex, smp);
    let m = w.add_material(&MaterialDesc {
        name: "unlit".into(),
        base_color_texture: Some(tex),
        extensions: Some("\"KHR_materials_unlit\":{}".into()),
        texture_transforms: transform
            .map(|t| vec![("baseColorTexture", t.to_string())])
            .unwrap_or_default(),
        ..Default::default()
    });
    w.extensions_required = vec!["KHR_materials_unlit".into()];
    if transform.is_some() {
        w.extensions_required.push("KHR_texture_transform".into());
    }
    view_filling_quad(&mut w, m);
    let mut loaded = load(&w, "unlit_quad");
    stage(&mut loaded.scene);
    loaded.scene
}

/// Worst |render − expected| over the view, and where.
fn worst_abs(img: &[[f32; 4]], expected: impl Fn(u32, u32) -> [f32; 3]) -> (f32, u32, u32) {
    assert_eq!(img.len(), (W * H) as usize, "image size");
    let mut worst = (0.0f32, 0, 0);
    for y in 0..H {
        for x in 0..W {
            let e = expected(x, y);
            let p = img[(y * W + x) as usize];
            for c in 0..3 {
                let d = (p[c] - e[c]).abs();
                if d > worst.0 || d.is_nan() {
                    worst = (d, x, y);
                }
            }
        }
    }
    worst
}

/// Nearest sampling: the render must give the texel the CPU picks. lavapipe's sRGB decode
/// is off from the exact formula by up to 1.15e-3 (measured: byte 210, 0.18%); a wrong
/// texel differs by at least 0.04 in red or green (bytes 60 apart), so 2e-3 absolute.
const NEAREST_TOL: f32 = 2e-3;
/// Bilinear: the same decode error (measured worst 1.15e-3 in the bilinear case too) plus
/// llvmpipe's 8-bit sub-texel weights (up to 1/512 of a neighbour difference ≤ 0.64,
/// 1.3e-3): 4e-3. A wrong wrap mixes in a texel at least 0.04 away with weight ≥ 1/8.
const LINEAR_TOL: f32 = 4e-3;

/// Vertex colours: interpolation and the factor's product round in f32 (a few ulps of
/// values under 1; 1.2e-7 measured on lavapipe in all three paths), so 1e-6. Without the
/// vertex colour every pixel is off by 0.05 or more.
const VERTEX_COLOUR_TOL: f32 = 1e-6;

/// Tiled deferred keeps the vertex colour's rgb to 8 bits a channel (in g_surface's w,
/// deferred/g_surface.wgsl): half a step, 0.5/255 of the factor, plus the f32 rounding.
/// Without it (white vertices) the quad is off by 0.05 or more.
fn deferred_colour_tol() -> f32 {
    COLOUR_FACTOR.max_element() * 0.5 / 255.0 + VERTEX_COLOUR_TOL
}

#[test]
fn sampler_wrap_and_filter_modes_match_a_cpu_sampler_in_forward_and_visibility() {
    let cases = [
        (
            GL_REPEAT,
            GL_CLAMP,
            GL_NEAREST,
            Wrap::Repeat,
            Wrap::ClampToEdge,
        ),
        (
            GL_MIRRORED,
            GL_REPEAT,
            GL_NEAREST,
            Wrap::MirroredRepeat,
            Wrap::Repeat,
        ),
        (
            GL_CLAMP,
            GL_MIRRORED,
            GL_LINEAR,
            Wrap::ClampToEdge,
            Wrap::MirroredRepeat,
        ),
    ];
    let mut r = renderer();
    let mut failures = Vec::new();
    for (s, t, mag, wrap_u, wrap_v) in cases {
        let json = format!(
            "{{\"wrapS\":{s},\"wrapT\":{t},\"magFilter\":{mag},\"minFilter\":{GL_NEAREST_MIPMAP_LINEAR}}}"
        );
        let scene = unlit_quad(&json, None);
        let desc = SamplerDesc {
            wrap_u,
            wrap_v,
            mag_filter: if mag == GL_NEAREST {
                Filter::Nearest
            } else {
                Filter::Linear
            },
            min_filter: Filter::Nearest,
            mipmap_filter: MipmapFilter::Linear,
        };
        assert_eq!(scene.materials[0].sampling.base_color.sampler, desc);
        let tol = if mag == GL_NEAREST {
            NEAREST_TOL
        } else {
            LINEAR_TOL
        };
        let img = texels();
        for graph in ["forward_plus.ron", "visibility_buffer.ron"] {
            let out = render_file(&mut r, graph, &scene, W, H);
            let (d, x, y) = worst_abs(&out.image, |x, y| sample(&img, pixel_uv(x, y), &desc));
            println!("{graph} {desc:?}: worst {d:.2e} at ({x}, {y})");
            if d > tol {
                failures.push(format!(
                    "{graph} {desc:?}: pixel ({x}, {y}) uv {:?} off by {d} (bound {tol}): got {:?}, expected {:?}",
                    pixel_uv(x, y),
                    out.image[(y * W + x) as usize],
                    sample(&img, pixel_uv(x, y), &desc)
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn texture_transform_moves_the_uv_before_sampling() {
    // A quarter turn, u stretched 2×, an offset: uv' = (v + 0.25, −2u) (cos ≈ 0).
    let t = UvTransform {
        offset: (0.25, 0.0),
        rotation: std::f32::consts::FRAC_PI_2,
        scale: (2.0, 1.0),
    };
    let json = format!(
        "{{\"offset\":[{:?},{:?}],\"rotation\":{:?},\"scale\":[{:?},{:?}]}}",
        t.offset.0, t.offset.1, t.rotation, t.scale.0, t.scale.1
    );
    let sampler = format!("{{\"magFilter\":{GL_NEAREST},\"wrapS\":{GL_REPEAT}}}");
    let scene = unlit_quad(&sampler, Some(&json));
    assert_eq!(scene.materials[0].sampling.base_color.transform, Some(t));
    let desc = scene.materials[0].sampling.base_color.sampler;
    let img = texels();
    let mut r = renderer();
    for graph in ["forward_plus.ron", "visibility_buffer.ron"] {
        let out = render_file(&mut r, graph, &scene, W, H);
        let (d, x, y) = worst_abs(&out.image, |x, y| {
            sample(&img, t.apply(pixel_uv(x, y)), &desc)
        });
        // Texel edges in the transformed uv fall at least 1/8 texel from pixel centres;
        // the rotation's cos (−4e-8) moves them by far less.
        assert!(d <= NEAREST_TOL, "{graph}: pixel ({x}, {y}) off by {d}");
    }
}

/// A tangent-space normal tilted towards +x and +y of the texture (+y: up the image).
const TILT: [u8; 4] = [192, 192, 218, 255];

/// Two quads side by side at z = −1.5, normal-mapped with a constant tilted normal: the
/// left with uv as usual, the right with u mirrored (the mirror image of the left). With
/// `tangents`, the file gives them (the right's w = −1); without, MikkTSpace makes them.
fn mirrored_pair(tangents: bool, normal_map: bool) -> Loaded {
    let mut w = GltfWriter::new();
    let normal = image::RgbaImage::from_pixel(2, 2, image::Rgba(TILT));
    let tex = w.add_texture_png("tilt", &normal, ImageStorage::BufferView);
    let m = w.add_material(&MaterialDesc {
        name: "bumpy".into(),
        base_color: Vec4::new(0.8, 0.8, 0.8, 1.0),
        metallic: 0.0,
        roughness: 0.6,
        normal_texture: normal_map.then_some(tex),
        ..Default::default()
    });
    let mut prims = Vec::new();
    for (x0, mirrored) in [(-1.0f32, false), (0.0, true)] {
        let p: Vec<Vec3> = [(0.0, -0.5), (1.0, -0.5), (1.0, 0.5), (0.0, 0.5)]
            .iter()
            .map(|&(x, y)| Vec3::new(x0 + x, y, -1.5))
            .collect();
        // v down the image: the top edge is v = 0.
        let uv: Vec<Vec2> = [(0.0, 1.0), (1.0, 1.0), (1.0, 0.0), (0.0, 0.0)]
            .iter()
            .map(|&(u, v)| Vec2::new(if mirrored { 1.0 - u } else { u }, v))
            .collect();
        let tangent = if mirrored {
            Vec4::new(-1.0, 0.0, 0.0, -1.0)
        } else {
            Vec4::new(1.0, 0.0, 0.0, 1.0)
        };
        prims.push(PrimitiveDesc {
            positions: w.add_positions(&p),
            normals: Some(w.add_vec3(&[Vec3::Z; 4])),
            uvs: Some(w.add_vec2(&uv)),
            uvs1: None,
            tangents: tangents.then(|| w.add_vec4(&[tangent; 4])),
            colors: None,
            indices: Some(w.add_indices(&[0, 1, 2, 0, 2, 3])),
            material: Some(m),
            mode: None,
        });
    }
    let mesh = w.add_mesh("pair", &prims);
    let node = w.add_node(&lightgraph::scene::gltf_writer::NodeDesc {
        mesh: Some(mesh),
        ..Default::default()
    });
    w.add_root(node);
    let mut loaded = load(&w, "mirrored_pair");
    let s = &mut loaded.scene;
    stage(s);
    s.ambient = Vec3::ZERO;
    // On the mirror plane x = 0, above the quads: the scene is mirror-symmetric in x and
    // the light's y makes the bitangent's sign show.
    s.lights = vec![Light::point(Vec3::new(0.0, 0.8, -0.9), 6.0, Vec3::ONE, 4.0)];
    loaded
}

/// Worst |left − mirrored right| relative to the frame's peak.
fn asymmetry(img: &[[f32; 4]]) -> (f32, u32, u32) {
    assert_eq!(img.len(), (W * H) as usize, "image size");
    let peak = img
        .iter()
        .flat_map(|p| p[..3].to_vec())
        .fold(1e-6f32, f32::max);
    let mut worst = (0.0f32, 0, 0);
    for y in 0..H {
        for x in 0..W / 2 {
            let (a, b) = (img[(y * W + x) as usize], img[(y * W + W - 1 - x) as usize]);
            for c in 0..3 {
                let d = (a[c] - b[c]).abs() / peak;
                if d > worst.0 || d.is_nan() {
                    worst = (d, x, y);
                }
            }
        }
    }
    worst
}

/// Mirror symmetry of the left and right quads: the same light on mirrored geometry,
/// differing only in f32 rounding (measured 5.5e-7 of the peak on lavapipe in both paths;
/// with the tangent's w ignored, 0.54).
const SYMMETRY_TOL: f32 = 1e-5;

#[test]
fn mirrored_uvs_shade_as_the_mirror_image_with_given_and_generated_tangents() {
    let given = mirrored_pair(true, true);
    let generated = mirrored_pair(false, true);
    let flat = mirrored_pair(true, false);
    // MikkTSpace gives the glTF convention: the right (mirrored) quad's tangent is −x
    // with w = −1, as the file's.
    let right = &generated.scene.meshes[1];
    assert!(
        right
            .tangents
            .iter()
            .all(|t| (*t - Vec4::new(-1.0, 0.0, 0.0, -1.0)).length() < 1e-5),
        "{:?}",
        right.tangents
    );
    let mut r = renderer();
    for graph in ["forward_plus.ron", "visibility_buffer.ron"] {
        let g = render_file(&mut r, graph, &given.scene, W, H).image;
        let m = render_file(&mut r, graph, &generated.scene, W, H).image;
        let f = render_file(&mut r, graph, &flat.scene, W, H).image;
        let (d, x, y) = asymmetry(&g);
        println!(
            "{graph}: asymmetry file {d:.2e}, MikkTSpace {:.2e}; MikkTSpace vs file {:.2e}; normal map vs flat {:.2e}",
            asymmetry(&m).0,
            max_rel_diff(&m, &g).0,
            max_rel_diff(&g, &f).0
        );
        assert!(
            d <= SYMMETRY_TOL,
            "{graph}, file tangents: ({x}, {y}) and its mirror differ by {d}"
        );
        let (d, x, y) = asymmetry(&m);
        assert!(
            d <= SYMMETRY_TOL,
            "{graph}, MikkTSpace: ({x}, {y}) and its mirror differ by {d}"
        );
        let (d, _) = max_rel_diff(&m, &g);
        assert!(
            d <= SYMMETRY_TOL,
            "{graph}: MikkTSpace and file tangents differ by {d}"
        );
        // The normal map matters: without it the shading is far from the same.
        let (d, _) = max_rel_diff(&g, &f);
        assert!(
            d > 0.05,
            "{graph}: the normal map changed the image by only {d}"
        );
    }
}

#[test]
fn mikktspace_gives_a_quads_known_tangents_and_splits_mirrored_seams() {
    // An upright quad (v down the image): tangent +x, w = +1 (bitangent +y, up the image).
    let quad = |mirrored: bool| {
        let mut m = Mesh {
            name: "quad".into(),
            ..Default::default()
        };
        for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            m.positions.push(Vec3::new(x, y, 0.0));
            m.normals.push(Vec3::Z);
            let u = if mirrored { 1.0 - x } else { x };
            m.uvs.push(Vec2::new(u, 1.0 - y));
        }
        m.indices = vec![0, 1, 2, 0, 2, 3];
        m
    };
    let mut up = quad(false);
    assert!(lightgraph::scene::tangent_space::mikktspace_tangents(
        &mut up
    ));
    assert_eq!(up.positions.len(), 4);
    for t in &up.tangents {
        assert!((*t - Vec4::new(1.0, 0.0, 0.0, 1.0)).length() < 1e-6, "{t}");
    }
    let mut mirrored = quad(true);
    lightgraph::scene::tangent_space::mikktspace_tangents(&mut mirrored);
    for t in &mirrored.tangents {
        assert!(
            (*t - Vec4::new(-1.0, 0.0, 0.0, -1.0)).length() < 1e-6,
            "{t}"
        );
    }
    // Two quads sharing an edge, the second mirrored in u: the shared vertices split.
    let mut pair = quad(false);
    pair.positions
        .extend([Vec3::new(2.0, 0.0, 0.0), Vec3::new(2.0, 1.0, 0.0)]);
    pair.normals.extend([Vec3::Z; 2]);
    pair.uvs.extend([Vec2::new(0.0, 1.0), Vec2::new(0.0, 0.0)]);
    pair.indices.extend([1, 4, 5, 1, 5, 2]);
    lightgraph::scene::tangent_space::mikktspace_tangents(&mut pair);
    assert_eq!(pair.positions.len(), 8, "the seam's two vertices split");
    for tri in pair.indices.chunks(3) {
        let right = tri.iter().any(|&i| pair.positions[i as usize].x > 1.5);
        let want = if right {
            Vec4::new(-1.0, 0.0, 0.0, -1.0)
        } else {
            Vec4::new(1.0, 0.0, 0.0, 1.0)
        };
        for &i in tri {
            let t = pair.tangents[i as usize];
            assert!((t - want).length() < 1e-6, "vertex {i}: {t}, want {want}");
        }
    }
}

#[test]
fn importer_reads_samplers_transforms_unlit_and_emissive_strength() {
    let mut w = GltfWriter::new();
    let tex = w.add_texture_png("texels", &texels(), ImageStorage::BufferView);
    let tex2 = w.add_texture_png("texels2", &texels(), ImageStorage::BufferView);
    let smp = w.add_sampler(&format!(
        "{{\"wrapS\":{GL_CLAMP},\"wrapT\":{GL_MIRRORED},\"magFilter\":{GL_NEAREST},\"minFilter\":{GL_LINEAR}}}"
    ));
    w.set_texture_sampler(tex, smp);
    let lit = w.add_material(&MaterialDesc {
        name: "lit".into(),
        emissive: Vec3::new(1.0, 0.5, 0.25),
        base_color_texture: Some(tex2),
        normal_texture: Some(tex),
        occlusion_texture: Some(tex2),
        extensions: Some("\"KHR_materials_emissive_strength\":{\"emissiveStrength\":4.0}".into()),
        texture_transforms: vec![
            // The gltf crate parses a textureInfo's transform, the importer a normal
            // texture's (raw JSON); texCoord 2 replaces the textureInfo's set.
            (
                "normalTexture",
                "{\"offset\":[0.5,0.25],\"scale\":[2,3],\"rotation\":0.5}".into(),
            ),
            ("occlusionTexture", "{\"texCoord\":2}".into()),
            ("baseColorTexture", "{\"offset\":[1,2]}".into()),
        ],
        ..Default::default()
    });
    let unlit = w.add_material(&MaterialDesc {
        name: "unlit".into(),
        extensions: Some("\"KHR_materials_unlit\":{}".into()),
        ..Default::default()
    });
    let (p, n, uv, i) = lightgraph::scene::gltf_writer::grid(1, 1.0);
    for m in [lit, unlit] {
        let mesh = w.add_simple_mesh("grid", &p, Some(&n), Some(&uv), Some(&i), Some(m));
        let node = w.add_node(&lightgraph::scene::gltf_writer::NodeDesc {
            mesh: Some(mesh),
            ..Default::default()
        });
        w.add_root(node);
    }
    w.extensions_required = vec!["KHR_materials_unlit".into(), "KHR_texture_transform".into()];
    let loaded = load(&w, "importer_reads");
    let mats = &loaded.scene.materials;
    let (lit, unlit) = (&mats[0], &mats[1]);
    assert!(!lit.unlit && unlit.unlit);
    assert_eq!(lit.emissive, Vec3::new(4.0, 2.0, 1.0));
    assert_eq!(
        lit.sampling.normal.sampler,
        SamplerDesc {
            wrap_u: Wrap::ClampToEdge,
            wrap_v: Wrap::MirroredRepeat,
            mag_filter: Filter::Nearest,
            min_filter: Filter::Linear,
            mipmap_filter: MipmapFilter::None,
        }
    );
    // No sampler: repeat, trilinear.
    assert_eq!(lit.sampling.base_color.sampler, SamplerDesc::default());
    assert_eq!(
        lit.sampling.normal.transform,
        Some(UvTransform {
            offset: (0.5, 0.25),
            rotation: 0.5,
            scale: (2.0, 3.0),
        })
    );
    assert_eq!(
        lit.sampling.base_color.transform,
        Some(UvTransform {
            offset: (1.0, 2.0),
            ..Default::default()
        })
    );
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains("occlusionTexture") && w.contains("TEXCOORD_2")),
        "{:?}",
        loaded.warnings
    );
    // The generated WGSL carries the transform and a second sampler after the textures.
    let code = lightgraph::material::Material::from_surface(lit)
        .wgsl()
        .unwrap();
    assert!(code.contains("var material_sampler1: sampler;"), "{code}");
    assert!(code.contains("let uv"), "{code}");
}

/// Unlit through the whole path: the unlit quad under ambient and a light shows its base
/// colour × texture exactly, where the same material lit does not.
#[test]
fn unlit_ignores_the_lights_that_light_the_same_material_lit() {
    let sampler = format!("{{\"magFilter\":{GL_NEAREST}}}");
    let unlit = unlit_quad(&sampler, None);
    let mut lit = unlit.clone();
    lit.materials[0].unlit = false;
    let desc = SamplerDesc {
        mag_filter: Filter::Nearest,
        ..Default::default()
    };
    let img = texels();
    let mut r = renderer();
    for graph in ["forward_plus.ron", "visibility_buffer.ron"] {
        let u = render_file(&mut r, graph, &unlit, W, H).image;
        let (d, x, y) = worst_abs(&u, |x, y| sample(&img, pixel_uv(x, y), &desc));
        assert!(
            d <= NEAREST_TOL,
            "{graph}: unlit pixel ({x}, {y}) off by {d}"
        );
        let l = render_file(&mut r, graph, &lit, W, H).image;
        let (d, _, _) = worst_abs(&l, |x, y| sample(&img, pixel_uv(x, y), &desc));
        assert!(
            d > 0.05,
            "{graph}: lit differs from the base colour by only {d}"
        );
    }
}

/// TEXCOORD_1 as the Sample Viewer reads it: a texture whose textureInfo names set 1, or
/// whose KHR_texture_transform's texCoord does (with an offset there too), samples the
/// second uv set, checked against the CPU sampler at second_uv(pixel_uv) in forward
/// shading, the hardware visibility buffer, the compute-first default frame and tiled
/// deferred (its G-buffer's g_uv1 and g_uv1_grad, in both layouts).
#[test]
fn texcoord_1_is_sampled_where_a_texture_names_it() {
    let sampler = format!("{{\"magFilter\":{GL_NEAREST},\"minFilter\":{GL_NEAREST}}}");
    let desc = SamplerDesc {
        mag_filter: Filter::Nearest,
        min_filter: Filter::Nearest,
        mipmap_filter: MipmapFilter::Nearest,
        ..Default::default()
    };
    let img = texels();
    let offset = [0.125f32, -0.25];
    let cases: [(&str, Option<String>, [f32; 2]); 2] = [
        ("textureInfo texCoord 1", None, [0.0, 0.0]),
        (
            "transform texCoord 1",
            Some(format!(
                "{{\"texCoord\":1,\"offset\":[{},{}]}}",
                offset[0], offset[1]
            )),
            offset,
        ),
    ];
    let mut r = renderer();
    let mut failures = Vec::new();
    for (name, transform, shift) in cases {
        let mut w = GltfWriter::new();
        let tex = w.add_texture_png("texels", &img, ImageStorage::BufferView);
        let smp = w.add_sampler(&sampler);
        w.set_texture_sampler(tex, smp);
        let m = w.add_material(&MaterialDesc {
            name: "unlit".into(),
            base_color_texture: Some(tex),
            extensions: Some("\"KHR_materials_unlit\":{}".into()),
            tex_coords: if transform.is_none() {
                vec![("baseColorTexture", 1)]
            } else {
                Vec::new()
            },
            texture_transforms: transform
                .map(|t| vec![("baseColorTexture", t)])
                .unwrap_or_default(),
            ..Default::default()
        });
        w.extensions_required = vec!["KHR_materials_unlit".into(), "KHR_texture_transform".into()];
        view_filling_quad_second_uv(&mut w, m);
        let mut loaded = load(&w, "second_uv");
        stage(&mut loaded.scene);
        assert_eq!(
            loaded.scene.materials[0].sampling.base_color.tex_coord, 1,
            "{name}"
        );
        let expected = |x: u32, y: u32| {
            let uv = second_uv(pixel_uv(x, y));
            sample(&img, [uv[0] + shift[0], uv[1] + shift[1]], &desc)
        };
        for graph in [
            "forward_plus.ron",
            "visibility_buffer.ron",
            "default.ron",
            "tiled_deferred.ron",
            "tiled_deferred_packed.ron",
        ] {
            let out = render_file(&mut r, graph, &loaded.scene, W, H);
            let (d, x, y) = worst_abs(&out.image, expected);
            println!("{name}, {graph}: worst {d:.2e} at ({x}, {y})");
            if d > NEAREST_TOL {
                failures.push(format!("{name}, {graph}: pixel ({x}, {y}) off by {d}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The vertex colour of `coloured_quad` at (tx, ty) across the quad: affine, so the
/// rasterizer's interpolation over either of its two triangles gives it exactly, and
/// within 0..1 at every corner (no clamp bends it). Alpha rises left to right.
fn quad_colour(tx: f32, ty: f32) -> Vec4 {
    Vec4::new(
        0.1 + 0.8 * tx,
        0.2 + 0.8 * ty,
        0.9 - 0.4 * tx - 0.4 * ty,
        tx,
    )
}

/// Where pixel (x, y)'s centre lies across the quad (which overhangs the view by half
/// its width on each side: the view is 0.25..0.75 of it).
fn quad_place(x: u32, y: u32) -> (f32, f32) {
    let nx = (x as f32 + 0.5) / W as f32 * 2.0 - 1.0;
    let ny = 1.0 - (y as f32 + 0.5) / H as f32 * 2.0;
    ((nx + 2.0) / 4.0, (ny + 2.0) / 4.0)
}

const COLOUR_FACTOR: Vec4 = Vec4::new(0.5, 1.0, 0.8, 1.0);

/// An unlit quad filling the view with `quad_colour` at its corners and base colour
/// factor COLOUR_FACTOR, opaque or alpha-masked at `cutoff`.
fn coloured_quad(cutoff: Option<f32>) -> Scene {
    let mut w = GltfWriter::new();
    let m = w.add_material(&MaterialDesc {
        name: "coloured".into(),
        base_color: COLOUR_FACTOR,
        alpha_mode: if cutoff.is_some() { "MASK" } else { "OPAQUE" },
        alpha_cutoff: cutoff,
        extensions: Some("\"KHR_materials_unlit\":{}".into()),
        ..Default::default()
    });
    w.extensions_required = vec!["KHR_materials_unlit".into()];
    view_filling_quad_coloured(&mut w, m, Some(&quad_colour));
    let mut loaded = load(&w, "coloured_quad");
    stage(&mut loaded.scene);
    loaded.scene
}

/// Vertex colours as the Sample Viewer draws them (glTF 3.9.2: base colour × COLOR_0, its
/// alpha × COLOR_0's): the unlit quad shows factor × the interpolated colour, computed
/// here from the pixel's place, in forward shading, the hardware visibility buffer and
/// the compute-first default frame, and in tiled deferred (its colour kept to 8 bits);
/// masked at 0.5, its left half (vertex alpha under 0.5) is cut away in each.
#[test]
fn vertex_colours_multiply_the_base_colour_and_alpha_in_every_fast_path() {
    let mut r = renderer();
    let expected = |x: u32, y: u32| {
        let (tx, ty) = quad_place(x, y);
        let c = COLOUR_FACTOR * quad_colour(tx, ty);
        [c.x, c.y, c.z]
    };
    let opaque = coloured_quad(None);
    let masked = coloured_quad(Some(0.5));
    let mut failures = Vec::new();
    for graph in [
        "forward_plus.ron",
        "visibility_buffer.ron",
        "default.ron",
        "tiled_deferred_prepass.ron",
        "tiled_deferred_packed.ron",
    ] {
        let tol = if graph.starts_with("tiled_deferred") {
            deferred_colour_tol()
        } else {
            VERTEX_COLOUR_TOL
        };
        let img = render_file(&mut r, graph, &opaque, W, H).image;
        let (d, x, y) = worst_abs(&img, expected);
        println!("{graph} opaque: worst {d:.2e} at ({x}, {y})");
        if d > tol {
            failures.push(format!("{graph}: pixel ({x}, {y}) off by {d}"));
        }
        let img = render_file(&mut r, graph, &masked, W, H).image;
        let (d, x, y) = worst_abs(&img, |x, y| {
            if quad_place(x, y).0 < 0.5 {
                [0.0; 3]
            } else {
                expected(x, y)
            }
        });
        println!("{graph} masked: worst {d:.2e} at ({x}, {y})");
        if d > tol {
            failures.push(format!("{graph} masked: pixel ({x}, {y}) off by {d}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Khronos's Avocado (tests/assets/khronos/Avocado, geometry only) carries the tangents
/// its exporter (glTF Tools for Unity) baked its normal map with: MikkTSpace here, from
/// its positions, normals and uvs alone, gives nearly the same frames. Not bit for bit:
/// the exporter's differ at a few corners (measured: 37 of 2046 corners more than 0.05
/// apart, 3 with the other sign; WaterBottle, by the same exporter, 1.8% and 0.9%). A
/// wrong convention (w from glTF's downward v) flips every sign.
const MAX_SIGN_FLIPS: usize = 10;
const MAX_FAR_CORNERS: usize = 80;

#[test]
fn mikktspace_reproduces_a_sample_models_baked_tangents() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/assets/khronos/Avocado/Avocado.gltf");
    let loaded = scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let file = &loaded.scene.meshes[0];
    let mut generated = file.clone();
    generated.tangents.clear();
    assert!(lightgraph::scene::tangent_space::mikktspace_tangents(
        &mut generated
    ));
    // Corner by corner: the generated mesh's vertex against the file's at that corner.
    let (mut worst, mut sign_flips, mut far) = (0.0f32, 0, 0);
    for (&g, &f) in generated.indices.iter().zip(&file.indices) {
        let (tg, tf) = (generated.tangents[g as usize], file.tangents[f as usize]);
        let d = (tg.truncate() - tf.truncate()).length();
        worst = worst.max(d);
        if d > 0.05 {
            far += 1;
        }
        if tg.w != tf.w {
            sign_flips += 1;
        }
    }
    let corners = file.indices.len();
    println!("Avocado: {corners} corners, worst |Δt| {worst:.2e}, {far} over 0.05, {sign_flips} sign flips");
    assert!(
        sign_flips <= MAX_SIGN_FLIPS && far <= MAX_FAR_CORNERS,
        "{sign_flips} sign flips (bound {MAX_SIGN_FLIPS}), {far} corners over 0.05 (bound {MAX_FAR_CORNERS})"
    );
}

/// A malformed or overflowing transform is an error naming the file, the material, the
/// texture and the extension.
#[test]
fn a_bad_texture_transform_is_an_error_naming_the_texture() {
    for (transform, says) in [
        ("{\"scale\":[1e39,1]}", "not all finite"),
        ("{\"offset\":\"left\"}", "offset is not two numbers"),
    ] {
        let mut w = GltfWriter::new();
        let tex = w.add_texture_png("texels", &texels(), ImageStorage::BufferView);
        let m = w.add_material(&MaterialDesc {
            name: "bumpy".into(),
            normal_texture: Some(tex),
            texture_transforms: vec![("normalTexture", transform.into())],
            ..Default::default()
        });
        let (p, n, uv, i) = lightgraph::scene::gltf_writer::grid(1, 1.0);
        let mesh = w.add_simple_mesh("grid", &p, Some(&n), Some(&uv), Some(&i), Some(m));
        let node = w.add_node(&lightgraph::scene::gltf_writer::NodeDesc {
            mesh: Some(mesh),
            ..Default::default()
        });
        w.add_root(node);
        let d = tmp("bad_transform");
        let path = d.join("bad.gltf");
        w.write_gltf(
            &path,
            &lightgraph::scene::gltf_writer::BufferStorage::Embedded,
        )
        .unwrap();
        let Err(e) = scene::load(&path) else {
            panic!("{transform}: loaded without an error");
        };
        let e = e.to_string();
        for part in [
            "bad.gltf",
            "material 0",
            "normalTexture",
            "KHR_texture_transform",
            says,
        ] {
            assert!(e.contains(part), "{e:?} does not say {part:?}");
        }
    }
}

/// A RON material sets a texture's sampler and transform as glTF does; slots sharing a
/// sampler share its binding.
#[test]
fn ron_material_textures_take_a_sampler_and_a_transform() {
    let d = tmp("ron_sampler");
    texels().save(d.join("t.png")).unwrap();
    let src = r#"(
        name: "tiles",
        textures: {
            "a": (file: "t.png", srgb: true, sampler: (wrap_u: MirroredRepeat, mag_filter: Nearest, mipmap_filter: None)),
            "b": (file: "t.png", transform: Some((offset: (0.5, 0), rotation: 0.25, scale: (2, 2)))),
            "c": (file: "t.png", sampler: (wrap_u: MirroredRepeat, mag_filter: Nearest, mipmap_filter: None)),
        },
        layers: [(lobes: [Lambert(color: Tex(texture: "a", scale: (1, 1, 1)))])],
    )"#;
    let m = lightgraph::material::Material::parse(src, d.join("tiles.ron")).unwrap();
    let slots = m.texture_slots();
    assert_eq!(slots[0].sampler.wrap_u, Wrap::MirroredRepeat);
    assert_eq!(slots[0].sampler.mipmap_filter, MipmapFilter::None);
    assert_eq!(slots[1].sampler, SamplerDesc::default());
    assert_eq!(slots[1].transform.unwrap().scale, (2.0, 2.0));
    let (samplers, of_slot) = m.samplers();
    assert_eq!(samplers.len(), 2);
    assert_eq!(of_slot, vec![0, 1, 0]);
    let code = m.wgsl().unwrap();
    // Textures at 1..=3, the second sampler after them.
    assert!(
        code.contains("@group(2) @binding(4) var material_sampler1: sampler;"),
        "{code}"
    );
    assert!(
        code.contains("textureSample(material_tex2, material_sampler, p.uv)"),
        "{code}"
    );
    assert!(
        code.contains("textureSample(material_tex1, material_sampler1, uv1)"),
        "{code}"
    );
}

/// Materials that read one image share its GPU copy: AlphaBlendModeTest's glass and four
/// label materials read one image, uploaded once (by the first of them in the scene's
/// order), the others binding that copy; the bed's own three textures are uploaded for
/// it.
#[test]
fn materials_that_read_one_image_upload_it_once() {
    let r = renderer();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("tests/assets/khronos/AlphaBlendModeTest/AlphaBlendModeTest.gltf");
    let s = scene::load(&path).unwrap().scene;
    let programs =
        lightgraph::render::MaterialProgram::for_scene(&r.ctx.device, &r.ctx.queue, &s).unwrap();
    let bytes = |name: &str| {
        programs
            .iter()
            .find(|p| p.name == name)
            .unwrap_or_else(|| panic!("material {name}"))
            .texture_bytes
    };
    assert!(bytes("MatBed") > 0);
    let labels = [
        "MatBlend",
        "MatCutoff25",
        "MatCutoff75",
        "MatCutoffDefault",
        "MatOpaque",
    ];
    let uploaded: Vec<u64> = labels.iter().map(|n| bytes(n)).filter(|&b| b > 0).collect();
    assert_eq!(
        uploaded.len(),
        1,
        "the labels uploaded {} times",
        uploaded.len()
    );
}
