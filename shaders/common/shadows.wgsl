// Ray-cast shadows, shared by job creation (shadow/shadow_ray_jobs.wgsl), casting
// (shadow/shadow_ray_cast.wgsl) and the light loop, so all of them number casters,
// offset origins and test facing the same way.
//
// A pixel's shadow-casting lights are numbered in the order its light list visits them,
// counting only those that reach it (radiance > 0): caster c is bit c of the pixel's
// 128-bit mask (4 words), set when the light is hidden. Casters past the 128th are lit
// unshadowed and counted by job creation (ShadowReport::overflow_pixels).
//
// Defines: SHADOW_NORMAL_OFFSET (origin offset along the geometric normal, relative to
// the position's magnitude), and in the light loop SHADOW_MASK (read the mask),
// SHADOW_TRACE (cast in the loop: the naive variant; needs the BVH and `shadow_ng`) or
// SHADOW_ATLAS (sample a ShadowAtlas pass's depth atlas, with SHADOW_PCF5 for the 5×5
// filter, else one 2×2 hardware-comparison tap; SHADOW_ATLAS_FLOAT: the atlas is the
// compute raster's R32Float, compared by hand with the same weights), or SHADOW_HYBRID
// with SHADOW_ATLAS and SHADOW_MASK or SHADOW_TRACE (the atlas for lights with a map this
// frame, the mask or the tracer for the rest: the tracer for glass, which no job
// covers). SHADOW_ATLAS_LIGHTS alone (job creation) reads only which lights have a map.
//
// The light loop asks `shadow_visibility` for the fraction of light that reaches p:
// 0 or 1 from the mask and the tracer, filtered from the atlas.

#include "common/shading_point.wgsl"

const LIGHT_CASTS_SHADOW: u32 = 1u;
const SHADOW_MAX_CASTERS: u32 = 128u;
const SHADOW_MASK_WORDS: u32 = 4u;
// The job buffer (src/graph/kinds/shadow_ray_jobs.rs): header words before the jobs, and
// words a job (pixel index, then light index | caster number << 24).
const JOB_HEADER_WORDS: u32 = 8u;
const JOB_WORDS: u32 = 2u;
// After JOB_CAPACITY jobs, per pixel the surface job creation found (position, then
// geometric normal): every ray of the pixel reads it instead of rebuilding it.
const JOB_SURFACE_WORDS: u32 = 6u;
// Jobs a workgroup of the casting pass (its dispatch is written by job creation).
const SHADOW_CAST_GROUP: u32 = 64u;

// The shadow ray's origin: off the surface along its geometric normal, by an amount that
// scales with the position's magnitude (float positions are that much less precise).
fn shadow_origin(p: vec3<f32>, ng: vec3<f32>) -> vec3<f32> {
    let scale = max(max(abs(p.x), abs(p.y)), max(abs(p.z), 1.0));
    return p + ng * (SHADOW_NORMAL_OFFSET * scale);
}

// The shadow ray's end, as t_max of origin + t * (light_pos - origin): short of the light
// by the same relative offset, along the ray, so a light lying on a surface or at an
// occluder's vertex is not hidden by that surface (its triangle is hit at t ≈ 1, either
// side of 1 by rounding). src/shadow/mod.rs: shadow_ray is the CPU twin of both.
fn shadow_t_max(origin: vec3<f32>, light_pos: vec3<f32>) -> f32 {
    let scale = max(max(abs(light_pos.x), abs(light_pos.y)), max(abs(light_pos.z), 1.0));
    return max(1.0 - SHADOW_NORMAL_OFFSET * scale / length(light_pos - origin), 0.0);
}

// A light behind the surface's face is hidden by the surface itself.
fn shadow_faces(p: vec3<f32>, ng: vec3<f32>, light_pos: vec3<f32>) -> bool {
    return dot(ng, light_pos - p) > 0.0;
}

#if SHADOW_MASK
#if SHADOW_HYBRID
#else
fn shadow_visibility(pixel_index: u32, caster: u32, light: u32, light_pos: vec3<f32>, p: ShadingPoint) -> f32 {
    return select(0.0, 1.0, shadow_visible(pixel_index, caster, light_pos, p.position));
}
#endif

fn shadow_visible(pixel_index: u32, caster: u32, light_pos: vec3<f32>, p: vec3<f32>) -> bool {
    if (caster >= SHADOW_MAX_CASTERS) {
        return true;
    }
    let word = shadow_mask[pixel_index * SHADOW_MASK_WORDS + caster / 32u];
    return (word & (1u << (caster % 32u))) == 0u;
}
#endif

#if SHADOW_TRACE
// The fragment's geometric normal, set by the fragment shader before shading.
var<private> shadow_ng: vec3<f32>;

#if SHADOW_HYBRID
#else
fn shadow_visibility(pixel_index: u32, caster: u32, light: u32, light_pos: vec3<f32>, p: ShadingPoint) -> f32 {
    return select(0.0, 1.0, shadow_visible(pixel_index, caster, light_pos, p.position));
}
#endif

fn shadow_visible(pixel_index: u32, caster: u32, light_pos: vec3<f32>, p: vec3<f32>) -> bool {
    if (!shadow_faces(p, shadow_ng, light_pos)) {
        return false;
    }
    let origin = shadow_origin(p, shadow_ng);
    return !bvh_occluded(origin, light_pos - origin, shadow_t_max(origin, light_pos));
}
#endif

#if SHADOW_ATLAS_LIGHTS
// The view table (src/kinds/shadow_atlas/rules.rs): a header (views, atlas side, lights,
// room for views), per view its view-projection, its tile in atlas UV (min, max) and
// (texel size at unit distance, normal offset in texels); then per light its first
// view + 1 (0: no shadow map this frame), bit 31 set for six cube faces.
const SHADOW_VIEW_VEC4S: u32 = 6u;
const SHADOW_CUBE_BIT: u32 = 0x80000000u;

// The light's entry in the view table: 0 when it has no map this frame (left to rays
// by the policy, dropped, or casting no shadow).
fn shadow_atlas_entry(light: u32) -> u32 {
    let header = bitcast<vec4<u32>>(shadow_views[0]);
    let table = 1u + SHADOW_VIEW_VEC4S * header.w;
    return bitcast<u32>(shadow_views[table + light / 4u][light % 4u]);
}
#endif

#if SHADOW_ATLAS
// The cube face a direction from the light falls on (src/shadow/atlas.rs: cube_face).
fn shadow_cube_face(d: vec3<f32>) -> u32 {
    let a = abs(d);
    if (a.x >= a.y && a.x >= a.z) {
        return select(1u, 0u, d.x >= 0.0);
    }
    if (a.y >= a.z) {
        return select(3u, 2u, d.y >= 0.0);
    }
    return select(5u, 4u, d.z >= 0.0);
}

// Where a point falls in its light's atlas tile: the tap's centre, the clamp range
// keeping every tap half a texel inside the tile (so the comparison's 2×2 footprint never
// reads a neighbour's depths), the reference depth; `lit` when no map covers it.
struct AtlasTap {
    uv: vec2<f32>,
    lo: vec2<f32>,
    hi: vec2<f32>,
    depth: f32,
    texel: f32,
    lit: bool,
};

fn shadow_atlas_tap(light: u32, light_pos: vec3<f32>, position: vec3<f32>, normal: vec3<f32>) -> AtlasTap {
    var tap: AtlasTap;
    tap.lit = true;
    let header = bitcast<vec4<u32>>(shadow_views[0]);
    let entry = shadow_atlas_entry(light);
    if (entry == 0u) {
        return tap; // no room this frame: unshadowed (reported by the atlas pass)
    }
    let first = (entry & ~SHADOW_CUBE_BIT) - 1u;
    let cube = (entry & SHADOW_CUBE_BIT) != 0u;
    // Off the surface by a few texels of the view the point falls in: a texel's world
    // size grows with the distance from the light.
    var base = 1u + SHADOW_VIEW_VEC4S * first;
    let dist = length(position - light_pos);
    let offset = shadow_views[base + 5u].y * shadow_views[base + 5u].x * dist;
    let q = position + normal * offset;
    if (cube) {
        base += SHADOW_VIEW_VEC4S * shadow_cube_face(q - light_pos);
    }
    let view_proj = mat4x4<f32>(
        shadow_views[base],
        shadow_views[base + 1u],
        shadow_views[base + 2u],
        shadow_views[base + 3u],
    );
    let tile = shadow_views[base + 4u];
    let clip = view_proj * vec4<f32>(q, 1.0);
    if (clip.w <= 0.0) {
        return tap;
    }
    let ndc = clip.xyz / clip.w;
    tap.uv = mix(tile.xy, tile.zw, vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5));
    tap.texel = 1.0 / f32(header.y);
    tap.lo = tile.xy + vec2<f32>(0.5 * tap.texel);
    tap.hi = tile.zw - vec2<f32>(0.5 * tap.texel);
    tap.depth = ndc.z;
    tap.lit = false;
    return tap;
}

#if SHADOW_ATLAS_FLOAT
// shadow_atlas_manual's 6×6 footprint from texel `first` on, when no texel of it is
// clamped: nine gathers of 2×2 texels instead of 36 loads.
fn shadow_atlas_gathered(depth: f32, first: vec2<i32>, f: vec2<f32>, side: f32) -> f32 {
    // Per-axis weights of footprint columns (rows) 0..5: 1 - f, 1, 1, 1, 1, f.
    var sum = 0.0;
    for (var j = 0; j < 3; j++) {
        let wy = vec2<f32>(select(1.0, 1.0 - f.y, j == 0), select(1.0, f.y, j == 2));
        for (var i = 0; i < 3; i++) {
            let wx = vec2<f32>(select(1.0, 1.0 - f.x, i == 0), select(1.0, f.x, i == 2));
            // The corner the quad's four texels share: gather returns (x, y + 1),
            // (x + 1, y + 1), (x + 1, y), (x, y) for its top-left texel (x, y).
            let corner = (vec2<f32>(first + vec2<i32>(2 * i, 2 * j)) + 1.0) / side;
            let stored = textureGather(0, shadow_atlas, shadow_gather, corner);
            // Lit where the reference is at most the stored depth (LessEqual).
            let lit = select(vec4<f32>(0.0), vec4<f32>(1.0), vec4<f32>(depth) <= stored);
            sum += dot(lit, vec4<f32>(wx.x * wy.y, wx.y * wy.y, wx.y * wy.x, wx.x * wy.x));
        }
    }
    return sum;
}

// The hardware's comparison filter by hand, for an R32Float atlas (a compute raster
// cannot store Depth32Float, and a draw converting it would put the work back on the
// raster units). A bilinear comparison tap at texel position p (uv × side − ½) weighs
// texels floor(p) and floor(p) + 1 by (1 − fract, fract) per axis; a tap clamped to
// [lo, hi] weighs exactly as the unclamped one with its texel indices clamped to the
// tile, per axis. So the 5×5 grid of taps, all sharing one fraction, is a 6×6 footprint
// of comparisons weighted (1 − f, 1, 1, 1, 1, f) per axis: 36 loads for 25 taps, or
// nine gathers where no texel of it is clamped.
// `taps` per axis: 1 (2×2) or 5 (PCF 5×5). The hardware weights with 8 fractional bits
// on most GPUs; these are exact, a difference of at most 1/256 of a tap at an edge.
fn shadow_atlas_manual(t: AtlasTap, taps: i32) -> f32 {
    let side = 1.0 / t.texel;
    let p = t.uv * side - 0.5;
    let base = vec2<i32>(floor(p));
    let f = p - floor(p);
    // Texel bounds of the tile: the clamp range's half-texel inset, back in texels.
    let lo = vec2<i32>(round(t.lo * side - 0.5));
    let hi = vec2<i32>(round(t.hi * side - 0.5));
    let reach = (taps - 1) / 2;
    let first = base - vec2<i32>(reach);
    if (taps == 5 && all(first >= lo) && all(first + vec2<i32>(taps) <= hi)) {
        return shadow_atlas_gathered(t.depth, first, f, side) / 25.0;
    }
    var sum = 0.0;
    for (var j = 0; j <= taps; j++) {
        let wy = select(select(1.0, f.y, j == taps), 1.0 - f.y, j == 0);
        let y = clamp(base.y - reach + j, lo.y, hi.y);
        for (var i = 0; i <= taps; i++) {
            let wx = select(select(1.0, f.x, i == taps), 1.0 - f.x, i == 0);
            let x = clamp(base.x - reach + i, lo.x, hi.x);
            let stored = textureLoad(shadow_atlas, vec2<i32>(x, y), 0).x;
            // Lit where the reference is at most the stored depth (LessEqual).
            sum += select(0.0, wx * wy, t.depth <= stored);
        }
    }
    return sum / f32(taps * taps);
}
#endif

// 25 comparison taps on a 5×5 texel grid (AMD TiledLighting11).
fn shadow_atlas_pcf5(t: AtlasTap) -> f32 {
    if (t.lit) {
        return 1.0;
    }
#if SHADOW_ATLAS_FLOAT
    return shadow_atlas_manual(t, 5);
#else
    var sum = 0.0;
    for (var j = -2; j <= 2; j++) {
        for (var i = -2; i <= 2; i++) {
            let uv = clamp(t.uv + vec2<f32>(f32(i), f32(j)) * t.texel, t.lo, t.hi);
            sum += textureSampleCompareLevel(shadow_atlas, shadow_sampler, uv, t.depth);
        }
    }
    return sum / 25.0;
#endif
}

// One comparison tap: the hardware's bilinear 2×2 comparison.
fn shadow_atlas_2x2(t: AtlasTap) -> f32 {
    if (t.lit) {
        return 1.0;
    }
#if SHADOW_ATLAS_FLOAT
    return shadow_atlas_manual(t, 1);
#else
    return textureSampleCompareLevel(shadow_atlas, shadow_sampler, clamp(t.uv, t.lo, t.hi), t.depth);
#endif
}

fn shadow_atlas_visibility(light: u32, light_pos: vec3<f32>, p: ShadingPoint) -> f32 {
    let tap = shadow_atlas_tap(light, light_pos, p.position, p.normal);
#if SHADOW_PCF5
    return shadow_atlas_pcf5(tap);
#else
    return shadow_atlas_2x2(tap);
#endif
}

#if SHADOW_HYBRID
// A light with a map this frame samples it; the others were ray-cast by job creation,
// which skipped the mapped ones (shadow/shadow_ray_jobs.wgsl) and numbered casters alike
// (SHADOW_MASK), or are traced here (SHADOW_TRACE).
fn shadow_visibility(pixel_index: u32, caster: u32, light: u32, light_pos: vec3<f32>, p: ShadingPoint) -> f32 {
    if (shadow_atlas_entry(light) != 0u) {
        return shadow_atlas_visibility(light, light_pos, p);
    }
    return select(0.0, 1.0, shadow_visible(pixel_index, caster, light_pos, p.position));
}
#else
fn shadow_visibility(pixel_index: u32, caster: u32, light: u32, light_pos: vec3<f32>, p: ShadingPoint) -> f32 {
    return shadow_atlas_visibility(light, light_pos, p);
}
#endif
#endif
