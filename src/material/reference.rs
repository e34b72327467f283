//! The f64 CPU reference: every lobe of `shaders/material/lobes.wgsl` and the layering of
//! the generated `material_eval`, formula for formula, in double precision. Tests compare
//! the GPU against this, integrate it over the hemisphere (white furnace) and check its
//! reciprocity.
//!
//! Layering: with layers `0..n` top first, lobe sums `S_i` and pass-through factors `T_i`,
//! `f = S_0 + T_0 (S_1 + T_1 (S_2 + ...))`, where
//! `T_i = transmission · max(1 − weight · F_schlick(F0(ior), v·h), 0) · exp(−σ d (1/cos θl' + 1/cos θv'))`
//! (θ' the angles refracted into the layer; no Fresnel when the layer has no IOR or IOR 1).
//! Lower layers are evaluated with the unrefracted l and v (as glTF's clearcoat does).

use super::model::{Color, ColorExpr, Lobe, Scalar, ScalarExpr};
use super::Material;
use std::collections::BTreeMap;

/// A 3-vector in f64, the reference's vector type.
pub type V3 = [f64; 3];

/// The constants of the lobe library, at the f32 values the GPU uses.
pub const ALPHA_MIN: f64 = 0.002f32 as f64;
/// Smallest sheen α (perceptual roughness 0.1), as `lg_sheen` clamps it.
pub const SHEEN_ALPHA_MIN: f64 = 0.01f32 as f64;
/// Smallest cosine a lobe sees (`nl`, `nv`, refracted cosines are clamped up to it).
pub const COS_MIN: f64 = 1e-4f32 as f64;
const INV_PI: f64 = std::f64::consts::FRAC_1_PI;
const PI: f64 = std::f64::consts::PI;

/// Dot product.
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
/// Cross product.
pub fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
/// Component-wise sum.
pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
/// `a` scaled by `s`.
pub fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
/// Component-wise product.
pub fn mul(a: V3, b: V3) -> V3 {
    [a[0] * b[0], a[1] * b[1], a[2] * b[2]]
}
/// `a` scaled to unit length.
pub fn normalize(a: V3) -> V3 {
    scale(a, 1.0 / dot(a, a).sqrt())
}
fn splat(x: f64) -> V3 {
    [x; 3]
}
fn max0(a: V3) -> V3 {
    [a[0].max(0.0), a[1].max(0.0), a[2].max(0.0)]
}

/// What the lobes need about (n, v, l); see `LgDirs` in the WGSL.
#[derive(Clone, Copy, Debug)]
pub struct Dirs {
    pub(crate) h: V3,
    /// n·l clamped to [`COS_MIN`] ..= 1.
    pub nl: f64,
    /// n·v clamped to [`COS_MIN`] ..= 1.
    pub nv: f64,
    /// n·h clamped to [0, 1].
    pub nh: f64,
    /// v·h computed as |l + v| / 2 (symmetric in l and v), in [0, 1].
    pub vh: f64,
    /// |n × h|², the squared sine of the half-vector angle, from the cross product (no 1 −
    /// (n·h)² cancellation).
    pub s2: f64,
    pub(crate) lv: f64,
}

/// The [`Dirs`] of unit normal `n`, view `v` and light `l` (`lg_dirs` in the WGSL).
pub fn dirs(n: V3, v: V3, l: V3) -> Dirs {
    let hs = add(l, v);
    let big = hs[0].abs().max(hs[1].abs()).max(hs[2].abs());
    let hs = if big > 1e-30 { hs } else { n };
    let len2 = dot(hs, hs);
    let len = len2.sqrt();
    let h = scale(hs, 1.0 / len);
    let c = cross(n, hs);
    Dirs {
        h,
        nl: dot(n, l).clamp(COS_MIN, 1.0),
        nv: dot(n, v).clamp(COS_MIN, 1.0),
        nh: (dot(n, hs) / len).clamp(0.0, 1.0),
        // v·h = l·h = |l + v| / 2 for unit vectors: symmetric in l and v.
        vh: (0.5 * dot(add(l, v), add(l, v)).sqrt()).clamp(0.0, 1.0),
        s2: (dot(c, c) / len2).min(1.0),
        lv: dot(l, v).clamp(-1.0, 1.0),
    }
}

/// GGX α from perceptual roughness, clamped to `[ALPHA_MIN, 1]`.
pub fn alpha(roughness: f64) -> f64 {
    let r = roughness.clamp(0.0, 1.0);
    (r * r).max(ALPHA_MIN)
}

/// Schlick F0 of a dielectric of index `ior` (against air): ((ior − 1) / (ior + 1))².
pub fn ior_f0(ior: f64) -> f64 {
    let r = (ior - 1.0) / (ior + 1.0);
    r * r
}

/// Schlick Fresnel at cosine `vh`, per channel.
pub fn schlick(f0: V3, vh: f64) -> V3 {
    let m5 = (1.0 - vh).powi(5);
    [
        f0[0] + (1.0 - f0[0]) * m5,
        f0[1] + (1.0 - f0[1]) * m5,
        f0[2] + (1.0 - f0[2]) * m5,
    ]
}

/// GGX D with its χ⁺(n·h): zero for a half vector below the horizon (`nh` is n·h clamped
/// to [0, 1]); see `lg_d_ggx`.
pub fn d_ggx(nh: f64, s2: f64, a: f64) -> f64 {
    if nh <= 0.0 {
        return 0.0;
    }
    let x = s2 + nh * nh * a * a;
    let r = a / x;
    r * r * INV_PI
}

/// Height-correlated Smith visibility V = G / (4 n·l n·v) for GGX α `a`.
pub fn v_smith(nl: f64, nv: f64, a: f64) -> f64 {
    let a2 = a * a;
    let gv = nl * (nv * nv * (1.0 - a2) + a2).sqrt();
    let gl = nv * (nl * nl * (1.0 - a2) + a2).sqrt();
    0.5 / (gv + gl)
}

/// The Lambert lobe, ρ/π.
pub fn lambert(color: V3) -> V3 {
    scale(color, INV_PI)
}

/// The isotropic GGX lobe (D · V · F) for reflectance `f0` and α `a`.
pub fn ggx(f0: V3, a: f64, d: &Dirs) -> V3 {
    scale(
        schlick(f0, d.vh),
        d_ggx(d.nh, d.s2, a) * v_smith(d.nl, d.nv, a),
    )
}

/// The anisotropic GGX lobe along tangent `t` and bitangent `b` (αt = α(1 + a), αb = α(1 − a)).
#[allow(clippy::too_many_arguments)]
pub fn ggx_aniso(f0: V3, a: f64, anisotropy: f64, t: V3, b: V3, v: V3, l: V3, d: &Dirs) -> V3 {
    let an = anisotropy.clamp(-1.0, 1.0);
    let at = (a * (1.0 + an)).max(ALPHA_MIN);
    let ab = (a * (1.0 - an)).max(ALPHA_MIN);
    let a2 = at * ab;
    // χ⁺(n·h), as in d_ggx
    if d.nh <= 0.0 {
        return [0.0; 3];
    }
    let w = [ab * dot(t, d.h), at * dot(b, d.h), a2 * d.nh];
    let w2 = a2 / dot(w, w);
    let dist = a2 * w2 * w2 * INV_PI;
    let len = |x: V3| dot(x, x).sqrt();
    let lam_v = d.nl * len([at * dot(t, v), ab * dot(b, v), d.nv]);
    let lam_l = d.nv * len([at * dot(t, l), ab * dot(b, l), d.nl]);
    let vis = 0.5 / (lam_v + lam_l);
    scale(schlick(f0, d.vh), dist * vis)
}

fn sheen_l(x: f64, a: f64) -> f64 {
    let t = (1.0 - a) * (1.0 - a);
    let mix = |p: f32, q: f32| p as f64 * (1.0 - t) + q as f64 * t;
    let p0 = mix(21.5473, 25.3245);
    let p1 = mix(3.82987, 3.32435);
    let p2 = mix(0.19823, 0.16801);
    let p3 = mix(-1.97760, -1.27393);
    let p4 = mix(-4.32054, -4.85967);
    p0 / (1.0 + p1 * x.powf(p2)) + p3 * x + p4
}

/// Estevez & Kulla's fitted Smith Λ for the Charlie distribution.
pub fn sheen_lambda(c: f64, a: f64) -> f64 {
    let l = if c < 0.5 {
        sheen_l(c, a)
    } else {
        2.0 * sheen_l(0.5, a) - sheen_l(1.0 - c, a)
    };
    let m = 1.0 - c;
    let m2 = m * m;
    let m8 = m2 * m2 * m2 * m2;
    (l * (1.0 + 2.0 * m8)).exp()
}

/// The Charlie sheen lobe (Estevez & Kulla D and fitted visibility) for perceptual `roughness`.
pub fn sheen(color: V3, roughness: f64, d: &Dirs) -> V3 {
    let r = roughness.clamp(0.0, 1.0);
    let a = (r * r).max(SHEEN_ALPHA_MIN);
    let inv = 1.0 / a;
    let dist = if d.s2 > 0.0 {
        (2.0 + inv) * d.s2.powf(0.5 * inv) * (0.5 * INV_PI)
    } else {
        0.0
    };
    let vis = 1.0 / ((1.0 + sheen_lambda(d.nv, a) + sheen_lambda(d.nl, a)) * (4.0 * d.nv * d.nl));
    scale(color, dist * vis)
}

/// Fujii's improved Oren–Nayar lobe; `roughness` is σ in [0, 1].
pub fn oren_nayar(color: V3, roughness: f64, d: &Dirs) -> V3 {
    let sigma = roughness.clamp(0.0, 1.0);
    let s = d.lv - d.nl * d.nv;
    let t = if s > 0.0 { d.nl.max(d.nv) } else { 1.0 };
    let a = 1.0 / (1.0 + (0.5 - 2.0 / (3.0 * PI)) * sigma);
    let b = sigma * a;
    scale(color, INV_PI * (a + b * s / t))
}

fn cos_inside(c: f64, ior: f64) -> f64 {
    (((ior - 1.0) * (ior + 1.0) + c * c).sqrt() / ior).max(COS_MIN)
}

fn one_minus_wf(f0: f64, w: f64, c: f64) -> f64 {
    let f = f0 + (1.0 - f0) * (1.0 - c).powi(5);
    (1.0 - w * f).max(0.0)
}

/// What a layer lets through (see `lg_through`): `coupling` 0 = `Interface`
/// (1 − wF(n·l))(1 − wF(n·v)), 1 = `HalfVector` (1 − wF(v·h)), glTF's fresnel_mix.
pub fn through(
    ior: f64,
    weight: f64,
    transmission: f64,
    sigma_d: V3,
    coupling: u32,
    d: &Dirs,
) -> V3 {
    let pass = if ior > 1.0 {
        let f0 = ior_f0(ior);
        transmission
            * if coupling == 1 {
                one_minus_wf(f0, weight, d.vh)
            } else {
                one_minus_wf(f0, weight, d.nl) * one_minus_wf(f0, weight, d.nv)
            }
    } else {
        transmission
    };
    let path = 1.0 / cos_inside(d.nl, ior) + 1.0 / cos_inside(d.nv, ior);
    [
        pass * (-sigma_d[0] * path).exp(),
        pass * (-sigma_d[1] * path).exp(),
        pass * (-sigma_d[2] * path).exp(),
    ]
}

/// `lg_tangent`: the tangent made orthogonal to n, or a basis from n alone.
pub fn tangent(n: V3, tangent: [f64; 4]) -> V3 {
    let t3 = [tangent[0], tangent[1], tangent[2]];
    let tt = add(t3, scale(n, -dot(n, t3)));
    let l2 = dot(tt, tt);
    if l2 > 1e-8 {
        return scale(tt, 1.0 / l2.sqrt());
    }
    let s = if n[2] >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (s + n[2]);
    let b = n[0] * n[1] * a;
    [1.0 + s * n[0] * n[0] * a, s * b, -s * n[0]]
}

/// `lg_bitangent`: n × t, flipped when the tangent's handedness `w` is negative.
pub fn bitangent(n: V3, t: V3, w: f64) -> V3 {
    scale(cross(n, t), if w < 0.0 { -1.0 } else { 1.0 })
}

/// Where a material is evaluated: the shading normal (no normal map is applied here: give
/// the perturbed normal directly), the mesh tangent (xyz + handedness; zero for none) and
/// texel values by texture name (a texture not listed reads as (1, 1, 1, 1)).
#[derive(Clone, Debug, Default)]
pub struct Surface {
    /// Shading normal, unit length.
    pub n: V3,
    /// Mesh tangent: xyz and handedness w (all zero for none).
    pub tangent: [f64; 4],
    /// Texel values (RGBA, linear) by texture name; a missing name reads (1, 1, 1, 1).
    pub texels: BTreeMap<String, [f64; 4]>,
    /// The interpolated vertex colour (RGBA, linear); `None` reads (1, 1, 1, 1), as a
    /// mesh without vertex colours does.
    pub vertex_color: Option<[f64; 4]>,
}

impl Surface {
    /// A surface with normal `n`, no tangent and every texture reading (1, 1, 1, 1).
    pub fn new(n: V3) -> Self {
        Self {
            n,
            ..Default::default()
        }
    }
    fn texel(&self, name: &str) -> [f64; 4] {
        self.texels.get(name).copied().unwrap_or([1.0; 4])
    }
}

/// Evaluates a scalar parameter at a surface (texture expressions read `at.texels`).
pub fn scalar(s: &Scalar, at: &Surface) -> f64 {
    match s {
        Scalar::Val(x) => *x as f64,
        Scalar::Expr(ScalarExpr::Tex {
            texture,
            channel,
            scale,
        }) => at.texel(texture)[channel.index()] * *scale as f64,
        Scalar::Expr(ScalarExpr::OneMinus(a)) => 1.0 - scalar(a, at),
        Scalar::Expr(ScalarExpr::Mul(a, b)) => scalar(a, at) * scalar(b, at),
        Scalar::Expr(ScalarExpr::VertexAlpha) => at.vertex_color.map_or(1.0, |c| c[3]),
    }
}

/// Evaluates a colour parameter at a surface, linear RGB.
pub fn color(c: &Color, at: &Surface) -> V3 {
    match c {
        Color::Rgb(r, g, b) => [*r as f64, *g as f64, *b as f64],
        Color::Expr(ColorExpr::Tex { texture, scale: s }) => {
            let t = at.texel(texture);
            [t[0] * s.0 as f64, t[1] * s.1 as f64, t[2] * s.2 as f64]
        }
        Color::Expr(ColorExpr::Mix { a, b, t }) => {
            let (a, b, t) = (color(a, at), color(b, at), scalar(t, at));
            add(scale(a, 1.0 - t), scale(b, t))
        }
        Color::Expr(ColorExpr::Scale(c, s)) => scale(color(c, at), scalar(s, at)),
        Color::Expr(ColorExpr::Mul(a, b)) => mul(color(a, at), color(b, at)),
        Color::Expr(ColorExpr::Vertex) => at.vertex_color.map_or([1.0; 3], |c| [c[0], c[1], c[2]]),
    }
}

/// F0 of a GGX lobe: the colour `f0` if given, else from `ior` (default 1.5).
pub fn lobe_f0(f0: &Option<Color>, ior: Option<f32>, at: &Surface) -> V3 {
    match f0 {
        Some(c) => max0(color(c, at)),
        None => splat(ior_f0(ior.unwrap_or(1.5) as f64)),
    }
}

/// One lobe, weighted, without the cosine.
pub fn lobe(lobe: &Lobe, at: &Surface, v: V3, l: V3, d: &Dirs) -> V3 {
    let (t, b) = {
        let t = tangent(at.n, at.tangent);
        (t, bitangent(at.n, t, at.tangent[3]))
    };
    let w = lobe.weight() as f64;
    let f = match lobe {
        Lobe::Lambert { color: c, .. } => lambert(max0(color(c, at))),
        Lobe::OrenNayar {
            color: c,
            roughness,
            ..
        } => oren_nayar(max0(color(c, at)), scalar(roughness, at), d),
        Lobe::Ggx {
            roughness, f0, ior, ..
        } => ggx(lobe_f0(f0, *ior, at), alpha(scalar(roughness, at)), d),
        Lobe::AnisoGgx {
            roughness,
            anisotropy,
            f0,
            ior,
            ..
        } => ggx_aniso(
            lobe_f0(f0, *ior, at),
            alpha(scalar(roughness, at)),
            scalar(anisotropy, at),
            t,
            b,
            v,
            l,
            d,
        ),
        Lobe::Clearcoat { roughness, ior, .. } => ggx(
            splat(ior_f0(ior.unwrap_or(1.5) as f64)),
            alpha(scalar(roughness, at)),
            d,
        ),
        Lobe::Sheen {
            color: c,
            roughness,
            ..
        } => sheen(max0(color(c, at)), scalar(roughness, at), d),
    };
    scale(f, w)
}

/// The layered BRDF f(l, v) (no cosine); 0 when l is below the surface.
pub fn brdf_at(m: &Material, at: &Surface, v: V3, l: V3) -> V3 {
    if dot(at.n, l) <= 0.0 {
        return [0.0; 3];
    }
    let d = dirs(at.n, v, l);
    let layers = &m.desc().layers;
    let mut acc = [0.0; 3];
    for (i, layer) in layers.iter().enumerate().rev() {
        let mut s = [0.0; 3];
        for lb in &layer.lobes {
            s = add(s, lobe(lb, at, v, l, &d));
        }
        if i + 1 == layers.len() {
            acc = s;
        } else {
            let ior = layer.ior.unwrap_or(1.0) as f64;
            let a = layer.absorption;
            let th = layer.thickness as f64;
            let sigma_d = [a.0 as f64 * th, a.1 as f64 * th, a.2 as f64 * th];
            let tr = through(
                ior,
                layer.weight as f64,
                layer.transmission as f64,
                sigma_d,
                layer.coupling as u32,
                &d,
            );
            acc = add(s, mul(tr, acc));
        }
    }
    acc
}

/// What `material_eval` returns: f(l, v) · max(n·l, 0).
pub fn eval_at(m: &Material, at: &Surface, v: V3, l: V3) -> V3 {
    let c = dot(at.n, l);
    if c <= 0.0 {
        return [0.0; 3];
    }
    scale(brdf_at(m, at, v, l), c.min(1.0))
}

/// `material_eval` for constant materials (textures read as white), no mesh tangent.
pub fn eval(m: &Material, n: V3, v: V3, l: V3) -> V3 {
    eval_at(m, &Surface::new(n), v, l)
}

/// f(l, v) without the cosine, for reciprocity checks.
pub fn brdf(m: &Material, n: V3, v: V3, l: V3) -> V3 {
    brdf_at(m, &Surface::new(n), v, l)
}

/// Directions for integrating `eval_at` over the hemisphere by multiple importance
/// sampling: an equal mixture of cosine sampling and GGX visible-normal sampling (Heitz
/// 2018) for every microfacet lobe of the material (one-sample balance heuristic).
pub struct LobeSampler {
    t: V3,
    b: V3,
    n: V3,
    /// None = cosine; Some((αx, αy)) = GGX VNDF along (t, b).
    proposals: Vec<Option<(f64, f64)>>,
}

impl LobeSampler {
    /// The proposals for `m` at `at` (cosine first).
    pub fn new(m: &Material, at: &Surface) -> Self {
        let n = at.n;
        let t = tangent(n, at.tangent);
        let b = bitangent(n, t, at.tangent[3]);
        let mut proposals: Vec<Option<(f64, f64)>> = vec![None];
        for layer in &m.desc().layers {
            for lb in &layer.lobes {
                let p = match lb {
                    Lobe::Ggx { roughness, .. } | Lobe::Clearcoat { roughness, .. } => {
                        let a = alpha(scalar(roughness, at));
                        Some((a, a))
                    }
                    Lobe::AnisoGgx {
                        roughness,
                        anisotropy,
                        ..
                    } => {
                        let a = alpha(scalar(roughness, at));
                        let an = scalar(anisotropy, at).clamp(-1.0, 1.0);
                        Some((
                            (a * (1.0 + an)).max(ALPHA_MIN),
                            (a * (1.0 - an)).max(ALPHA_MIN),
                        ))
                    }
                    _ => None,
                };
                if p.is_some() && !proposals.contains(&p) {
                    proposals.push(p);
                }
            }
        }
        Self { t, b, n, proposals }
    }

    /// How many proposals: 1 (cosine alone) for a material without microfacet lobes.
    pub fn proposals(&self) -> usize {
        self.proposals.len()
    }

    fn to_local(&self, x: V3) -> V3 {
        [dot(x, self.t), dot(x, self.b), dot(x, self.n)]
    }

    /// A direction (world space) drawn from proposal `which` for view `v`, from uniform
    /// (u1, u2); None when it falls below the surface.
    pub fn sample(&self, which: usize, v: V3, u1: f64, u2: f64) -> Option<V3> {
        let ll = match self.proposals[which] {
            None => {
                let r = u1.sqrt();
                let phi = 2.0 * PI * u2;
                [r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt()]
            }
            Some((ax, ay)) => {
                let vl = self.to_local(v);
                let h = sample_vndf(vl, ax, ay, u1, u2);
                add(scale(h, 2.0 * dot(vl, h)), scale(vl, -1.0))
            }
        };
        (ll[2] > 0.0).then(|| {
            add(
                add(scale(self.t, ll[0]), scale(self.b, ll[1])),
                scale(self.n, ll[2]),
            )
        })
    }

    /// The mixture's density over solid angle at direction `l` for view `v`.
    pub fn pdf(&self, v: V3, l: V3) -> f64 {
        let (vl, ll) = (self.to_local(v), self.to_local(l));
        if ll[2] <= 0.0 {
            return 0.0;
        }
        self.proposals
            .iter()
            .map(|p| match p {
                None => ll[2] * INV_PI,
                Some((ax, ay)) => pdf_vndf(vl, ll, *ax, *ay),
            })
            .sum::<f64>()
            / self.proposals.len() as f64
    }
}

/// Directional albedo ∫ f(l, v) cos θl dl over the hemisphere for view `v`, estimated with
/// `samples` deterministic low-discrepancy (R2) samples through a [`LobeSampler`].
pub fn albedo(m: &Material, at: &Surface, v: V3, samples: usize) -> V3 {
    let sampler = LobeSampler::new(m, at);
    let k = sampler.proposals();
    let g = 1.324_717_957_244_746_f64;
    let (a1, a2) = (1.0 / g, 1.0 / (g * g));
    let mut sum = [0.0; 3];
    for i in 0..samples {
        let j = (i / k) as f64;
        let u1 = (0.5 + a1 * j).fract();
        let u2 = (0.5 + a2 * j).fract();
        let Some(l) = sampler.sample(i % k, v, u1, u2) else {
            continue;
        };
        let pdf = sampler.pdf(v, l);
        if pdf <= 0.0 {
            continue;
        }
        let f = eval_at(m, at, v, l);
        sum = add(sum, scale(f, 1.0 / pdf));
    }
    scale(sum, 1.0 / samples as f64)
}

/// Heitz 2018, "Sampling the GGX Distribution of Visible Normals" (local frame, z = n).
fn sample_vndf(v: V3, ax: f64, ay: f64, u1: f64, u2: f64) -> V3 {
    let vh = normalize([ax * v[0], ay * v[1], v[2]]);
    let lensq = vh[0] * vh[0] + vh[1] * vh[1];
    let t1 = if lensq > 0.0 {
        scale([-vh[1], vh[0], 0.0], 1.0 / lensq.sqrt())
    } else {
        [1.0, 0.0, 0.0]
    };
    let t2 = cross(vh, t1);
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh[2]);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).sqrt() + s * r * phi.sin();
    let p3 = (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    let nh = add(add(scale(t1, p1), scale(t2, p2)), scale(vh, p3));
    normalize([ax * nh[0], ay * nh[1], nh[2].max(0.0)])
}

/// The density over l of `sample_vndf` followed by reflection about h.
fn pdf_vndf(v: V3, l: V3, ax: f64, ay: f64) -> f64 {
    let h = normalize(add(v, l));
    let vh = dot(v, h);
    if vh <= 0.0 || h[2] <= 0.0 || v[2] <= 0.0 {
        return 0.0;
    }
    let x = h[0] * h[0] / (ax * ax) + h[1] * h[1] / (ay * ay) + h[2] * h[2];
    let d = 1.0 / (PI * ax * ay * x * x);
    let lam = (-1.0
        + (1.0 + (ax * ax * v[0] * v[0] + ay * ay * v[1] * v[1]) / (v[2] * v[2])).sqrt())
        / 2.0;
    let g1 = 1.0 / (1.0 + lam);
    let dv = g1 * vh * d / v[2];
    dv / (4.0 * vh)
}
