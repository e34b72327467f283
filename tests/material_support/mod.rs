//! Shared by the material tests: a deterministic RNG, sample generators that hit the hard
//! cases (roughness 0 and 1, grazing angles, GGX peaks), a compute-shader runner and the
//! error metric.
#![allow(dead_code)]

use lightgraph::gpu::{readback::read_buffer, GpuContext};
use wgpu::util::DeviceExt;

/// SplitMix64.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn f(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.f()
    }
    pub fn pick<T: Copy>(&mut self, xs: &[T]) -> T {
        xs[(self.next_u64() % xs.len() as u64) as usize]
    }
    pub fn unit(&mut self) -> [f64; 3] {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, std::f64::consts::TAU);
        let r = (1.0 - z * z).sqrt();
        [r * phi.cos(), r * phi.sin(), z]
    }
    /// Roughness with the edge cases well represented.
    pub fn roughness(&mut self) -> f64 {
        match self.next_u64() % 6 {
            0 => 0.0,
            1 => 1.0,
            2 => self.range(0.0, 0.08),
            _ => self.f(),
        }
    }
}

pub type V3 = [f64; 3];

pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
pub fn sc(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub fn norm(a: V3) -> V3 {
    sc(a, 1.0 / dot(a, a).sqrt())
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Rounds to what the GPU sees, so both sides evaluate the very same inputs.
pub fn f32v(a: V3) -> V3 {
    [a[0] as f32 as f64, a[1] as f32 as f64, a[2] as f32 as f64]
}

/// A direction at angle θ (cos θ = c) from `n`, azimuth φ.
fn around(n: V3, c: f64, phi: f64) -> V3 {
    let t = norm(if n[0].abs() < 0.9 {
        cross(n, [1.0, 0.0, 0.0])
    } else {
        cross(n, [0.0, 1.0, 0.0])
    });
    let b = cross(n, t);
    let s = (1.0 - c * c).max(0.0).sqrt();
    norm(add(
        add(sc(t, s * phi.cos()), sc(b, s * phi.sin())),
        sc(n, c),
    ))
}

/// One geometric configuration: normal, tangent (xyz, w = ±1), view, light (all f32-exact).
#[derive(Clone, Copy, Debug)]
pub struct Geo {
    pub n: V3,
    pub t: [f64; 4],
    pub v: V3,
    pub l: V3,
}

/// Random (n, t, v, l): a quarter near the specular peak (l ≈ mirror of v, within ~α),
/// grazing views and lights, normal incidence, retro-reflection, and some lights below the
/// horizon when `below` is set.
pub fn geo(rng: &mut Rng, below: bool) -> Geo {
    let n = rng.unit();
    let cos = |rng: &mut Rng| match rng.next_u64() % 8 {
        0 => rng.range(1e-4, 0.02),
        1 => 1.0,
        2 => rng.range(0.999, 1.0),
        _ => rng.range(0.0, 1.0).sqrt(),
    };
    let cv = cos(rng);
    let v = around(n, cv, rng.range(0.0, std::f64::consts::TAU));
    let mirror = add(sc(n, 2.0 * dot(n, v)), sc(v, -1.0));
    let l = match rng.next_u64() % 8 {
        0 | 1 => {
            // near the mirror direction: perturb by a small angle
            let eps = rng.pick(&[0.0, 1e-4, 1e-3, 3e-3, 1e-2, 0.05]) * rng.f();
            norm(add(mirror, sc(rng.unit(), eps)))
        }
        2 => v,
        3 if below => around(n, -rng.range(0.0, 1.0), rng.range(0.0, 6.3)),
        _ => around(n, cos(rng), rng.range(0.0, std::f64::consts::TAU)),
    };
    let t0 = rng.unit();
    let w = if rng.f() < 0.5 { 1.0 } else { -1.0 };
    let t = if rng.next_u64().is_multiple_of(5) {
        [0.0; 4] // no mesh tangent: the basis is built from n
    } else {
        let t = norm(add(t0, sc(n, -dot(n, t0))));
        let t = f32v(t);
        [t[0], t[1], t[2], w]
    };
    Geo {
        n: f32v(n),
        t,
        v: f32v(v),
        l: f32v(l),
    }
}

/// (n, v, l) with l within `max_angle` rad of v's mirror direction about n and n·v ≥ 0.05,
/// no mesh tangent: the specular peak, sampled densely.
pub fn near_mirror_geo(rng: &mut Rng, max_angle: f64) -> Geo {
    loop {
        let n = rng.unit();
        let v = norm(add(n, sc(rng.unit(), rng.range(0.0, 1.5))));
        if dot(n, v) < 0.05 {
            continue;
        }
        let mirror = add(sc(n, 2.0 * dot(n, v)), sc(v, -1.0));
        let l = norm(add(mirror, sc(rng.unit(), max_angle * rng.f())));
        return Geo {
            n: f32v(n),
            t: [0.0; 4],
            v: f32v(v),
            l: f32v(l),
        };
    }
}

/// A configuration as the GPU harnesses read it: n, t, v, l as four vec4s (w 0 but t's).
pub fn geo_floats(g: &Geo) -> [f32; 16] {
    let mut out = [0.0f32; 16];
    for (k, x) in [g.n[0], g.n[1], g.n[2], 0.0]
        .iter()
        .chain(&g.t)
        .chain(&[g.v[0], g.v[1], g.v[2], 0.0])
        .chain(&[g.l[0], g.l[1], g.l[2], 0.0])
        .enumerate()
    {
        out[k] = *x as f32;
    }
    out
}

/// Error of a GPU value against the reference: |g − r| / max(|r|, 1e-3), i.e. relative
/// where the reference is ≥ 1e-3 and absolute (scaled by 1e-3) below.
pub fn err(g: f32, r: f64) -> f64 {
    (g as f64 - r).abs() / r.abs().max(1e-3)
}

/// Runs `entry` of `wgsl` over `input` (storage, read, binding 0) writing `out_bytes` bytes
/// to binding 1, one invocation per `items` (workgroup size 64).
pub fn run_compute(
    gpu: &GpuContext,
    wgsl: &str,
    input: &[u8],
    out_bytes: u64,
    items: u32,
) -> Vec<u8> {
    run_compute_with_textures(gpu, wgsl, input, out_bytes, items, &[])
}

/// As [`run_compute`], plus `@group(2)`: a filtering sampler at binding 0 and one texture
/// per image at bindings 1.. (the material contract).
pub fn run_compute_with_textures(
    gpu: &GpuContext,
    wgsl: &str,
    input: &[u8],
    out_bytes: u64,
    items: u32,
    images: &[lightgraph::scene::TextureImage],
) -> Vec<u8> {
    let device = &gpu.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("material test"),
        source: wgpu::ShaderSource::Wgsl(wgsl.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("material test"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let inb = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("samples"),
        contents: input,
        usage: wgpu::BufferUsages::STORAGE,
    });
    let outb = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("out"),
        size: out_bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: inb.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: outb.as_entire_binding(),
            },
        ],
    });
    let group2 = (!images.is_empty()).then(|| {
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let views: Vec<_> = images
            .iter()
            .map(|img| {
                let tex = device.create_texture_with_data(
                    &gpu.queue,
                    &wgpu::TextureDescriptor {
                        label: Some(&img.name),
                        size: wgpu::Extent3d {
                            width: img.width,
                            height: img.height,
                            depth_or_array_layers: 1,
                        },
                        mip_level_count: 1,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D2,
                        format: if img.srgb {
                            wgpu::TextureFormat::Rgba8UnormSrgb
                        } else {
                            wgpu::TextureFormat::Rgba8Unorm
                        },
                        usage: wgpu::TextureUsages::TEXTURE_BINDING,
                        view_formats: &[],
                    },
                    wgpu::util::TextureDataOrder::LayerMajor,
                    &img.rgba8,
                );
                tex.create_view(&Default::default())
            })
            .collect();
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::Sampler(&sampler),
        }];
        for (i, v) in views.iter().enumerate() {
            entries.push(wgpu::BindGroupEntry {
                binding: i as u32 + 1,
                resource: wgpu::BindingResource::TextureView(v),
            });
        }
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("material textures"),
            layout: &pipeline.get_bind_group_layout(2),
            entries: &entries,
        })
    });
    let mut enc = device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        if let Some(g2) = &group2 {
            pass.set_bind_group(2, g2, &[]);
        }
        pass.dispatch_workgroups(items.div_ceil(64), 1, 1);
    }
    gpu.queue.submit([enc.finish()]);
    read_buffer(device, &gpu.queue, &outb).expect("readback")
}

pub fn f32s(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

pub fn to_bytes(xs: &[f32]) -> Vec<u8> {
    xs.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A view just behind the shading normal's horizon (n·v = −c < 0: the silhouettes of
/// smooth-shaded meshes, where interpolated normals turn away from the eye) and a light
/// nearly opposite it (l ≈ −v − k n, 0 < k < c, so n·l > 0): h = normalize(l + v) then
/// lies below the horizon, where GGX's D is zero (its χ⁺(n·h)).
pub fn back_facing(rng: &mut Rng) -> Geo {
    let n = rng.unit();
    let c = rng.pick(&[1e-4, 1e-3, 3e-3, 1e-2, 0.05]) * rng.range(0.5, 1.5);
    let v = around(n, -c, rng.range(0.0, std::f64::consts::TAU));
    let k = c * rng.range(0.05, 0.95);
    // off the exact line by up to a fraction of c (exactly on it: l + v ∥ −n)
    let tau = sc(rng.unit(), c * rng.pick(&[0.0, 1e-3, 1e-2, 0.1, 0.5]));
    let l = norm(add(add(sc(v, -1.0), sc(n, -k)), tau));
    let t0 = rng.unit();
    let t = f32v(norm(add(t0, sc(n, -dot(n, t0)))));
    Geo {
        n: f32v(n),
        t: [t[0], t[1], t[2], 1.0],
        v: f32v(v),
        l: f32v(l),
    }
}

/// The most a GGX lobe with F ≤ 1 can reflect, f·cos θl, for α_t, α_b ≤ 1: D ≤ 1/(π α_t α_b)
/// and V·cos θl ≤ 1/(2 min(α_t, α_b)) (Smith's Λ_v ≥ min α for views above the horizon),
/// both wherever n·h > 0.
pub fn ggx_cos_bound(at: f64, ab: f64) -> f64 {
    1.0 / (2.0 * std::f64::consts::PI * at * ab * at.min(ab))
}
