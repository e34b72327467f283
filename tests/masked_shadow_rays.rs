//! Ray-cast shadows of alpha-masked casters, on the real adapter (lavapipe on CI): a quad
//! textured with alpha stripes (255 and 20, cut at 0.5) over a floor under one casting
//! point light. Every floor pixel's shadow, in every graph that traces rays (jobs from
//! the G-buffer, from the visibility buffer, rays in the light loop, Forward+, tiled
//! deferred, the compute-first frame and stochastic light sampling), equals the stripes projected from the light
//! (computed here from the texture's stripe layout, not by the shaders' code), except
//! pixels whose projection lies within a texel and a half of a stripe's or the quad's
//! edge (counted). The CPU twin (`ShadowBvh::occluded`) agrees on the same pixels.
//!
//! Each sampler a masked material may read through (mirrored repeat, clamp to edge, a
//! uv transform, the second uv set, bilinear filtering, the vertex alpha) on quads hit by
//! rays straight down: the GPU's `bvh_occluded` (a standalone kernel) and the CPU twin
//! each equal the texel the glTF sampler's definition picks (computed here in f64),
//! except rays within 1e-3 texel of a texel's edge or 1e-3 of the cutoff (counted).
//!
//! A byte budget (the device's storage binding limit) first copies the textures at a
//! smaller mip level, then gives the alpha test up, saying so. A reloaded masked
//! material (a copy of the upload with its program replaced, as hot reload makes)
//! reshapes the rays' shadows: the BVH's alpha is built again.

mod common;

use common::shadow_jobs::raycast_inspection_graph;
use common::textured::push_striped_quad;
use common::{graph_text, lambert, prepare_text, renderer};
use glam::{DVec3, Vec3};
use lightgraph::scene::geometry::MeshBuilder;
use lightgraph::scene::{light_flags, Camera, Light, Scene};
use lightgraph::shadow::{shadow_ray, ShadowBvh};

const W: u32 = 128;
const H: u32 = 96;
/// Shaders' SHADOW_NORMAL_OFFSET default (ShadowRayCast's normal_offset).
const OFFSET: f32 = 1e-4;
const LIGHT: Vec3 = Vec3::new(0.3, 3.0, 0.2);
/// The striped quad: centre, half extents along x and along −z (uv over [0, 2]²).
const QUAD_Y: f64 = 1.0;
const HALF: f64 = 0.8;
/// The stripes texture's width in texels (`common::textured::checker`, 64 a side).
const TEXELS: f64 = 64.0;

fn scene(masked: bool) -> Scene {
    let mut floor = MeshBuilder::new("floor", 0);
    floor.quad(
        Vec3::new(-4.0, 0.0, 4.0),
        Vec3::new(8.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -8.0),
        glam::Vec2::ONE,
    );
    let mut light = Light::point(LIGHT, 30.0, Vec3::ONE, 5.0);
    light.flags |= light_flags::CASTS_SHADOW;
    let mut s = Scene {
        name: "striped quad over a floor".into(),
        meshes: vec![floor.build()],
        materials: vec![lambert("floor", Vec3::splat(0.8))],
        lights: vec![light],
        camera: Camera {
            eye: Vec3::new(0.0, 5.0, 2.5),
            target: Vec3::new(0.0, 0.0, 0.0),
            ..Default::default()
        },
        ..Default::default()
    };
    push_striped_quad(
        &mut s,
        "stripes",
        Vec3::new(0.0, QUAD_Y as f32, 0.0),
        Vec3::new(HALF as f32, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -HALF as f32),
        !masked,
    );
    s
}

/// Where the floor point `p` sees the light through the quad's plane: Some(shadowed) or
/// None within 1.5 texels of a stripe's edge or 1e-3 m of the quad's. The stripes are
/// `checker`'s alpha: texel column x is opaque where ⌊4x / 64⌋ is even.
fn expected(p: DVec3) -> Option<bool> {
    let l = LIGHT.as_dvec3();
    let q = p + (l - p) * ((QUAD_Y - p.y) / (l.y - p.y));
    let (a, b) = (q.x / HALF, -q.z / HALF);
    let edge = (1.0 - a.abs()).abs().min((1.0 - b.abs()).abs()) * HALF;
    if edge < 1e-3 {
        return None;
    }
    if a.abs() > 1.0 || b.abs() > 1.0 {
        return Some(false);
    }
    let x = (a + 1.0).fract() * TEXELS;
    let stripe = TEXELS / 4.0;
    let from_edge = (x / stripe - (x / stripe).round()).abs() * stripe;
    if from_edge < 1.5 {
        return None;
    }
    Some(((x / stripe).floor() as u32).is_multiple_of(2))
}

/// The floor's world positions per pixel (None off the floor), from the G-buffer of
/// raycast_shadows.ron.
fn floor_positions(r: &mut lightgraph::render::Renderer, s: &Scene) -> Vec<Option<DVec3>> {
    let text = raycast_inspection_graph();
    let prepared = prepare_text(r, &text, s, W, H, false).expect("prepare");
    prepared.render(r).expect("render");
    let g = prepared.read_texture(r, "g_position").unwrap();
    g.iter()
        .map(|g| {
            (g[3] >= 0.0 && g[1].abs() < 1e-3)
                .then(|| DVec3::new(g[0] as f64, g[1] as f64, g[2] as f64))
        })
        .collect()
}

#[test]
fn masked_casters_shadow_only_where_their_alpha_is_kept_in_every_tracer() {
    let mut r = renderer();
    let s = scene(true);
    let floor = floor_positions(&mut r, &s);
    // The CPU twin on the floor's rays.
    let bvh = ShadowBvh::build(&s).unwrap();
    assert!(
        bvh.alpha.records() == 2,
        "the quad's two triangles alpha-test"
    );
    let (mut shadowed, mut lit, mut ambiguous) = (0, 0, 0);
    for (pixel, p) in floor.iter().enumerate() {
        let Some(p) = p else { continue };
        let Some(hidden) = expected(*p) else {
            ambiguous += 1;
            continue;
        };
        let (o, dir, t_max) = shadow_ray(p.as_vec3(), Vec3::Y, LIGHT, OFFSET);
        assert_eq!(
            bvh.occluded(o, dir, t_max),
            hidden,
            "CPU twin at pixel {pixel}"
        );
        if hidden {
            shadowed += 1;
        } else {
            lit += 1;
        }
    }
    eprintln!("floor: {shadowed} shadowed, {lit} lit, {ambiguous} by an edge");
    assert!(
        shadowed > 150 && lit > 2000,
        "{shadowed} shadowed, {lit} lit"
    );
    for graph in [
        "raycast_shadows.ron",
        "raycast_shadows_naive.ron",
        "tiled_deferred_raycast_shadows.ron",
        "transparent_raycast_shadows.ron",
        "visibility_raycast_shadows.ron",
        "visibility_raycast_shadows_naive.ron",
        "default.ron",
        "visibility_stochastic_shadows.ron",
    ] {
        let prepared = prepare_text(&mut r, &graph_text(graph), &s, W, H, false)
            .unwrap_or_else(|e| panic!("{graph}: {e}"));
        let image = prepared.render(&r).expect("render").image;
        assert_eq!(image.len(), (W * H) as usize, "{graph}: image size");
        let mut wrong = Vec::new();
        for (pixel, p) in floor.iter().enumerate() {
            let Some(hidden) = p.and_then(expected) else {
                continue;
            };
            // No ambient light: a shadowed floor pixel is black, a lit one is not.
            if (image[pixel][0] == 0.0) != hidden {
                wrong.push(pixel);
            }
        }
        assert!(
            wrong.is_empty(),
            "{graph}: {} floor pixels shadowed against the stripes, first {:?}",
            wrong.len(),
            &wrong[..wrong.len().min(8)]
        );
    }
}

#[test]
fn the_same_quad_opaque_shadows_its_whole_square() {
    // What the stripes are cut from: without the mask every ray through the square is
    // blocked, so the test above can tell a mask from none.
    let mut r = renderer();
    let s = scene(false);
    let floor = floor_positions(&mut r, &s);
    let bvh = ShadowBvh::build(&s).unwrap();
    assert_eq!(bvh.alpha.records(), 0);
    let prepared = prepare_text(&mut r, &graph_text("default.ron"), &s, W, H, false).unwrap();
    let image = prepared.render(&r).expect("render").image;
    let mut through_cut_outs = 0;
    for (pixel, p) in floor.iter().enumerate() {
        if let (Some(p), Some(false)) = (p, p.and_then(expected)) {
            let l = LIGHT.as_dvec3();
            let q = *p + (l - *p) * ((QUAD_Y - p.y) / (l.y - p.y));
            if q.x.abs() < HALF && q.z.abs() < HALF {
                assert_eq!(image[pixel][0], 0.0, "pixel {pixel} under the solid quad");
                through_cut_outs += 1;
            }
        }
    }
    assert!(
        through_cut_outs > 150,
        "{through_cut_outs} pixels under cut-outs"
    );
}

/// What a standalone kernel of `shadow/bvh.wgsl` answers for each ray (origin, dir,
/// t_max): `bvh_occluded` on the GPU with the BVH's alpha data bound.
fn gpu_occluded(
    r: &lightgraph::render::Renderer,
    bvh: &ShadowBvh,
    rays: &[(Vec3, Vec3, f32)],
) -> Vec<bool> {
    use lightgraph::shader::ShaderLibrary;
    use std::collections::BTreeMap;
    use wgpu::util::DeviceExt;
    let defines = BTreeMap::from([
        ("BVH_STANDALONE".to_string(), "1".to_string()),
        ("BVH_ALPHA_TEST".to_string(), "1".to_string()),
    ]);
    let mut text = ShaderLibrary::builtin()
        .compose("shadow/bvh.wgsl", &defines, &BTreeMap::new())
        .unwrap()
        .text;
    text.push_str(
        "@group(0) @binding(3) var<storage, read> rays: array<vec4<f32>>;\n\
         @group(0) @binding(4) var<storage, read_write> hits: array<u32>;\n\
         @compute @workgroup_size(64)\n\
         fn main(@builtin(global_invocation_id) id: vec3<u32>) {\n\
             let k = id.x;\n\
             if (k >= arrayLength(&hits)) { return; }\n\
             let o = rays[2u * k];\n\
             let d = rays[2u * k + 1u];\n\
             hits[k] = select(0u, 1u, bvh_occluded(o.xyz, d.xyz, d.w));\n\
         }\n",
    );
    let device = &r.ctx.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("alpha rays"),
        source: wgpu::ShaderSource::Wgsl(text.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("alpha rays"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let storage = |label: &str, bytes: &[u8], extra: wgpu::BufferUsages| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytes,
            usage: wgpu::BufferUsages::STORAGE | extra,
        })
    };
    let (nodes, tris) = bvh.gpu_bytes();
    let ray_data: Vec<[f32; 4]> = rays
        .iter()
        .flat_map(|(o, d, t)| [o.extend(0.0).to_array(), d.extend(*t).to_array()])
        .collect();
    let buffers = [
        storage("nodes", nodes, wgpu::BufferUsages::empty()),
        storage("triangles", tris, wgpu::BufferUsages::empty()),
        storage(
            "alpha",
            bvh.alpha_bytes().unwrap(),
            wgpu::BufferUsages::empty(),
        ),
        storage(
            "rays",
            bytemuck::cast_slice(&ray_data),
            wgpu::BufferUsages::empty(),
        ),
        storage(
            "hits",
            &vec![0u8; 4 * rays.len()],
            wgpu::BufferUsages::COPY_SRC,
        ),
    ];
    let entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .enumerate()
        .map(|(k, b)| wgpu::BindGroupEntry {
            binding: k as u32,
            resource: b.as_entire_binding(),
        })
        .collect();
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    let read = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: 4 * rays.len() as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups((rays.len() as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&buffers[4], 0, &read, 0, read.size());
    r.ctx.queue.submit([encoder.finish()]);
    read.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let words: Vec<u32> =
        bytemuck::cast_slice(&read.slice(..).get_mapped_range().unwrap()[..]).to_vec();
    words.into_iter().map(|w| w != 0).collect()
}

/// How one quad of the sampler scene maps its points to what its material reads.
#[derive(Clone, Copy)]
struct SamplerCase {
    name: &'static str,
    wrap: Wrap,
    filter: Filter,
    /// uv at the quad's (0, 0) and (1, 1) corners.
    uv: ([f64; 2], [f64; 2]),
    transform: Option<UvTransform>,
    /// The texture read through TEXCOORD_1 (TEXCOORD_0 left at zero).
    uv1: bool,
    /// No texture: alpha is the vertex alpha, 0 along the quad's left edge, 1 along its right.
    vertex_alpha: bool,
}

use lightgraph::material::model::{
    Filter, MipmapFilter, SamplerDesc, TextureSampling, UvTransform, Wrap,
};

const CASES: [SamplerCase; 6] = [
    SamplerCase {
        name: "mirrored repeat, nearest",
        wrap: Wrap::MirroredRepeat,
        filter: Filter::Nearest,
        uv: ([-1.5, -1.25], [2.5, 2.0]),
        transform: None,
        uv1: false,
        vertex_alpha: false,
    },
    SamplerCase {
        name: "clamp to edge, nearest",
        wrap: Wrap::ClampToEdge,
        filter: Filter::Nearest,
        uv: ([-0.5, -0.75], [1.5, 1.25]),
        transform: None,
        uv1: false,
        vertex_alpha: false,
    },
    SamplerCase {
        name: "repeat, nearest, uv transform",
        wrap: Wrap::Repeat,
        filter: Filter::Nearest,
        uv: ([0.0, 0.0], [1.0, 1.0]),
        transform: Some(UvTransform {
            offset: (0.1, 0.2),
            rotation: 0.3,
            scale: (1.5, 2.0),
        }),
        uv1: false,
        vertex_alpha: false,
    },
    SamplerCase {
        name: "repeat, nearest, second uv set",
        wrap: Wrap::Repeat,
        filter: Filter::Nearest,
        uv: ([0.25, 0.0], [1.75, 1.0]),
        transform: None,
        uv1: true,
        vertex_alpha: false,
    },
    SamplerCase {
        name: "vertex alpha",
        wrap: Wrap::Repeat,
        filter: Filter::Nearest,
        uv: ([0.0, 0.0], [1.0, 1.0]),
        transform: None,
        uv1: false,
        vertex_alpha: true,
    },
    SamplerCase {
        name: "repeat, bilinear",
        wrap: Wrap::Repeat,
        filter: Filter::Linear,
        uv: ([-0.5, 0.0], [1.5, 1.0]),
        transform: None,
        uv1: false,
        vertex_alpha: false,
    },
];

/// Texels a side of the random alpha texture.
const N: usize = 8;

/// Alpha 0 or 255 per texel, fixed.
fn alpha_texels() -> Vec<u8> {
    let mut rng = common::Rng(5);
    (0..N * N)
        .map(|_| if rng.f32() < 0.5 { 0 } else { 255 })
        .collect()
}

/// Quads side by side in the plane z = 0, 1 m a side, facing +z: quad k spans
/// x in [2k, 2k + 1], y in [0, 1].
fn sampler_scene() -> Scene {
    use lightgraph::scene::{AlphaMode, Mesh, SlotSampling, SurfaceMaterial, TextureImage};
    let rgba8: Vec<u8> = alpha_texels()
        .iter()
        .flat_map(|&a| [200, 100, 50, a])
        .collect();
    let image = std::sync::Arc::new(TextureImage {
        name: "random alpha".into(),
        width: N as u32,
        height: N as u32,
        rgba8,
        srgb: true,
    });
    let mut s = Scene::default();
    for (k, c) in CASES.iter().enumerate() {
        let sampler = SamplerDesc {
            wrap_u: c.wrap,
            wrap_v: c.wrap,
            mag_filter: c.filter,
            min_filter: c.filter,
            mipmap_filter: MipmapFilter::Linear,
        };
        let mut sampling = SlotSampling::default();
        sampling.base_color = TextureSampling {
            sampler,
            transform: c.transform,
            tex_coord: u32::from(c.uv1),
        };
        s.materials.push(SurfaceMaterial {
            name: c.name.into(),
            base_color_texture: (!c.vertex_alpha).then(|| image.clone()),
            alpha_mode: AlphaMode::Mask(0.5),
            double_sided: true,
            vertex_color: c.vertex_alpha,
            sampling,
            ..Default::default()
        });
        let x0 = 2.0 * k as f32;
        let mut m = Mesh {
            name: c.name.into(),
            material: k,
            ..Default::default()
        };
        for (s_, t) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            m.positions.push(Vec3::new(x0 + s_, t, 0.0));
            m.normals.push(Vec3::Z);
            let (lo, hi) = c.uv;
            let uv = glam::Vec2::new(
                (lo[0] + (hi[0] - lo[0]) * s_ as f64) as f32,
                (lo[1] + (hi[1] - lo[1]) * t as f64) as f32,
            );
            if c.uv1 {
                m.uvs.push(glam::Vec2::ZERO);
                m.uvs1.push(uv);
            } else {
                m.uvs.push(uv);
            }
            m.tangents.push(glam::Vec4::new(1.0, 0.0, 0.0, 1.0));
            if c.vertex_alpha {
                m.colors.push(glam::Vec4::new(1.0, 1.0, 1.0, s_));
            }
        }
        m.indices.extend([0, 1, 2, 0, 2, 3]);
        s.meshes.push(m);
    }
    s
}

/// The texel index a nearest sampler reads at `c` (uv units) by the glTF sampler's
/// definition, or None within 1e-3 of a texel's edge.
fn nearest_texel(c: f64, wrap: Wrap) -> Option<usize> {
    let n = N as f64;
    let folded = match wrap {
        Wrap::Repeat => c - c.floor(),
        // Past either side: the edge texel, whatever the distance.
        Wrap::ClampToEdge if c <= 0.0 => return Some(0),
        Wrap::ClampToEdge if c >= 1.0 => return Some(N - 1),
        Wrap::ClampToEdge => c,
        // Even periods run forwards, odd ones backwards.
        Wrap::MirroredRepeat => {
            let period = c.floor();
            let f = c - period;
            if (period as i64).rem_euclid(2) == 0 {
                f
            } else {
                1.0 - f
            }
        }
    };
    let x = folded * n;
    if (x - x.round()).abs() < 1e-3 {
        return None;
    }
    Some((x.floor() as usize).min(N - 1))
}

/// Whether case `c`'s material keeps (blocks rays) at point (s, t) of its quad, computed
/// from the case's definition; None where a texel's edge or the cutoff is too near to say.
fn kept(c: &SamplerCase, s: f64, t: f64, texels: &[u8]) -> Option<bool> {
    if c.vertex_alpha {
        return ((s - 0.5).abs() > 1e-4).then_some(s >= 0.5);
    }
    let (lo, hi) = c.uv;
    let (mut u, mut v) = (lo[0] + (hi[0] - lo[0]) * s, lo[1] + (hi[1] - lo[1]) * t);
    if let Some(tr) = c.transform {
        // KHR_texture_transform: scale, then rotate, then offset.
        let (su, sv) = (u * tr.scale.0 as f64, v * tr.scale.1 as f64);
        let (sin, cos) = (tr.rotation as f64).sin_cos();
        u = cos * su + sin * sv + tr.offset.0 as f64;
        v = -sin * su + cos * sv + tr.offset.1 as f64;
    }
    if c.filter == Filter::Linear {
        // Bilinear between the four texel centres around (u, v), tiled (repeat only).
        assert_eq!(c.wrap, Wrap::Repeat);
        let (x, y) = (u * N as f64 - 0.5, v * N as f64 - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let at = |i: f64, j: f64| {
            let (i, j) = (
                i.rem_euclid(N as f64) as usize,
                j.rem_euclid(N as f64) as usize,
            );
            texels[j * N + i] as f64 / 255.0
        };
        let (tx, ty) = (x - x0, y - y0);
        let top = at(x0, y0) * (1.0 - tx) + at(x0 + 1.0, y0) * tx;
        let bottom = at(x0, y0 + 1.0) * (1.0 - tx) + at(x0 + 1.0, y0 + 1.0) * tx;
        let alpha = top * (1.0 - ty) + bottom * ty;
        return ((alpha - 0.5).abs() > 1e-3).then_some(alpha >= 0.5);
    }
    let (i, j) = (nearest_texel(u, c.wrap)?, nearest_texel(v, c.wrap)?);
    Some(texels[j * N + i] >= 128)
}

#[test]
fn every_wrap_mode_filter_transform_and_uv_set_alpha_tests_rays_as_sampled() {
    let r = renderer();
    let scene = sampler_scene();
    let bvh = ShadowBvh::build(&scene).unwrap();
    assert!(
        bvh.alpha.unsupported.is_empty(),
        "{:?}",
        bvh.alpha.unsupported
    );
    assert_eq!(bvh.alpha.records(), 2 * CASES.len() as u32);
    let texels = alpha_texels();
    let mut rng = common::Rng(17);
    let mut rays = Vec::new();
    let mut points = Vec::new();
    for k in 0..CASES.len() {
        for _ in 0..600 {
            let (s, t) = (rng.f32() as f64, rng.f32() as f64);
            let x = 2.0 * k as f64 + s;
            // Straight down through the quad; a ray on its diagonal may meet both
            // triangles or neither, so the diagonal's neighbourhood is left out.
            if (s - t).abs() < 1e-4 {
                continue;
            }
            rays.push((
                Vec3::new(x as f32, t as f32, 1.0),
                Vec3::new(0.0, 0.0, -2.0),
                1.0,
            ));
            points.push((k, s, t));
        }
    }
    let gpu = gpu_occluded(&r, &bvh, &rays);
    for (k, c) in CASES.iter().enumerate() {
        let (mut blocked, mut passed, mut unsure, mut gpu_differs) = (0, 0, 0, 0);
        for (i, &(case, s, t)) in points.iter().enumerate() {
            if case != k {
                continue;
            }
            let (o, d, t_max) = rays[i];
            let cpu = bvh.occluded(o, d, t_max);
            if cpu != gpu[i] {
                gpu_differs += 1;
            }
            match kept(c, s, t, &texels) {
                Some(want) => {
                    assert_eq!(cpu, want, "{}: CPU twin at ({s}, {t})", c.name);
                    assert_eq!(gpu[i], want, "{}: GPU at ({s}, {t})", c.name);
                    if want {
                        blocked += 1;
                    } else {
                        passed += 1;
                    }
                }
                None => unsure += 1,
            }
        }
        eprintln!(
            "{}: {blocked} blocked, {passed} through, {unsure} by an edge; GPU against the CPU twin: {gpu_differs} differ",
            c.name
        );
        // The twins run the same f32 steps; only a rounding at the cutoff could split them.
        assert!(gpu_differs <= 2, "{}: {gpu_differs} rays differ", c.name);
        assert!(
            blocked > 100 && passed > 100,
            "{}: {blocked} / {passed}",
            c.name
        );
    }
}

#[test]
fn a_byte_budget_shrinks_the_textures_then_gives_the_alpha_test_up() {
    use common::textured::checker;
    use lightgraph::shadow::BuildOptions;
    // The stripes at 256 texels a side (256 KiB of texels), over a grid of floor points.
    let mut s = scene(true);
    s.materials[1].base_color_texture = Some(std::sync::Arc::new(checker(
        "stripes",
        256,
        8,
        [230, 120, 40],
        [40, 90, 200],
    )));
    let points: Vec<DVec3> = (0..80 * 80)
        .map(|k| {
            DVec3::new(
                -2.0 + (k % 80) as f64 * 0.05,
                0.0,
                -2.0 + (k / 80) as f64 * 0.05,
            )
        })
        .collect();
    let agreement = |budget: u64| {
        let options = BuildOptions {
            max_alpha_bytes: budget,
            ..Default::default()
        };
        let bvh = ShadowBvh::build_with(&s, &options).unwrap();
        let bytes = 4 * bvh.alpha.words.len() as u64;
        assert!(bytes <= budget, "{bytes} bytes over a budget of {budget}");
        let (mut agree, mut total) = (0, 0);
        for p in &points {
            let Some(hidden) = expected(*p) else { continue };
            let (o, dir, t_max) = shadow_ray(p.as_vec3(), Vec3::Y, LIGHT, OFFSET);
            total += 1;
            agree += usize::from(bvh.occluded(o, dir, t_max) == hidden);
        }
        (bvh, bytes, agree, total)
    };
    let (full, full_bytes, agree, total) = agreement(1 << 20);
    assert!(full.alpha.unsupported.is_empty());
    assert_eq!(agree, total, "at level 0");
    // Half the level-0 texels: the next level (128 a side, 64 KiB) fits, and its box
    // filter keeps the 32-texel stripes but for their edge texels.
    let (half, bytes, agree, total) = agreement(full_bytes / 2);
    assert_eq!(half.alpha.records(), 2);
    assert!(bytes < full_bytes / 3, "{bytes} of {full_bytes}");
    assert!(agree * 100 >= total * 98, "{agree} of {total} at level 1");
    // Under the 64-texel floor: no alpha test, said, and the quad blocks as a solid one.
    let (none, _, _, _) = agreement(8 << 10);
    assert_eq!(none.alpha.records(), 0);
    assert!(
        none.alpha.unsupported[0].contains("over the 0 MiB"),
        "{:?}",
        none.alpha.unsupported
    );
    let l = LIGHT.as_dvec3();
    let under_cut_outs: Vec<&DVec3> = points
        .iter()
        .filter(|p| {
            let q = **p + (l - **p) * ((QUAD_Y - p.y) / (l.y - p.y));
            expected(**p) == Some(false) && q.x.abs() < HALF && q.z.abs() < HALF
        })
        .collect();
    assert!(under_cut_outs.len() > 100, "{}", under_cut_outs.len());
    for p in under_cut_outs {
        let (o, dir, t_max) = shadow_ray(p.as_vec3(), Vec3::Y, LIGHT, OFFSET);
        assert!(none.occluded(o, dir, t_max), "under a cut-out at {p}");
        assert!(!full.occluded(o, dir, t_max), "under a cut-out at {p}");
    }
}

#[test]
fn a_reloaded_masked_material_reshapes_the_rays_shadows() {
    use lightgraph::graph::{self, FrameSize};
    use lightgraph::material::Material;
    use lightgraph::render::{MaterialProgram, SceneGpu};
    use lightgraph::scene::AlphaMode;
    use lightgraph::shader::ShaderLibrary;
    let mut r = renderer();
    let before = scene(true);
    let floor = floor_positions(&mut r, &before);
    // The stripes' cut-out alpha is 20/255: a cutoff of 0.05 keeps every texel.
    let mut after = before.clone();
    after.materials[1].alpha_mode = AlphaMode::Mask(0.05);
    let size = FrameSize {
        width: W,
        height: H,
        lights: 1,
    };
    let frame = |r: &mut lightgraph::render::Renderer, s: &Scene, gpu: &SceneGpu| {
        let checked = graph::check_text(
            std::path::Path::new("default.ron"),
            &graph_text("default.ron"),
            &ShaderLibrary::builtin(),
        )
        .unwrap();
        let compiled = graph::compile(checked, &s.features(), size);
        let prepared = r.prepare(compiled, s, gpu, size, false).unwrap();
        prepared.render(r).unwrap().image
    };
    let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, &before).unwrap();
    let stripes = frame(&mut r, &before, &gpu);
    // What a material hot reload does: a copy of the live upload with the program
    // replaced, the scene (whose material the BVH's alpha reads) as it now stands.
    let mut edited = gpu.clone();
    let program = MaterialProgram::new(
        &r.ctx.device,
        &r.ctx.queue,
        &Material::from_surface(&after.materials[1]),
        after.materials[1].alpha_mode,
        true,
    )
    .unwrap();
    edited.set_material(1, program);
    let solid = frame(&mut r, &after, &edited);
    // Pixels that show the floor in both frames (the solid quad now hides some).
    let floor_after = floor_positions(&mut r, &after);
    let mut newly_shadowed = 0;
    for (pixel, p) in floor.iter().enumerate() {
        let (Some(p), Some(false), Some(_)) = (p, p.and_then(expected), floor_after[pixel]) else {
            continue;
        };
        let l = LIGHT.as_dvec3();
        let q = *p + (l - *p) * ((QUAD_Y - p.y) / (l.y - p.y));
        if q.x.abs() < HALF && q.z.abs() < HALF {
            // Under a cut-out: lit through it before, shadowed once every texel is kept.
            assert!(stripes[pixel][0] > 0.0, "pixel {pixel} lit before");
            assert_eq!(solid[pixel][0], 0.0, "pixel {pixel} after the edit");
            newly_shadowed += 1;
        }
    }
    assert!(newly_shadowed > 150, "{newly_shadowed} pixels");
}
