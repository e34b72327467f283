//! GPU (f32 WGSL) against the f64 reference: every lobe of the library on random
//! (n, l, v, roughness, F0, anisotropy, IOR) samples, then whole layered materials through
//! the generated `material_setup` + `material_eval`.
//!
//! Metric: |gpu − ref| / max(|ref|, 1e-3) ≤ 1e-4 (relative where ref ≥ 1e-3, absolute
//! below), and no NaN or Inf anywhere.

mod material_support;

use lightgraph::gpu::GpuContext;
use lightgraph::material::reference as r;
use lightgraph::material::wgsl::{LOBE_LIBRARY, SHADING_POINT_WGSL};
use lightgraph::material::{Material, WgslOptions};
use material_support::*;

const TOL: f64 = 1e-4;

const LOBE_NAMES: [&str; 7] = [
    "lambert",
    "oren_nayar",
    "ggx",
    "ggx_aniso",
    "sheen",
    "layer_through",
    "clearcoat",
];

const LOBE_HARNESS: &str = "
struct Sample {
    n: vec4<f32>,
    t: vec4<f32>,
    v: vec4<f32>,
    l: vec4<f32>,
    p: vec4<f32>, // roughness, anisotropy, ior, sigma·d
    f0: vec4<f32>,
};
@group(0) @binding(0) var<storage, read> samples: array<Sample>;
@group(0) @binding(1) var<storage, read_write> out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&samples)) {
        return;
    }
    let s = samples[i];
    let n = s.n.xyz;
    let v = s.v.xyz;
    let l = s.l.xyz;
    // As generated material code takes them: guarded |n × h|² unless a sheen lobe reads it.
    let d = lg_dirs(n, v, l, LG_S2_GUARDED);
    let ds = lg_dirs(n, v, l, LG_S2_EXACT);
    let t = lg_tangent(n, s.t);
    let b = lg_bitangent(n, t, s.t.w);
    let a = lg_alpha(s.p.x);
    let c = s.f0.xyz;
    let o = i * 7u;
    out[o] = vec4<f32>(lg_lambert(c), 0.0);
    out[o + 1u] = vec4<f32>(lg_oren_nayar(c, s.p.x, d), 0.0);
    out[o + 2u] = vec4<f32>(lg_ggx(c, a, d), 0.0);
    out[o + 3u] = vec4<f32>(lg_ggx_aniso(c, a, s.p.y, t, b, v, l, d), 0.0);
    out[o + 4u] = vec4<f32>(lg_sheen(c, s.p.x, ds), 0.0);
    out[o + 5u] = vec4<f32>(lg_through(s.p.z, 1.0, 1.0, s.p.w * vec3<f32>(1.0, 0.5, 0.1), i % 2u, d), 0.0);
    out[o + 6u] = vec4<f32>(lg_ggx(vec3<f32>(lg_ior_f0(s.p.z)), a, d), 0.0);
}
";

fn lobe_refs(i: usize, g: &Geo, p: [f64; 4], f0: r::V3) -> [r::V3; 7] {
    let d = r::dirs(g.n, g.v, g.l);
    let t = r::tangent(g.n, g.t);
    let b = r::bitangent(g.n, t, g.t[3]);
    let a = r::alpha(p[0]);
    [
        r::lambert(f0),
        r::oren_nayar(f0, p[0], &d),
        r::ggx(f0, a, &d),
        r::ggx_aniso(f0, a, p[1], t, b, g.v, g.l, &d),
        r::sheen(f0, p[0], &d),
        r::through(
            p[2],
            1.0,
            1.0,
            [p[3], p[3] * 0.5, p[3] * 0.1],
            i as u32 % 2,
            &d,
        ),
        r::ggx([r::ior_f0(p[2]); 3], a, &d),
    ]
}

/// A lobe's worst error: (error, case, channel, GPU value, reference value).
type Worst = (f64, usize, usize, f32, f64);

/// Every lobe of the harness over `cases` (geometry, [roughness, anisotropy, ior, σ·d],
/// F0) on the GPU against the f64 reference: each lobe's worst error and how many values
/// were not finite.
fn lobe_errors(gpu: &GpuContext, cases: &[(Geo, [f64; 4], r::V3)]) -> ([Worst; 7], usize) {
    let mut input = Vec::with_capacity(cases.len() * 24);
    for (g, p, f0) in cases {
        input.extend(geo_floats(g));
        input.extend(
            p.iter()
                .chain(&[f0[0], f0[1], f0[2], 0.0])
                .map(|x| *x as f32),
        );
    }
    let wgsl = format!("{LOBE_LIBRARY}\n{LOBE_HARNESS}");
    let out = f32s(&run_compute(
        gpu,
        &wgsl,
        &to_bytes(&input),
        (cases.len() * 7 * 16) as u64,
        cases.len() as u32,
    ));
    let mut worst = [(0.0f64, 0usize, 0usize, 0.0f32, 0.0f64); 7];
    let mut nonfinite = 0;
    for (i, (g, p, f0)) in cases.iter().enumerate() {
        let refs = lobe_refs(i, g, *p, *f0);
        for (k, rv) in refs.iter().enumerate() {
            for c in 0..3 {
                let gv = out[(i * 7 + k) * 4 + c];
                if !gv.is_finite() || !rv[c].is_finite() {
                    nonfinite += 1;
                    continue;
                }
                let e = err(gv, rv[c]);
                if e > worst[k].0 {
                    worst[k] = (e, i, c, gv, rv[c]);
                }
            }
        }
    }
    (worst, nonfinite)
}

fn print_worst(gpu: &GpuContext, cases: &[(Geo, [f64; 4], r::V3)], worst: &[Worst; 7]) {
    println!(
        "GPU vs f64 over {} samples ({}):",
        cases.len(),
        gpu.adapter_name()
    );
    for (k, w) in worst.iter().enumerate() {
        let (g, p, _) = &cases[w.1];
        println!(
            "  {:14} max err {:.3e}  (gpu {:e}, ref {:e}, roughness {}, anisotropy {}, n·l {:.3e}, n·v {:.3e})",
            LOBE_NAMES[k],
            w.0,
            w.3,
            w.4,
            p[0],
            p[1],
            r::dot(g.n, g.l),
            r::dot(g.n, g.v)
        );
    }
    if std::env::var("MATERIAL_DEBUG").is_ok() {
        for w in worst {
            let (g, p, f0) = &cases[w.1];
            println!("worst: {g:?} {p:?} {f0:?} {:?}", r::dirs(g.n, g.v, g.l));
        }
    }
}

#[test]
fn lobes_match_f64_reference() {
    let gpu = GpuContext::new_headless().expect("GPU (lavapipe) needed");
    let count = 1 << 16;
    let seed = std::env::var("MATERIAL_SEED").map_or(0x5eed_1234, |s| s.parse().unwrap());
    let mut rng = Rng(seed);
    let mut cases = Vec::with_capacity(count);
    for _ in 0..count {
        let g = geo(&mut rng, false);
        let rough = rng.roughness() as f32 as f64;
        let o = [-1.0, 0.0, 1.0, rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
        let an = rng.pick(&o) as f32 as f64;
        let o = [1.0, 1.5, rng.range(1.0, 3.0)];
        let ior = rng.pick(&o) as f32 as f64;
        let o = [0.0, rng.range(0.0, 2.0)];
        let sigma = rng.pick(&o) as f32 as f64;
        let mut f0 = [0.0; 3];
        for c in &mut f0 {
            let o = [0.0, 1.0, rng.f(), rng.f(), rng.range(0.0, 2.0)];
            *c = rng.pick(&o) as f32 as f64;
        }
        cases.push((g, [rough, an, ior, sigma], f0));
    }
    let (worst, nonfinite) = lobe_errors(&gpu, &cases);
    print_worst(&gpu, &cases, &worst);
    assert_eq!(nonfinite, 0, "NaN or Inf in lobe values");
    for (k, w) in worst.iter().enumerate() {
        assert!(w.0 <= TOL, "{}: error {:e} > {TOL:e}", LOBE_NAMES[k], w.0);
    }
}

/// The smoothest GGX (α = 0.002, D up to 8e4) at its specular peak, every sample within
/// 3e-3 rad of the mirror direction (the general test samples the peak rarely): within
/// 1e-4 of f64. D's denominator |n × h|² + (n·h)²α² is only ~4e-6 there, so |n × h|² must
/// come from a cross product, not from 1 − (n·h)² (which fails here). A plain cross
/// product there stays within 1e-4 too (7.1e-5 against 4.9e-5 split): the guard on it is
/// tested by `dirs_take_plain_products_only_where_they_are_accurate`.
#[test]
fn smoothest_ggx_peak_matches_f64_reference() {
    let gpu = GpuContext::new_headless().expect("GPU (lavapipe) needed");
    let mut rng = Rng(0x9ea4_0002);
    let mut cases = Vec::with_capacity(1 << 16);
    while cases.len() < 1 << 16 {
        let g = near_mirror_geo(&mut rng, 3e-3);
        let an = rng.pick(&[0.0, 0.5, -1.0]) as f32 as f64;
        cases.push((g, [0.0, an, 1.5, 0.0], [1.0, 0.5, 0.04]));
    }
    let (worst, nonfinite) = lobe_errors(&gpu, &cases);
    print_worst(&gpu, &cases, &worst);
    assert_eq!(nonfinite, 0, "NaN or Inf in lobe values");
    for k in [2, 3, 6] {
        let w = worst[k];
        assert!(w.0 <= TOL, "{}: error {:e} > {TOL:e}", LOBE_NAMES[k], w.0);
    }
}

const DIRS_HARNESS: &str = "
struct Sample {
    n: vec4<f32>,
    t: vec4<f32>,
    v: vec4<f32>,
    l: vec4<f32>,
};
@group(0) @binding(0) var<storage, read> samples: array<Sample>;
@group(0) @binding(1) var<storage, read_write> out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&samples)) {
        return;
    }
    let s = samples[i];
    let g = lg_dirs(s.n.xyz, s.v.xyz, s.l.xyz, LG_S2_GUARDED);
    let e = lg_dirs(s.n.xyz, s.v.xyz, s.l.xyz, LG_S2_EXACT);
    out[2u * i] = vec4<f32>(g.nl, g.nv, g.nh, g.s2);
    out[2u * i + 1u] = vec4<f32>(e.nl, e.nv, e.nh, e.s2);
}
";

/// (n·l, n·v, n·h, |n × h|²) in f64 from the f32 inputs and the half vector l + v as f32
/// addition rounds it (correctly, on every Vulkan device): what `lg_dirs`'s products
/// would give if they were exact. The rounding of l + v is the shader's too and is not
/// what is tested here (at the GGX peak it alone moves |n × h|² by ~2e-10).
fn products_of_f32_half_vector(g: &Geo) -> [f64; 4] {
    let hs: [f64; 3] = std::array::from_fn(|k| (g.l[k] as f32 + g.v[k] as f32) as f64);
    let big = hs.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let hs = if big > 1e-30 { hs } else { g.n };
    let len2 = r::dot(hs, hs);
    let c = r::cross(g.n, hs);
    [
        r::dot(g.n, g.l).clamp(r::COS_MIN, 1.0),
        r::dot(g.n, g.v).clamp(r::COS_MIN, 1.0),
        (r::dot(g.n, hs) / len2.sqrt()).clamp(0.0, 1.0),
        (r::dot(c, c) / len2).min(1.0),
    ]
}

/// `lg_dirs` takes plain f32 products only where they are accurate (LG_PLAIN_MIN,
/// LG_S2_GUARDED): over the general samples (grazing views and lights, peaks) and 16,384
/// more within 3e-3 rad of the mirror direction, n·l, n·v and n·h stay within 1e-5
/// relative of the exact products (below 1e-3 absolute against 1e-3: the lobes' metric),
/// and |n × h|² within 1e-5 of max(|n × h|², α²) at the smallest α (4e-6): the error GGX's
/// D sees in its denominator |n × h|² + (n·h)²α². 1e-5: the guarded plain products' bound
/// (5.8e-6) plus the rounding of the division by |h| or |h|²; the split products are
/// within ~1e-6 of it. A plain product at n·l = 1e-3 can be off by 1.8e-4 of it, a plain
/// cross product at |n × h|² = 4e-6 by 1e-4: either taken without its guard fails here.
#[test]
fn dirs_take_plain_products_only_where_they_are_accurate() {
    let gpu = GpuContext::new_headless().expect("GPU (lavapipe) needed");
    let mut rng = Rng(0xd125_0001);
    let mut geos: Vec<Geo> = (0..1 << 16).map(|_| geo(&mut rng, true)).collect();
    geos.extend((0..1 << 14).map(|_| near_mirror_geo(&mut rng, 3e-3)));
    let input: Vec<f32> = geos.iter().flat_map(geo_floats).collect();
    let wgsl = format!("{LOBE_LIBRARY}\n{DIRS_HARNESS}");
    let out = f32s(&run_compute(
        &gpu,
        &wgsl,
        &to_bytes(&input),
        (geos.len() * 2 * 16) as u64,
        geos.len() as u32,
    ));
    let alpha_min_sq = r::alpha(0.0) * r::alpha(0.0);
    let names = ["n·l", "n·v", "n·h", "|n×h|²"];
    // worst[path][field]: (error, sample)
    let mut worst = [[(0.0f64, 0usize); 4]; 2];
    for (i, g) in geos.iter().enumerate() {
        let want = products_of_f32_half_vector(g);
        for (path, w) in worst.iter_mut().enumerate() {
            let got = &out[(2 * i + path) * 4..(2 * i + path) * 4 + 4];
            for k in 0..4 {
                let floor = if k == 3 { alpha_min_sq } else { 1e-3 };
                let e = (got[k] as f64 - want[k]).abs() / want[k].abs().max(floor);
                assert!(
                    e.is_finite(),
                    "sample {i} {}: {} against {}",
                    names[k],
                    got[k],
                    want[k]
                );
                if e > w[k].0 {
                    w[k] = (e, i);
                }
            }
        }
    }
    for (path, w) in ["LG_S2_GUARDED", "LG_S2_EXACT"].iter().zip(&worst) {
        println!(
            "{path}: worst {}",
            names
                .iter()
                .zip(w)
                .map(|(n, (e, _))| format!("{n} {e:.2e}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    for (path, w) in worst.iter().enumerate() {
        for (k, (e, i)) in w.iter().enumerate() {
            assert!(
                *e <= 1e-5,
                "path {path} {}: error {e:e} at {:?}",
                names[k],
                geos[*i]
            );
        }
    }
}

/// The f32 lobes where the shading normal faces away from the eye (n·v < 0) and the light
/// is almost straight behind the point (`back_facing`): every GGX lobe within its physical
/// bound (see material_cpu.rs), no NaN or Inf. Without GGX's χ⁺(n·h) they reached 1e8 × it.
#[test]
fn ggx_lobes_stay_bounded_when_the_shading_normal_faces_away() {
    let gpu = GpuContext::new_headless().expect("GPU (lavapipe) needed");
    let count = 1 << 14;
    let mut rng = Rng(0xbac9);
    let mut input = Vec::with_capacity(count * 24);
    let mut cases = Vec::with_capacity(count);
    for i in 0..count {
        let g = back_facing(&mut rng);
        let rough = [0.0, 0.05, 0.3, 0.6, 0.7][i % 5];
        let an = [-0.6, 0.0, 0.6][i % 3];
        let p = [rough, an, 1.5, 0.0];
        for x in [g.n[0], g.n[1], g.n[2], 0.0]
            .iter()
            .chain(&g.t)
            .chain(&[g.v[0], g.v[1], g.v[2], 0.0])
            .chain(&[g.l[0], g.l[1], g.l[2], 0.0])
            .chain(&p)
            .chain(&[1.0, 1.0, 1.0, 0.0])
        {
            input.push(*x as f32);
        }
        cases.push((g, p));
    }
    let wgsl = format!("{LOBE_LIBRARY}\n{LOBE_HARNESS}");
    let out = f32s(&run_compute(
        &gpu,
        &wgsl,
        &to_bytes(&input),
        (count * 7 * 16) as u64,
        count as u32,
    ));
    // lobes 2 (ggx, F0 = 1), 3 (ggx_aniso, F0 = 1), 6 (GGX at the IOR's F0: clearcoat's)
    let mut worst = [(0.0f64, 0usize); 3];
    for (i, (g, p)) in cases.iter().enumerate() {
        let cos = r::dot(g.n, g.l).clamp(0.0, 1.0);
        let a = r::alpha(p[0]);
        let at = (a * (1.0 + p[1])).max(r::ALPHA_MIN);
        let ab = (a * (1.0 - p[1])).max(r::ALPHA_MIN);
        for (k, (lobe, bound)) in [
            (2, ggx_cos_bound(a, a)),
            (3, ggx_cos_bound(at, ab)),
            (6, ggx_cos_bound(a, a)),
        ]
        .into_iter()
        .enumerate()
        {
            for c in 0..3 {
                let v = out[(i * 7 + lobe) * 4 + c] as f64;
                assert!(v.is_finite(), "{}: {v} at {g:?} {p:?}", LOBE_NAMES[lobe]);
                let x = v * cos / bound;
                if x > worst[k].0 {
                    worst[k] = (x, i);
                }
            }
        }
    }
    println!(
        "n·v < 0, l ≈ −v ({}): max f·cos over its bound: ggx {:.3e}, ggx_aniso {:.3e}, clearcoat {:.3e}",
        gpu.adapter_name(),
        worst[0].0,
        worst[1].0,
        worst[2].0
    );
    for (k, (w, i)) in worst.iter().enumerate() {
        // 1% for the anisotropic bound's |v_t| ≥ 0.997 and f32 rounding
        assert!(
            *w <= 1.01,
            "{}: f·cos is {w:e} × its bound at {:?}",
            LOBE_NAMES[[2, 3, 6][k]],
            cases[*i]
        );
    }
}

const MATERIAL_HARNESS: &str = "
struct Sample {
    n: vec4<f32>,
    t: vec4<f32>,
    v: vec4<f32>,
    l: vec4<f32>,
};
@group(0) @binding(0) var<storage, read> samples: array<Sample>;
@group(0) @binding(1) var<storage, read_write> out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&samples)) {
        return;
    }
    let s = samples[i];
    var p: ShadingPoint;
    p.position = vec3<f32>(0.0);
    p.normal = s.n.xyz;
    p.tangent = s.t;
    p.uv = vec2<f32>(0.5);
    p.view = s.v.xyz;
    p.color = vec4<f32>(0.8, 0.5, 0.25, 0.6);
    let m = material_setup(p);
    out[i] = vec4<f32>(material_eval(m, s.l.xyz), material_alpha(m));
}
";

/// Max error of `material_eval` against `reference::eval_at` over `count` samples.
/// The vertex colour MATERIAL_HARNESS gives every sample (its WGSL literal).
const HARNESS_VERTEX_COLOR: [f32; 4] = [0.8, 0.5, 0.25, 0.6];

fn check_material(gpu: &GpuContext, m: &Material, count: usize, seed: u64) -> f64 {
    let code = m
        .wgsl_with(&WgslOptions {
            sample_level_zero: true,
            ..Default::default()
        })
        .expect("valid WGSL");
    let wgsl = format!("{SHADING_POINT_WGSL}\n{code}\n{MATERIAL_HARNESS}");
    let mut rng = Rng(seed);
    let geos: Vec<Geo> = (0..count).map(|_| geo(&mut rng, true)).collect();
    let mut input = Vec::with_capacity(count * 16);
    for g in &geos {
        input.extend(geo_floats(g));
    }
    let out = f32s(&run_compute(
        gpu,
        &wgsl,
        &to_bytes(&input),
        (count * 16) as u64,
        count as u32,
    ));
    let mut worst = 0.0f64;
    for (i, g) in geos.iter().enumerate() {
        let surf = r::Surface {
            n: g.n,
            tangent: g.t,
            texels: Default::default(),
            vertex_color: Some(HARNESS_VERTEX_COLOR.map(f64::from)),
        };
        let rv = r::eval_at(m, &surf, g.v, g.l);
        for c in 0..3 {
            let gv = out[i * 4 + c];
            assert!(
                gv.is_finite() && rv[c].is_finite(),
                "{}: non-finite value (gpu {gv}, ref {}) at {g:?}",
                m.name(),
                rv[c]
            );
            let e = err(gv, rv[c]);
            if e > worst {
                worst = e;
            }
            assert!(
                e <= TOL,
                "{}: error {e:e} (gpu {gv:e}, ref {:e}) at {g:?}",
                m.name(),
                rv[c]
            );
        }
    }
    worst
}

#[test]
fn shipped_materials_match_f64_reference() {
    let gpu = GpuContext::new_headless().expect("GPU (lavapipe) needed");
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("materials");
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    names.sort();
    assert!(names.len() >= 5);
    let mut textured = Vec::new();
    for (k, path) in names.iter().enumerate() {
        let m = Material::load(path).unwrap();
        if !m.texture_slots().is_empty() {
            textured.push(m.name().to_string());
            continue;
        }
        let worst = check_material(&gpu, &m, 8192, 77 + k as u64);
        println!("  {:24} max err {worst:.3e} (8192 samples)", m.name());
    }
    // This harness binds no textures; none of the shipped materials has any today. One
    // that does needs a check like textured_gltf_matches_f64_reference, not a silent skip.
    assert!(
        textured.is_empty(),
        "shipped textured materials left unchecked: {textured:?}"
    );
}

/// Random layered materials: 1–3 layers of 1–3 random lobes with random parameters
/// (roughness 0 and 1 included), interfaces with IOR, weight, transmission, absorption.
fn random_material(rng: &mut Rng, k: usize) -> String {
    let mut layers = Vec::new();
    let nl = 1 + rng.next_u64() % 3;
    let num = |rng: &mut Rng, a: f64, b: f64| format!("{:.4}", rng.range(a, b));
    for li in 0..nl {
        let mut lobes = Vec::new();
        for _ in 0..1 + rng.next_u64() % 3 {
            let w = num(rng, 0.1, 1.0);
            let rough = format!("{}", rng.roughness() as f32);
            let col = format!(
                "({}, {}, {})",
                num(rng, 0.0, 1.0),
                num(rng, 0.0, 1.0),
                num(rng, 0.0, 1.0)
            );
            let lobe = match rng.next_u64() % 6 {
                0 => format!("Lambert(weight: {w}, color: {col})"),
                1 => format!("OrenNayar(weight: {w}, color: {col}, roughness: {rough})"),
                2 => format!("Ggx(weight: {w}, roughness: {rough}, f0: Some({col}))"),
                3 => format!(
                    "AnisoGgx(weight: {w}, roughness: {rough}, anisotropy: {}, ior: Some({}))",
                    num(rng, -1.0, 1.0),
                    num(rng, 1.0, 2.5)
                ),
                4 => format!("Clearcoat(weight: {w}, roughness: {rough})"),
                _ => format!("Sheen(weight: {w}, color: {col}, roughness: {rough})"),
            };
            lobes.push(lobe);
        }
        let a = num(rng, 0.0, 3.0);
        layers.push(format!(
            "(name: \"l{li}\", ior: Some({}), coupling: {}, weight: {}, transmission: {}, thickness: {}, absorption: ({a}, 0.5, 0.0), lobes: [{}])",
            num(rng, 1.0, 2.0),
            rng.pick(&["Interface", "HalfVector"]),
            num(rng, 0.0, 1.0),
            num(rng, 0.5, 1.0),
            num(rng, 0.0, 1.0),
            lobes.join(", ")
        ));
    }
    format!(
        "(name: \"random{k}\", layers: [\n{}\n])",
        layers.join(",\n")
    )
}

#[test]
fn random_layered_materials_match_f64_reference() {
    let gpu = GpuContext::new_headless().expect("GPU (lavapipe) needed");
    let mut rng = Rng(0x00a1_1ce0);
    let mut worst = 0.0f64;
    let n = 24;
    for k in 0..n {
        let src = random_material(&mut rng, k);
        let m = Material::parse(&src, "random.ron").unwrap_or_else(|e| panic!("{e}\n{src}"));
        worst = worst.max(check_material(&gpu, &m, 1024, 1000 + k as u64));
    }
    println!("  {n} random layered materials × 1024 samples: max err {worst:.3e}");
}

/// `Vertex`, `VertexAlpha` and a colour product read the shading point's vertex colour
/// (the harness's HARNESS_VERTEX_COLOR) as the f64 reference reads `Surface::vertex_color`:
/// in a Lambert colour, a GGX F0 mix, emission and alpha.
#[test]
fn vertex_colour_expressions_match_f64_reference() {
    let gpu = GpuContext::new_headless().expect("GPU (lavapipe) needed");
    let m = Material::parse(
        "(
        name: \"painted\",
        alpha: Mul(0.9, VertexAlpha),
        emissive: Some(Scale(Vertex, 0.25)),
        layers: [
            (ior: Some(1.5), lobes: [Ggx(weight: 1, roughness: 0.4, f0: Some(Mix(a: (0.04, 0.04, 0.04), b: Vertex, t: OneMinus(VertexAlpha))))]),
            (lobes: [Lambert(weight: 1, color: Mul((0.9, 0.7, 0.3), Vertex))]),
        ],
    )",
        "painted.ron",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(m.desc().reads_vertex_color());
    let worst = check_material(&gpu, &m, 4096, 99);
    println!("  vertex colour expressions: max err {worst:.3e}");
}

#[test]
fn artist_values_stay_finite_on_the_gpu() {
    let gpu = GpuContext::new_headless().expect("GPU (lavapipe) needed");
    let m = Material::parse(
        "(
        name: \"pushed\",
        layers: [
            (ior: Some(0.5), weight: 80, transmission: 3, thickness: 1e30, absorption: (-1, 0, 1e30), lobes: [
                Ggx(weight: 2.5, roughness: -0.5, f0: Some((4, 1.5, 1e30))),
                Sheen(weight: 1e9, color: (2, 2, 2), roughness: 7),
            ]),
            (ior: Some(3), coupling: HalfVector, weight: 5, lobes: [Clearcoat(weight: 40, roughness: 0)]),
            (lobes: [AnisoGgx(weight: 3, roughness: 2, anisotropy: 5, ior: Some(1e9)), Lambert(weight: 2, color: (5, -1, 2))]),
        ],
    )",
        "pushed.ron",
    )
    .unwrap();
    assert!(!m.warnings().is_empty());
    let worst = check_material(&gpu, &m, 16384, 4242);
    println!("  pushed past physical ranges: max err {worst:.3e}, all finite");
}

const TEXTURED_HARNESS: &str = "
struct Sample {
    n: vec4<f32>,
    t: vec4<f32>,
    v: vec4<f32>,
    l: vec4<f32>,
};
@group(0) @binding(0) var<storage, read> samples: array<Sample>;
@group(0) @binding(1) var<storage, read_write> out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&samples)) {
        return;
    }
    let s = samples[i];
    var p: ShadingPoint;
    p.position = vec3<f32>(0.0);
    p.normal = s.n.xyz;
    p.tangent = s.t;
    p.uv = vec2<f32>(0.5);
    p.view = s.v.xyz;
    let m = material_setup(p);
    out[4u * i] = vec4<f32>(material_eval(m, s.l.xyz), material_alpha(m));
    out[4u * i + 1u] = vec4<f32>(m.n, material_occlusion(m));
    out[4u * i + 2u] = vec4<f32>(m.t, 0.0);
    out[4u * i + 3u] = vec4<f32>(m.c0_0, m.r0_0);
}
";

fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A textured glTF material (base colour sRGB, metallic-roughness in B/G, normal map with
/// scale, occlusion): material_setup samples the textures and perturbs the normal on the
/// GPU; the f64 reference evaluates at the GPU's shading frame with the decoded texels.
#[test]
fn textured_gltf_matches_f64_reference() {
    use lightgraph::scene::{SurfaceMaterial, TextureImage};
    use std::sync::Arc;
    let gpu = GpuContext::new_headless().expect("GPU (lavapipe) needed");
    let img = |name: &str, rgba: [u8; 4], srgb: bool| {
        Some(Arc::new(TextureImage {
            name: name.into(),
            width: 1,
            height: 1,
            rgba8: rgba.to_vec(),
            srgb,
        }))
    };
    let s = SurfaceMaterial {
        name: "textured_gltf".into(),
        base_color: glam::Vec4::new(0.9, 0.8, 1.0, 0.75),
        metallic: 0.8,
        roughness: 0.9,
        // Linear here: lavapipe's sRGB decode deviates from the exact sRGB curve by up to
        // 0.2 % (byte 200: 0.5766 against 0.5776), which is the texture unit's business,
        // not the material's. The sRGB flag itself is checked in material_parse.
        base_color_texture: img("base", [200, 90, 40, 170], false),
        metallic_roughness_texture: img("mr", [0, 120, 150, 255], false),
        normal_texture: img("normal", [160, 100, 230, 255], false),
        normal_scale: 0.7,
        occlusion_texture: img("occlusion", [100, 0, 0, 255], false),
        occlusion_strength: 0.5,
        ..Default::default()
    };
    let m = Material::from_surface(&s);
    let images: Vec<TextureImage> = m
        .texture_slots()
        .iter()
        .map(|slot| (*slot.source.load().unwrap()).clone())
        .collect();
    let mut texels = std::collections::BTreeMap::new();
    for (slot, im) in m.texture_slots().iter().zip(&images) {
        let t: [f64; 4] = std::array::from_fn(|c| {
            let x = im.rgba8[c] as f64 / 255.0;
            if im.srgb && c < 3 {
                srgb_to_linear(x)
            } else {
                x
            }
        });
        texels.insert(slot.name.clone(), t);
    }
    let code = m
        .wgsl_with(&WgslOptions {
            sample_level_zero: true,
            ..Default::default()
        })
        .unwrap();
    let wgsl = format!("{SHADING_POINT_WGSL}\n{code}\n{TEXTURED_HARNESS}");
    let count = 16384;
    let mut rng = Rng(2024);
    let geos: Vec<Geo> = (0..count).map(|_| geo(&mut rng, true)).collect();
    let mut input = Vec::new();
    for g in &geos {
        input.extend(geo_floats(g));
    }
    let out = f32s(&run_compute_with_textures(
        &gpu,
        &wgsl,
        &to_bytes(&input),
        (count * 64) as u64,
        count as u32,
        &images,
    ));
    let (mut worst, mut worst_n, mut worst_t) = (0.0f64, 0.0f64, 0.0f64);
    for (i, g) in geos.iter().enumerate() {
        let o = &out[i * 16..i * 16 + 16];
        let n_gpu = [o[4] as f64, o[5] as f64, o[6] as f64];
        let t_gpu = [o[8] as f64, o[9] as f64, o[10] as f64];
        // The perturbed normal against f64 (glTF: n' = normalize(T x s + B y s + N z)).
        let t0 = r::tangent(g.n, g.t);
        let b0 = r::bitangent(g.n, t0, g.t[3]);
        let nt = texels["normal"];
        let k = [
            (nt[0] * 2.0 - 1.0) * 0.7,
            (nt[1] * 2.0 - 1.0) * 0.7,
            nt[2] * 2.0 - 1.0,
        ];
        let np = r::normalize(r::add(
            r::add(r::scale(t0, k[0]), r::scale(b0, k[1])),
            r::scale(g.n, k[2]),
        ));
        // The tangent, Gram-Schmidt against the perturbed normal (the BRDF below is
        // evaluated in the GPU's frame, so a wrong one would go unseen there).
        let tp = r::tangent(np, [t0[0], t0[1], t0[2], 1.0]);
        for c in 0..3 {
            worst_n = worst_n.max((n_gpu[c] - np[c]).abs());
            worst_t = worst_t.max((t_gpu[c] - tp[c]).abs());
        }
        // The BRDF at the GPU's frame and the decoded texels.
        let at = r::Surface {
            n: n_gpu,
            tangent: [t_gpu[0], t_gpu[1], t_gpu[2], g.t[3]],
            texels: texels.clone(),
            vertex_color: None,
        };
        let rv = r::eval_at(&m, &at, g.v, g.l);
        for c in 0..3 {
            assert!(o[c].is_finite(), "non-finite at {g:?}");
            let e = err(o[c], rv[c]);
            worst = worst.max(e);
            assert!(
                e <= TOL,
                "error {e:e} (gpu {}, ref {:e}) at {g:?}",
                o[c],
                rv[c]
            );
        }
        let alpha = texels["base_color"][3] * 0.75;
        assert!(
            (o[3] as f64 - alpha).abs() < 1e-6,
            "alpha {} vs {alpha}",
            o[3]
        );
        let occ = 1.0 + 0.5 * (texels["occlusion"][0] - 1.0);
        assert!(
            (o[7] as f64 - occ).abs() < 1e-6,
            "occlusion {} vs {occ}",
            o[7]
        );
    }
    println!("  textured glTF (normal map): max err {worst:.3e}, perturbed normal max abs err {worst_n:.1e}, tangent {worst_t:.1e}");
    assert!(worst_n < 1e-6, "perturbed normal off by {worst_n:e}");
    assert!(worst_t < 1e-6, "tangent off by {worst_t:e}");
}

const PRODUCT_HARNESS: &str = "
struct Pair {
    a: vec4<f32>,
    b: vec4<f32>,
};
@group(0) @binding(0) var<storage, read> pairs: array<Pair>;
@group(0) @binding(1) var<storage, read_write> out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&pairs)) {
        return;
    }
    let a = pairs[i].a.xyz;
    let b = pairs[i].b.xyz;
    let s = lg_split(a);
    let o = i * 4u;
    out[o] = vec4<f32>(s.hi, 0.0);
    out[o + 1u] = vec4<f32>(s.lo, 0.0);
    out[o + 2u] = vec4<f32>(vec3<f32>(s.steps), lg_dot(a, b));
    out[o + 3u] = vec4<f32>(lg_cross(a, b), 0.0);
}
";

/// The accurate products' parts on the GPU: `lg_split` gives hi on the 2^-11 grid with
/// hi · 2048 its steps, |lo| under one step and hi + lo equal to the input exactly, for
/// random unit vectors and for components at and around grid points and half steps (where
/// rounding ties and lo is largest), ±1, 0 and tiny values; `lg_dot` and `lg_cross` come within their result's rounding (half an
/// ulp of the f32 result, 2^-24 relative) plus 4e-10 of the f64 products: the rounded
/// terms are two small dot products (hi·lo and lo·b) of at most √3·2^-11 each, rounded
/// three times at 2^-24 relative (≤ 1.6e-10 each), then summed. Also for nearly parallel
/// and nearly perpendicular pairs, where plain f32 products leave ~6e-8 absolute.
#[test]
fn accurate_products_split_exactly_and_match_f64() {
    let gpu = GpuContext::new_headless().expect("GPU (lavapipe) needed");
    let mut rng = Rng(0x0dd_5eed);
    let grid = 1.0f64 / 2048.0;
    let edges: Vec<f64> = [
        0.0,
        1.0,
        0.5,
        grid,
        grid / 2.0,
        grid / 2.0 + 1e-9,
        grid / 2.0 - 1e-9,
        1.5 * grid,
        1e-30,
        1e-8,
        1.0 - 1e-7,
        0.999_999_94,
    ]
    .iter()
    .flat_map(|&x| [x, -x])
    .collect();
    let mut pairs: Vec<([f64; 3], [f64; 3])> = Vec::new();
    for _ in 0..20_000 {
        let a = f32v(rng.unit());
        let b = f32v(match rng.pick(&[0, 1, 2]) {
            0 => rng.unit(),
            // Nearly parallel and nearly perpendicular to a: cancellation in the cross
            // product and in the dot product.
            1 => norm([a[0] + 1e-4 * rng.f(), a[1] - 1e-4 * rng.f(), a[2]]),
            _ => norm(r::cross(a, [a[1] + 1e-3 * rng.f(), a[2], a[0]])),
        });
        pairs.push((a, b));
    }
    for &x in &edges {
        for &y in &edges {
            let a = [x, y, rng.pick(&edges)];
            pairs.push((f32v(a), f32v(rng.unit())));
        }
    }
    let mut input = Vec::with_capacity(pairs.len() * 8);
    for (a, b) in &pairs {
        input.extend([a[0], a[1], a[2], 0.0, b[0], b[1], b[2], 0.0].map(|x| x as f32));
    }
    let wgsl = format!("{LOBE_LIBRARY}\n{PRODUCT_HARNESS}");
    let out = f32s(&run_compute(
        &gpu,
        &wgsl,
        &to_bytes(&input),
        (pairs.len() * 4 * 16) as u64,
        pairs.len() as u32,
    ));
    let bound = |exact: f64| exact.abs() * 2f64.powi(-24) + 4e-10;
    let (mut worst_dot, mut worst_cross) = (0.0f64, 0.0f64);
    for (i, (a, b)) in pairs.iter().enumerate() {
        let row = |k: usize| &out[(i * 4 + k) * 4..(i * 4 + k) * 4 + 4];
        // Rows: hi, lo, the steps with lg_dot in w, lg_cross.
        let (hi, lo, steps, cross) = (row(0), row(1), row(2), row(3));
        let gpu_dot = steps[3] as f64;
        for c in 0..3 {
            let (h, l, s) = (hi[c] as f64, lo[c] as f64, steps[c] as f64);
            assert_eq!(
                h + l,
                a[c],
                "pair {i} component {c}: hi {h:e} + lo {l:e} != {:e}",
                a[c]
            );
            assert_eq!(
                h * 2048.0,
                s,
                "pair {i} component {c}: hi {h:e} is not steps {s} / 2048"
            );
            assert!(
                l.abs() < grid,
                "pair {i} component {c}: |lo| {l:e} past the grid's step"
            );
        }
        let dot = r::dot(*a, *b);
        let e = (gpu_dot - dot).abs();
        assert!(
            e <= bound(dot),
            "pair {i} {a:?}·{b:?}: {gpu_dot:e} against {dot:e}"
        );
        worst_dot = worst_dot.max(e - dot.abs() * 2f64.powi(-24));
        let exact = r::cross(*a, *b);
        for c in 0..3 {
            let e = (cross[c] as f64 - exact[c]).abs();
            assert!(
                e <= bound(exact[c]),
                "pair {i} {a:?}×{b:?} component {c}: {} against {:e}",
                cross[c],
                exact[c]
            );
            worst_cross = worst_cross.max(e - exact[c].abs() * 2f64.powi(-24));
        }
    }
    println!(
        "{} pairs: worst error past the result's rounding: dot {worst_dot:.2e}, cross {worst_cross:.2e}",
        pairs.len()
    );
}
