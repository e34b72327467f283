// Lobe library for layered materials. Included textually by the generated material code
// (src/material/wgsl.rs); mirrored exactly in f64 by src/material/reference.rs, which the
// tests compare against. Every function returns the BRDF value f(l, v) without the cosine.
// Names are prefixed `lg_` to stay out of the way of the including shader.

const LG_PI: f32 = 3.14159265358979;
const LG_INV_PI: f32 = 0.318309886183791;
// Smallest GGX α (glTF: α must never be 0). α = 0.002 is perceptual roughness 0.0447,
// Filament's desktop floor; it also bounds the f32 error of D at its peak (see docs).
const LG_ALPHA_MIN: f32 = 0.002;
// Smallest Charlie sheen α (keeps the exponent 1/α ≤ 100).
const LG_SHEEN_ALPHA_MIN: f32 = 0.01;
// Cosines are clamped to at least this inside lobes: no division by zero at grazing angles.
const LG_COS_MIN: f32 = 1e-4;

// Accurate products. Cosines near 0 (grazing light or view) and |n × h| near 0 (the GGX
// peak, sheen at h ≈ n) come out of cancellations, and plain f32 dot and cross products
// leave an absolute error of ~1e-7 there: a large relative error. FMA-based error-free
// transformations do not survive every Vulkan driver (lavapipe does not fuse `fma`; NIR's
// algebraic passes fold TwoSum away and factor a·b + a·c), so the inputs (|x| ≤ 1) are
// split instead: hi = x rounded to a 2^-11 grid, lo = x − hi (exact). The hi·hi products
// are done in i32 (integers up to 2^22, sums below 2^24, converted to f32 exactly): exact,
// and out of reach of float reassociation. Only the small hi·lo and lo·b terms are rounded
// (≤ ~3e-10 absolute, tests/material_gpu.rs).
// The conversions cost, so the lobes split only where a plain product would be inaccurate
// (lg_dot_guarded, lg_dirs). A split without conversions (|x| + 4 with its low mantissa
// bits cleared, the integer products taken to f32 through the bits of 1.5·2^23) measured
// slower on the H200: more instructions than the conversions saved.

// x split as hi + lo, with hi · 2048 as an integer (`steps`). lo = x − hi is exact: where
// hi is 0 it is x; else |x| ≥ 2^-12 makes x and hi multiples of 2^-35, and |lo| ≤ 2^-12
// is at most 2^23 of those (24 bits).
struct LgSplit {
    hi: vec3<f32>,
    lo: vec3<f32>,
    steps: vec3<i32>,
};

fn lg_split(x: vec3<f32>) -> LgSplit {
    let steps = vec3<i32>(round(x * 2048.0));
    let hi = vec3<f32>(steps) * (1.0 / 2048.0);
    return LgSplit(hi, x - hi, steps);
}

fn lg_dot(a: vec3<f32>, b: vec3<f32>) -> f32 {
    let sa = lg_split(a);
    let sb = lg_split(b);
    let p = sa.steps * sb.steps;
    let hh = f32(p.x + p.y + p.z) * (1.0 / 4194304.0);
    return hh + (dot(sa.hi, sb.lo) + dot(sa.lo, b));
}

// a × b for |components| ≤ 1, each component accurate to ~3e-10 absolute.
fn lg_cross(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    let sa = lg_split(a);
    let sb = lg_split(b);
    let ia = sa.steps;
    let ib = sb.steps;
    let ic = ia.yzx * ib.zxy - ia.zxy * ib.yzx;
    return vec3<f32>(ic) * (1.0 / 4194304.0) + (cross(sa.hi, sb.lo) + cross(sa.lo, b));
}

// Plain f32 products where they are accurate enough, the split ones where they are not.
// A plain dot product of a unit vector with one of length ≤ √3 (h unnormalised) is within
// 3·2^-24·√3 ≈ 3.1e-7 of the exact one, fused or not: at a magnitude of LG_PLAIN_MIN =
// 2^-4 or more that is 5e-6 relative. Only near-grazing cosines (n·l, n·v, n·h under
// 1/16) take the split product, so a warp mostly runs one side of the branch (on the H200
// plain products shade harada's 65,536 lights 0.83 ms faster than split ones).
const LG_PLAIN_MIN: f32 = 0.0625;

fn lg_dot_guarded(a: vec3<f32>, b: vec3<f32>) -> f32 {
    let p = dot(a, b);
    if (abs(p) >= LG_PLAIN_MIN) {
        return p;
    }
    return lg_dot(a, b);
}

// How small |n × h|² may be and still come from plain products, by what reads it. A plain
// cross product of those vectors is within 2·2^-24·√3·√3 ≈ 3.6e-7 per unit of |h|, so
// |n × h|² is within 7.2e-7 / |n × h| relative: at |n × h|² / |h|² ≥ 1/16 (with |h| ≥ 1/2,
// |n × h| ≥ 1/8) that is 5.8e-6.
// - LG_S2_GUARDED: only GGX lobes read it; their D = α²/(π (|n×h|² + (n·h)²α²)²) is
//   within twice its relative error.
// - LG_S2_EXACT: a sheen lobe reads it; its D raises it to 1/(2α) (up to 50). Where
//   that D is large enough to be judged relatively (≥ 1e-3: |n × h|² ≥ 0.82 at α =
//   0.01) the bound gives 50 × 1.6e-6 = 8e-5, too near the 1e-4 the material tests allow
//   (measured: 3.8e-7 for |n × h|², so 2e-5), so sheen always takes the split product
//   (|n × h|² / |h|² never reaches 2).
const LG_S2_GUARDED: f32 = 0.0625;
const LG_S2_EXACT: f32 = 2.0;

// What the lobes need about (n, v, l). `s2` is |n × h|² = 1 − (n·h)², from a cross product
// with the unnormalised l + v (exact where l ≈ −v, by Sterbenz's lemma), so it keeps its
// precision where n·h ≈ 1. `s2_plain_min`: LG_S2_GUARDED or LG_S2_EXACT, above.
struct LgDirs {
    h: vec3<f32>,
    // h − n (n·h) = (n × h) × n, from the same cross product: t·h and b·h from it do not
    // pick up the f32 tilt of the tangent frame out of the tangent plane.
    hp: vec3<f32>,
    nl: f32,
    nv: f32,
    nh: f32,
    vh: f32,
    s2: f32,
    lv: f32,
};

fn lg_dirs(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, s2_plain_min: f32) -> LgDirs {
    var d: LgDirs;
    // l + v is exact where l ≈ −v (Sterbenz). Scale it by a power of two (exact) so its
    // largest component is in [0.5, 1): the products then stay accurate relative to
    // their results even when l + v is tiny (grazing mirror configurations).
    // The powers of two from big's exponent bits: big is normal here (1e-30 < big ≤ 2),
    // so with b its biased exponent, frexp would give e = b − 126, and 2^-e has the bits
    // (253 − b) << 23, 2^(e−1) the bits b << 23. Multiplying by them is exact, so this is
    // frexp and ldexp's result bit for bit, in fewer instructions.
    var hq = n;
    var half_scale = 0.5;
    let hs = l + v;
    let big = max(max(abs(hs.x), abs(hs.y)), abs(hs.z));
    if (big > 1e-30) {
        let b = (bitcast<u32>(big) >> 23u) & 0xffu;
        hq = hs * bitcast<f32>((253u - b) << 23u);
        half_scale = bitcast<f32>(b << 23u);
    }
    let len2 = dot(hq, hq);
    let len = sqrt(len2);
    d.h = hq / len;
    d.nl = clamp(lg_dot_guarded(n, l), LG_COS_MIN, 1.0);
    d.nv = clamp(lg_dot_guarded(n, v), LG_COS_MIN, 1.0);
    d.nh = clamp(lg_dot_guarded(n, hq) / len, 0.0, 1.0);
    var c = cross(n, hq);
    if (dot(c, c) < s2_plain_min * len2) {
        c = lg_cross(n, hq);
    }
    d.s2 = min(dot(c, c) / len2, 1.0);
    d.hp = cross(c, n) / len;
    // v·h = l·h = |l + v| / 2 for unit l, v: symmetric in l and v, and no cancellation.
    d.vh = clamp(half_scale * len, 0.0, 1.0);
    // Oren-Nayar's l·v − (n·l)(n·v) cancels: always the split product (only it reads lv).
    d.lv = clamp(lg_dot(l, v), -1.0, 1.0);
    return d;
}

fn lg_alpha(roughness: f32) -> f32 {
    let r = clamp(roughness, 0.0, 1.0);
    return max(r * r, LG_ALPHA_MIN);
}

fn lg_ior_f0(ior: f32) -> f32 {
    let r = (ior - 1.0) / (ior + 1.0);
    return r * r;
}

fn lg_schlick(f0: vec3<f32>, vh: f32) -> vec3<f32> {
    let m = 1.0 - vh;
    let m2 = m * m;
    let m5 = m2 * m2 * m;
    return f0 + (vec3<f32>(1.0) - f0) * m5;
}

fn lg_schlick1(f0: f32, vh: f32) -> f32 {
    let m = 1.0 - vh;
    let m2 = m * m;
    let m5 = m2 * m2 * m;
    return f0 + (1.0 - f0) * m5;
}

// GGX D = χ⁺(n·h) α² / (π ((n·h)²(α² − 1) + 1)²), with (n·h)²(α² − 1) + 1 = |n×h|² + (n·h)²α².
// χ⁺: no microfacet faces below the horizon. `nh` is n·h clamped to [0, 1], so nh = 0 is
// n·h ≤ 0: where the shading normal faces away from the eye (n·v < 0, at the silhouettes
// of smooth-shaded meshes) and the light is almost straight behind the point, h falls
// below the horizon; there |n×h| → 0 with nh = 0 made x → 0 and D unbounded (a 700 spike
// from one VPL of flux 0.01 in the atrium at 1920×1080).
fn lg_d_ggx(nh: f32, s2: f32, a: f32) -> f32 {
    if (nh <= 0.0) {
        return 0.0;
    }
    let x = s2 + nh * nh * (a * a);
    let r = a / x;
    return r * r * LG_INV_PI;
}

// Height-correlated Smith visibility (holds the 1 / (4 n·l n·v)).
fn lg_v_smith(nl: f32, nv: f32, a: f32) -> f32 {
    let a2 = a * a;
    let gv = nl * sqrt(nv * nv * (1.0 - a2) + a2);
    let gl = nv * sqrt(nl * nl * (1.0 - a2) + a2);
    return 0.5 / (gv + gl);
}

fn lg_lambert(color: vec3<f32>) -> vec3<f32> {
    return color * LG_INV_PI;
}

fn lg_ggx(f0: vec3<f32>, a: f32, d: LgDirs) -> vec3<f32> {
    return lg_schlick(f0, d.vh) * (lg_d_ggx(d.nh, d.s2, a) * lg_v_smith(d.nl, d.nv, a));
}

// Anisotropic GGX; t, b: unit tangent and bitangent orthogonal to n.
fn lg_ggx_aniso(
    f0: vec3<f32>,
    a: f32,
    anisotropy: f32,
    t: vec3<f32>,
    b: vec3<f32>,
    v: vec3<f32>,
    l: vec3<f32>,
    d: LgDirs,
) -> vec3<f32> {
    let an = clamp(anisotropy, -1.0, 1.0);
    let at = max(a * (1.0 + an), LG_ALPHA_MIN);
    let ab = max(a * (1.0 - an), LG_ALPHA_MIN);
    let a2 = at * ab;
    // χ⁺(n·h), as in lg_d_ggx
    if (d.nh <= 0.0) {
        return vec3<f32>(0.0);
    }
    let w = vec3<f32>(ab * dot(t, d.hp), at * dot(b, d.hp), a2 * d.nh);
    let w2 = a2 / dot(w, w);
    let dist = a2 * w2 * w2 * LG_INV_PI;
    let lam_v = d.nl * length(vec3<f32>(at * dot(t, v), ab * dot(b, v), d.nv));
    let lam_l = d.nv * length(vec3<f32>(at * dot(t, l), ab * dot(b, l), d.nl));
    let vis = 0.5 / (lam_v + lam_l);
    return lg_schlick(f0, d.vh) * (dist * vis);
}

// Charlie sheen (Estevez & Kulla 2017): D = (2 + 1/α) sin(θh)^(1/α) / (2π), with their
// fitted Smith Λ for the visibility, V = 1 / ((1 + Λ(n·v) + Λ(n·l)) 4 n·v n·l)
// (Neubelt's cheaper 1/(4(n·l + n·v − n·l n·v)) reflects up to 3.6× the light at grazing).
// Sheen is not a closed layer: give its layer a transmission ≤ 1 − sheen albedo.
fn lg_sheen_l(x: f32, a: f32) -> f32 {
    let t = (1.0 - a) * (1.0 - a);
    let p0 = mix(21.5473, 25.3245, t);
    let p1 = mix(3.82987, 3.32435, t);
    let p2 = mix(0.19823, 0.16801, t);
    let p3 = mix(-1.97760, -1.27393, t);
    let p4 = mix(-4.32054, -4.85967, t);
    return p0 / (1.0 + p1 * pow(x, p2)) + p3 * x + p4;
}

// Λ with Estevez & Kulla's terminator softening, Λ^(1 + 2(1 − c)^8), applied to both
// directions (reciprocal). Without it the fitted Λ lets a smooth sheen reflect up to 2.1×
// the light at grazing view; with it the white sheen's albedo stays below 0.47.
fn lg_sheen_lambda(c: f32, a: f32) -> f32 {
    var l = 2.0 * lg_sheen_l(0.5, a) - lg_sheen_l(1.0 - c, a);
    if (c < 0.5) {
        l = lg_sheen_l(c, a);
    }
    let m = 1.0 - c;
    let m2 = m * m;
    let m4 = m2 * m2;
    return exp(l * (1.0 + 2.0 * m4 * m4));
}

fn lg_sheen(color: vec3<f32>, roughness: f32, d: LgDirs) -> vec3<f32> {
    let r = clamp(roughness, 0.0, 1.0);
    let a = max(r * r, LG_SHEEN_ALPHA_MIN);
    let inv = 1.0 / a;
    var dist = 0.0;
    if (d.s2 > 0.0) {
        dist = (2.0 + inv) * pow(d.s2, 0.5 * inv) * (0.5 * LG_INV_PI);
    }
    let vis = 1.0 / ((1.0 + lg_sheen_lambda(d.nv, a) + lg_sheen_lambda(d.nl, a)) * (4.0 * d.nv * d.nl));
    return color * (dist * vis);
}

// Fujii's improved Oren-Nayar ("A tiny improvement of Oren-Nayar reflectance model"),
// σ = roughness in [0, 1]; σ = 0 is Lambert.
fn lg_oren_nayar(color: vec3<f32>, roughness: f32, d: LgDirs) -> vec3<f32> {
    let sigma = clamp(roughness, 0.0, 1.0);
    let s = d.lv - d.nl * d.nv;
    var t = 1.0;
    if (s > 0.0) {
        t = max(d.nl, d.nv);
    }
    let a = 1.0 / (1.0 + (0.5 - 2.0 / (3.0 * LG_PI)) * sigma);
    let b = sigma * a;
    return color * (LG_INV_PI * (a + b * s / t));
}

// The cosine of a direction refracted into a layer of IOR `ior` (≥ 1).
// cos θ' = sqrt(1 − (1 − c²)/η²) = sqrt((η − 1)(η + 1) + c²) / η, the second form without
// cancellation at grazing angles.
fn lg_cos_inside(c: f32, ior: f32) -> f32 {
    return max(sqrt((ior - 1.0) * (ior + 1.0) + c * c) / ior, LG_COS_MIN);
}

// 1 − w·F(c) for a Schlick interface of reflectance f0 at normal incidence:
// (1 − w) + w (1 − f0) (1 − m⁵) with 1 − m⁵ = c (1 + m + m² + m³ + m⁴), m = 1 − c: no
// cancellation where c → 0.
fn lg_one_minus_wf(f0: f32, w: f32, c: f32) -> f32 {
    let m = 1.0 - c;
    let q = c * (1.0 + m * (1.0 + m * (1.0 + m * (1.0 + m))));
    return max((1.0 - w) + w * (1.0 - f0) * q, 0.0);
}

// What a layer lets through to the layer below, times transmission and Beer-Lambert
// absorption exp(−σ d (1/cos θl' + 1/cos θv')) along the refracted in and out paths.
// coupling 0 (`Interface`, the default): light crosses the interface going in and coming
// out, (1 − w F(n·l)) (1 − w F(n·v)): reciprocal and energy-conserving.
// coupling 1 (`HalfVector`, glTF's fresnel_mix): (1 − w F(v·h)).
fn lg_through(
    ior: f32,
    weight: f32,
    transmission: f32,
    sigma_d: vec3<f32>,
    coupling: u32,
    d: LgDirs,
) -> vec3<f32> {
    let path = 1.0 / lg_cos_inside(d.nl, ior) + 1.0 / lg_cos_inside(d.nv, ior);
    return lg_through_clear(ior, weight, transmission, coupling, d) * exp(-sigma_d * path);
}

// lg_through of a layer that absorbs nothing (σ d = 0): its Beer-Lambert factor is
// exp(−0 · path) = 1 for every path (path is finite: each cosine is at least LG_COS_MIN),
// so the refracted cosines, their reciprocals and the three exponentials are left out.
// Every glTF material's specular layer is one.
fn lg_through_clear(ior: f32, weight: f32, transmission: f32, coupling: u32, d: LgDirs) -> f32 {
    var pass_ = transmission;
    if (ior > 1.0) {
        let f0 = lg_ior_f0(ior);
        if (coupling == 1u) {
            pass_ *= lg_one_minus_wf(f0, weight, d.vh);
        } else {
            pass_ *= lg_one_minus_wf(f0, weight, d.nl) * lg_one_minus_wf(f0, weight, d.nv);
        }
    }
    return pass_;
}

// Tangent frame: the tangent made orthogonal to n, or a branchless basis from n alone (Duff
// et al. 2017) when the mesh has none.
fn lg_tangent(n: vec3<f32>, tangent: vec4<f32>) -> vec3<f32> {
    let tt = tangent.xyz - n * dot(n, tangent.xyz);
    let l2 = dot(tt, tt);
    if (l2 > 1e-8) {
        return tt / sqrt(l2);
    }
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    return vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
}

fn lg_bitangent(n: vec3<f32>, t: vec3<f32>, w: f32) -> vec3<f32> {
    return cross(n, t) * select(1.0, -1.0, w < 0.0);
}
