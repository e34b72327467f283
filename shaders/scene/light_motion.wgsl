// Scene-file light motion, evaluated per light on the GPU before the graph's passes: each
// light as placed, moved by its motion's phase at this frame's time, written over the
// light buffers every pass reads. The same f32 arithmetic as `Motion::apply_phase`
// (src/scene/motion.rs); the phases (orbit rotation, path segment, flicker cell) are taken
// per motion on the CPU in f64, so no sine is taken here.

#include "common/types.wgsl"

// One motion's parameters (`GpuMotion` in src/render/light_motion.rs), uploaded once.
struct Motion {
    centre: vec3<f32>,
    // ORBIT | PATH | FLICKER | CATMULL_ROM
    flags: u32,
    // The first light of the motion's run: flicker seeds with the place in the run.
    first_light: u32,
    first_point: u32,
    points: u32,
    amplitude: f32,
    // The flicker seed, low and high words.
    seed: vec2<u32>,
    _pad: vec2<u32>,
};

// One motion at this frame's time (`GpuMotionPhase`), written every frame.
struct Phase {
    // The orbit's rotation quaternion (x, y, z, w).
    turn: vec4<f32>,
    segment: u32,
    along: f32,
    blend: f32,
    _pad0: u32,
    // The flicker's lattice cell as a two's-complement 64-bit integer (low, high).
    cell: vec2<u32>,
    _pad1: vec2<u32>,
};

const NO_MOTION: u32 = 0xffffffffu;
const ORBIT: u32 = 1u;
const PATH: u32 = 2u;
const FLICKER: u32 = 4u;
const CATMULL_ROM: u32 = 8u;

@group(0) @binding(0) var<storage, read> motion_of_light: array<u32>;
@group(0) @binding(1) var<storage, read> placed_geometry: array<LightGeometry>;
@group(0) @binding(2) var<storage, read> placed_properties: array<LightProperties>;
@group(0) @binding(3) var<storage, read> motions: array<Motion>;
@group(0) @binding(4) var<storage, read> phases: array<Phase>;
@group(0) @binding(5) var<storage, read> path_points: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> light_geometry: array<LightGeometry>;
@group(0) @binding(7) var<storage, read_write> light_properties: array<LightProperties>;

// glam's `Quat * Vec3`, term for term.
fn rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let b = q.xyz;
    let b2 = dot(b, b);
    return v * (q.w * q.w - b2) + b * (dot(v, b) * 2.0) + cross(b, v) * (q.w * 2.0);
}

fn path_point(m: Motion, k: u32) -> vec3<f32> {
    return path_points[m.first_point + k % m.points].xyz;
}

// `KeyframePath::offset_at`.
fn path_offset(m: Motion, ph: Phase) -> vec3<f32> {
    let n = m.points;
    if (n < 2u) {
        return path_point(m, 0u);
    }
    let i = ph.segment;
    let s = ph.along;
    if ((m.flags & CATMULL_ROM) == 0u) {
        return path_point(m, i) * (1.0 - s) + path_point(m, i + 1u) * s;
    }
    let p0 = path_point(m, i + n - 1u);
    let p1 = path_point(m, i);
    let p2 = path_point(m, i + 1u);
    let p3 = path_point(m, i + 2u);
    let s2 = s * s;
    let s3 = s * s * s;
    return 0.5 * (2.0 * p1
        + (p2 - p0) * s
        + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * s2
        + (3.0 * p1 - p0 - 3.0 * p2 + p3) * s3);
}

// 64-bit integers as (low, high) words, for the flicker's hash.
fn add64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    return vec2<u32>(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

// The full 64-bit product of two 32-bit words, from 16-bit halves.
fn mul_wide(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let p11 = a1 * b1;
    let mid = (p00 >> 16u) + (p01 & 0xffffu) + (p10 & 0xffffu);
    return vec2<u32>((p00 & 0xffffu) | (mid << 16u), p11 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u));
}

// a × b mod 2^64.
fn mul64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let w = mul_wide(a.x, b.x);
    return vec2<u32>(w.x, w.y + a.x * b.y + a.y * b.x);
}

// a ^ (a >> n) for 0 < n < 32.
fn xor_shr64(a: vec2<u32>, n: u32) -> vec2<u32> {
    return a ^ vec2<u32>((a.x >> n) | (a.y << (32u - n)), a.y >> n);
}

// SplitMix64's finaliser (`mix64` in src/scene/motion.rs).
fn mix64(z0: vec2<u32>) -> vec2<u32> {
    var z = add64(z0, vec2<u32>(0x7F4A7C15u, 0x9E3779B9u));
    z = mul64(xor_shr64(z, 30u), vec2<u32>(0x1CE4E5B9u, 0xBF58476Du));
    z = mul64(xor_shr64(z, 27u), vec2<u32>(0x133111EBu, 0x94D049BBu));
    return xor_shr64(z, 31u);
}

// The flicker's lattice value of light `index` in cell `k`, in [-1, 1]: exact (24 bits).
fn lattice(seed: vec2<u32>, index: u32, k: vec2<u32>) -> f32 {
    let h = mix64(seed ^ mix64(vec2<u32>(k.x, index ^ k.y)));
    return f32(h.y >> 8u) * (2.0 / 16777216.0) - 1.0;
}

// `Flicker::factor`.
fn flicker_factor(m: Motion, ph: Phase, index: u32) -> f32 {
    let a = lattice(m.seed, index, ph.cell);
    let b = lattice(m.seed, index, add64(ph.cell, vec2<u32>(1u, 0u)));
    let noise = a + (b - a) * ph.blend;
    return max(1.0 + m.amplitude * noise, 0.0);
}

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&motion_of_light)) {
        return;
    }
    var g = placed_geometry[i];
    var p = placed_properties[i];
    let which = motion_of_light[i];
    if (which != NO_MOTION) {
        let m = motions[which];
        let ph = phases[which];
        if ((m.flags & PATH) != 0u) {
            g.position += path_offset(m, ph);
        }
        if ((m.flags & ORBIT) != 0u) {
            g.position = m.centre + rotate(ph.turn, g.position - m.centre);
            // Zero for point lights, and it stays zero.
            g.direction = rotate(ph.turn, g.direction);
        }
        if ((m.flags & FLICKER) != 0u) {
            p.color *= flicker_factor(m, ph, i - m.first_light);
        }
    }
    light_geometry[i] = g;
    light_properties[i] = p;
}
