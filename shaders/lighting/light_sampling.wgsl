// Stochastic direct lighting with shadow rays (LightSampling), one invocation a pixel of
// a visibility buffer, its surface rebuilt as the shadow passes rebuild it
// (shadow/surface_source.wgsl: the pixel-centre point and the triangle's normal facing
// the eye, `ng`).
//
// The target function p̂ of a light at a surface is its unshadowed contribution without
// the material: the luminance of the radiance arriving (common/lighting.wgsl's
// incident_light) times the cosine at ng; zero for a light that casts no shadow (shading
// lights those exactly), reaches no further, or lies behind ng (ray-cast shadows count it
// hidden). It is positive wherever a shadow-casting light can add light, so the estimate
// below is unbiased whatever the material does with it.
//
// `candidates`: the SAMPLE_EXACT lights of the tile list with the largest p̂ are traced
// exactly (bit 31 of their word set when hidden). Each of SAMPLE_COUNT reservoirs then
// streams SAMPLE_CANDIDATES lights drawn uniformly from the list (pdf 1/count), weighted
// by p̂ × count, with the exact lights' p̂ set to zero, and keeps one in proportion to its
// weight (weighted reservoir sampling); its contribution weight is
// W = wsum / (M p̂(y)), so E[f(y) V(y) W] is the sum of f V over the lights left to
// sampling (Talbot et al., "Importance Resampling for Global Illumination"). Without
// SAMPLE_SPATIAL the chosen light's shadow ray is traced here and a hidden one gets W = 0.
//
// `spatial` (SAMPLE_SPATIAL): each reservoir is resampled with the same reservoir of
// SPATIAL_NEIGHBOURS pixels drawn in a disc of SPATIAL_RADIUS pixels (skipping those whose
// depth differs by over 10% or whose normal by over ~25°), each weighted by
// p̂_here(y_q) W_q M_q (Bitterli et al., "Spatiotemporal reservoir resampling for
// real-time ray tracing with dynamic direct lighting"). Biased: W = wsum / (ΣM p̂(y)).
// With SPATIAL_UNBIASED: W = wsum / (Z p̂(y)), Z the M of only those pixels (this one
// included) whose own p̂ (their surface, their exact set) is non-zero at y: the 1/Z
// weight, unbiased because the target has no visibility in it. The chosen light's ray is
// traced after the resampling.
//
// `temporal` (SAMPLE_TEMPORAL): see its comment below.
//
// `advance` counts frames in the header, so every frame draws new numbers, and keeps the
// view-projection for the next frame's reprojection.
// Defines: LIGHT_LISTS, VISIBILITY_IDS, SHADOW_NORMAL_OFFSET, SAMPLE_EXACT, EXACT_ARRAY
// (max(SAMPLE_EXACT, 1)), SAMPLE_COUNT, SAMPLE_CANDIDATES, SAMPLE_SEED; SAMPLE_SPATIAL
// with SPATIAL_NEIGHBOURS, SPATIAL_RADIUS and SPATIAL_UNBIASED; SAMPLE_TEMPORAL with
// HISTORY_REGION and HISTORY_CAP; SAMPLE_REGIONS; TRACE_CANDIDATES or TRACE_TEMPORAL (the
// dispatch that traces the chosen lights when no later one does).

#include "common/types.wgsl"
#include "common/lighting.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
#include "common/light_inputs.wgsl"
@group(0) @binding(5) var<storage, read> bvh_nodes: array<BvhNode>;
@group(0) @binding(6) var<storage, read> bvh_triangles: array<BvhTriangle>;
#if BVH_ALPHA_TEST
@group(0) @binding(8) var<storage, read> bvh_alpha: array<u32>;
#endif
@group(0) @binding(7) var<storage, read_write> light_samples: array<u32>;

#include "shadow/bvh.wgsl"
#include "common/shadows.wgsl"
#include "shadow/surface_source.wgsl"
#include "common/light_samples.wgsl"

const LUMINANCE: vec3<f32> = vec3<f32>(0.2126, 0.7152, 0.0722);
// Below this p̂ is clamped up where radiance arrives, so a dim light keeps its support.
const MIN_TARGET: f32 = 1e-30;

fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

var<private> rng: u32;

// Uniform in [0, 1).
fn rand() -> f32 {
    rng = pcg(rng);
    return f32(rng >> 8u) * (1.0 / 16777216.0);
}

fn seed_rng(pixel: u32, stream: u32) {
    rng = pcg(pixel ^ pcg(SAMPLE_SEED ^ pcg(light_samples[0] * 2u + stream)));
}

fn sample_target(light: u32, position: vec3<f32>, ng: vec3<f32>) -> f32 {
    let props = light_properties[light];
    if ((props.flags & LIGHT_CASTS_SHADOW) == 0u) {
        return 0.0;
    }
    let g = light_geometry[light];
    if (!shadow_faces(position, ng, g.position)) {
        return 0.0;
    }
    let inc = incident_light(g, props, position);
    if (!any(inc.radiance > vec3<f32>(0.0))) {
        return 0.0;
    }
    return max(dot(inc.radiance, LUMINANCE) * dot(ng, inc.dir), MIN_TARGET);
}

fn hidden(s: ShadowSurface, light: u32) -> bool {
    let origin = shadow_origin(s.position, s.ng);
    let light_pos = light_geometry[light].position;
    return bvh_occluded(origin, light_pos - origin, shadow_t_max(origin, light_pos));
}

// Whether `light` is one of `pixel`'s exact lights (as written by `candidates`).
fn is_exact(pixel: u32, light: u32) -> bool {
    for (var j = 0u; j < SAMPLE_EXACT; j++) {
        if ((light_samples[exact_word(pixel, j)] & ~SAMPLE_HIDDEN) == light) {
            return true;
        }
    }
    return false;
}

fn store_reservoir(region: u32, pixel: u32, j: u32, light: u32, w: f32, m: f32) {
    let base = reservoir_word(region, pixel, j);
    light_samples[base] = light;
    light_samples[base + 1u] = bitcast<u32>(w);
    light_samples[base + 2u] = bitcast<u32>(m);
}

struct Reservoir {
    light: u32,
    w: f32,
    m: f32,
};

fn load_reservoir(region: u32, pixel: u32, j: u32) -> Reservoir {
    let base = reservoir_word(region, pixel, j);
    return Reservoir(
        light_samples[base],
        bitcast<f32>(light_samples[base + 1u]),
        bitcast<f32>(light_samples[base + 2u]),
    );
}

fn view_depth(p: vec3<f32>) -> f32 {
    return -(frame.view * vec4<f32>(p, 1.0)).z;
}

#if EXACT_PER_BLOCK
// The block's exact lights (EXACT_PER_BLOCK): the SAMPLE_EXACT lights of largest p̂ at any
// of four points of the 8×8 block (the centres of its 4×4 quarters, those with a
// surface). Each point's list is walked by the block's 64 invocations together, each
// keeping its own best lights (one entry a light, its largest p̂); then SAMPLE_EXACT
// rounds each take the largest entry left in the block (ties to the lower light index)
// and drop that light from every invocation's entries.
var<workgroup> block_point: array<ShadowSurface, 4>;
var<workgroup> block_best: atomic<u32>;
var<workgroup> block_winner: atomic<u32>;
var<workgroup> round_best: u32;
var<workgroup> round_winner: u32;
var<workgroup> block_exact: array<u32, EXACT_ARRAY>;

struct Kept {
    light: array<u32, EXACT_ARRAY>,
    t: array<f32, EXACT_ARRAY>,
    n: u32,
};

// `light` at target t offered to `kept`: its entry raised if kept, else added while room
// is left, else put in place of the weakest when stronger.
fn keep(kept: ptr<function, Kept>, light: u32, t: f32) {
    if (t <= 0.0) {
        return;
    }
    var weakest = 0u;
    for (var e = 0u; e < (*kept).n; e++) {
        if ((*kept).light[e] == light) {
            (*kept).t[e] = max((*kept).t[e], t);
            return;
        }
        if ((*kept).t[e] < (*kept).t[weakest]) {
            weakest = e;
        }
    }
    if ((*kept).n < SAMPLE_EXACT) {
        (*kept).light[(*kept).n] = light;
        (*kept).t[(*kept).n] = t;
        (*kept).n += 1u;
    } else if (t > (*kept).t[weakest]) {
        (*kept).light[weakest] = light;
        (*kept).t[weakest] = t;
    }
}

// The block's exact lights into block_exact; returns how many. Every invocation of the
// workgroup calls it (barriers).
fn choose_block_exact(lane: u32, block: vec2<u32>) -> u32 {
    if (lane < 4u) {
        let xy = min(block * 8u + vec2<u32>(2u + 4u * (lane % 2u), 2u + 4u * (lane / 2u)), frame.size - 1u);
        block_point[lane] = shadow_surface(xy);
    }
    if (lane == 0u) {
        atomicStore(&block_best, 0u);
        atomicStore(&block_winner, SAMPLE_NONE);
    }
    workgroupBarrier();
    var kept: Kept;
    kept.n = 0u;
    for (var q = 0u; q < 4u; q++) {
        let point = block_point[q];
        if (!point.valid) {
            continue;
        }
        let xy = min(block * 8u + vec2<u32>(2u + 4u * (q % 2u), 2u + 4u * (q / 2u)), frame.size - 1u);
        let range = light_range(vec2<f32>(xy) + 0.5, view_depth(point.position));
        for (var k = lane; k < range.count; k += 64u) {
            let i = light_at(range, k);
            keep(&kept, i, sample_target(i, point.position, point.ng));
        }
    }
    var n = 0u;
    for (var j = 0u; j < SAMPLE_EXACT; j++) {
        var mine = 0.0;
        for (var e = 0u; e < kept.n; e++) {
            mine = max(mine, kept.t[e]);
        }
        // p̂ is positive or zero, so its bits order as the values do.
        atomicMax(&block_best, bitcast<u32>(mine));
        workgroupBarrier();
        if (lane == 0u) {
            round_best = atomicLoad(&block_best);
        }
        let best = workgroupUniformLoad(&round_best);
        if (best == 0u) {
            break;
        }
        for (var e = 0u; e < kept.n; e++) {
            if (bitcast<u32>(kept.t[e]) == best) {
                atomicMin(&block_winner, kept.light[e]);
            }
        }
        workgroupBarrier();
        if (lane == 0u) {
            round_winner = atomicLoad(&block_winner);
            block_exact[j] = round_winner;
            atomicStore(&block_best, 0u);
            atomicStore(&block_winner, SAMPLE_NONE);
        }
        let winner = workgroupUniformLoad(&round_winner);
        for (var e = 0u; e < kept.n; e++) {
            if (kept.light[e] == winner) {
                kept.t[e] = 0.0;
            }
        }
        n = j + 1u;
    }
    return n;
}
#endif

@compute @workgroup_size(8, 8, 1)
fn candidates(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(workgroup_id) group: vec3<u32>,
) {
#if EXACT_PER_BLOCK
    // Before any invocation leaves: the choice takes the whole workgroup.
    let block_n = choose_block_exact(lane, group.xy);
#endif
    if (any(gid.xy >= frame.size)) {
        return;
    }
    let pixel = gid.y * frame.size.x + gid.x;
    let s = shadow_surface(gid.xy);
    if (!s.valid) {
        for (var j = 0u; j < SAMPLE_EXACT; j++) {
            light_samples[exact_word(pixel, j)] = SAMPLE_NONE;
        }
        for (var j = 0u; j < SAMPLE_COUNT; j++) {
            store_reservoir(0u, pixel, j, SAMPLE_NONE, 0.0, 0.0);
        }
        return;
    }
    seed_rng(pixel, 0u);
    let range = light_range(vec2<f32>(gid.xy) + 0.5, view_depth(s.position));

    // The exact lights: the SAMPLE_EXACT largest p̂ of the list (ties to the first). The
    // list is walked only when some are asked for.
    var exact: array<u32, EXACT_ARRAY>;
    var exact_t: array<f32, EXACT_ARRAY>;
    var n = 0u;
    var weakest = 0u;
#if EXACT_PER_BLOCK
    // The block's lights: traced where they reach this pixel; one that does not (p̂ = 0:
    // out of reach or behind the surface, which ray-cast shadows count hidden) is
    // hidden without a ray. All are left out of the sampling.
    for (var j = 0u; j < block_n; j++) {
        exact[j] = block_exact[j];
    }
    n = block_n;
    for (var j = 0u; j < SAMPLE_EXACT; j++) {
        var word = SAMPLE_NONE;
        if (j < n) {
            word = exact[j];
            if (!(sample_target(exact[j], s.position, s.ng) > 0.0) || hidden(s, exact[j])) {
                word |= SAMPLE_HIDDEN;
            }
        }
        light_samples[exact_word(pixel, j)] = word;
    }
#else
    let walked = select(0u, range.count, SAMPLE_EXACT > 0u);
    for (var k = 0u; k < walked; k++) {
        let i = light_at(range, k);
        let t = sample_target(i, s.position, s.ng);
        if (t <= 0.0) {
            continue;
        }
        if (n < SAMPLE_EXACT) {
            exact[n] = i;
            exact_t[n] = t;
            n += 1u;
        } else if (SAMPLE_EXACT > 0u && t > exact_t[weakest]) {
            exact[weakest] = i;
            exact_t[weakest] = t;
        } else {
            continue;
        }
        if (n == SAMPLE_EXACT) {
            for (var j = 0u; j < n; j++) {
                if (exact_t[j] < exact_t[weakest]) {
                    weakest = j;
                }
            }
        }
    }
    for (var j = 0u; j < SAMPLE_EXACT; j++) {
        var word = SAMPLE_NONE;
        if (j < n) {
            word = exact[j];
            if (hidden(s, exact[j])) {
                word |= SAMPLE_HIDDEN;
            }
        }
        light_samples[exact_word(pixel, j)] = word;
    }
#endif

    // The reservoirs over the rest of the list.
    let count = f32(range.count);
    for (var j = 0u; j < SAMPLE_COUNT; j++) {
        var wsum = 0.0;
        var chosen = SAMPLE_NONE;
        var chosen_t = 0.0;
        if (range.count > 0u) {
            for (var c = 0u; c < SAMPLE_CANDIDATES; c++) {
                let k = min(u32(rand() * count), range.count - 1u);
                let i = light_at(range, k);
                var t = sample_target(i, s.position, s.ng);
                for (var e = 0u; e < n; e++) {
                    if (exact[e] == i) {
                        t = 0.0;
                    }
                }
                let w = t * count;
                wsum += w;
                if (w > 0.0 && rand() * wsum < w) {
                    chosen = i;
                    chosen_t = t;
                }
            }
        }
        var weight = 0.0;
        if (chosen != SAMPLE_NONE) {
            weight = wsum / (f32(SAMPLE_CANDIDATES) * chosen_t);
#if TRACE_CANDIDATES
            if (hidden(s, chosen)) {
                weight = 0.0;
            }
#endif
        }
        store_reservoir(0u, pixel, j, chosen, weight, f32(SAMPLE_CANDIDATES));
    }
}

// p̂ of `light` at a pixel's surface, with that pixel's exact lights left out.
fn target_at(pixel: u32, s: ShadowSurface, light: u32) -> f32 {
    if (is_exact(pixel, light)) {
        return 0.0;
    }
    return sample_target(light, s.position, s.ng);
}

#if SAMPLE_TEMPORAL
fn surface_word(parity: u32, pixel: u32) -> u32 {
    let first = SAMPLE_HEADER_WORDS + sample_pixels() * SAMPLE_EXACT
        + SAMPLE_REGIONS * sample_pixels() * SAMPLE_COUNT * RESERVOIR_WORDS;
    return first + (parity * sample_pixels() + pixel) * 6u;
}

fn load_vec3(word: u32) -> vec3<f32> {
    return vec3<f32>(
        bitcast<f32>(light_samples[word]),
        bitcast<f32>(light_samples[word + 1u]),
        bitcast<f32>(light_samples[word + 2u]),
    );
}

fn store_vec3(word: u32, v: vec3<f32>) {
    light_samples[word] = bitcast<u32>(v.x);
    light_samples[word + 1u] = bitcast<u32>(v.y);
    light_samples[word + 2u] = bitcast<u32>(v.z);
}

// The previous frame's view-projection, kept in the header by `advance`.
fn previous_view_proj() -> mat4x4<f32> {
    var m: mat4x4<f32>;
    for (var c = 0u; c < 4u; c++) {
        for (var r = 0u; r < 4u; r++) {
            m[c][r] = bitcast<f32>(light_samples[4u + c * 4u + r]);
        }
    }
    return m;
}

// The pixel whose surface the previous frame saw this point at, or SAMPLE_NONE: the point
// projected with the previous view, kept where that pixel's position lies within 1% of
// the distance to the eye and its normal within about 25°.
fn previous_pixel(s: ShadowSurface, read: u32) -> u32 {
    let clip = previous_view_proj() * vec4<f32>(s.position, 1.0);
    if (!(clip.w > 0.0)) {
        return SAMPLE_NONE;
    }
    let ndc = clip.xy / clip.w;
    let size = vec2<f32>(frame.size);
    let at = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * size;
    if (any(at < vec2<f32>(0.0)) || any(at >= size)) {
        return SAMPLE_NONE;
    }
    let q = vec2<u32>(at);
    let qpixel = q.y * frame.size.x + q.x;
    let word = surface_word(read, qpixel);
    let position = load_vec3(word);
    let ng = load_vec3(word + 3u);
    let scale = max(length(s.position - frame.camera_pos.xyz), 1e-3);
    if (length(position - s.position) > 0.01 * scale || dot(ng, s.ng) < 0.9) {
        return SAMPLE_NONE;
    }
    return qpixel;
}

// Each reservoir resamples its own (from `candidates`) and the previous frame's at the
// reprojected pixel, whose M is capped at HISTORY_CAP, weighted p̂_here(y) W M and
// normalised by the M of both (1/M: exact where the two pixels' targets agree, as on a
// still camera; biased where they differ). The result, before its shadow ray, is kept as
// the next frame's history.
@compute @workgroup_size(8, 8, 1)
fn temporal(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (any(gid.xy >= frame.size)) {
        return;
    }
    let pixel = gid.y * frame.size.x + gid.x;
    let write = light_samples[0] % 2u;
    let read = 1u - write;
    let s = shadow_surface(gid.xy);
    let keep = surface_word(write, pixel);
    if (!s.valid) {
        store_vec3(keep, vec3<f32>(0.0));
        store_vec3(keep + 3u, vec3<f32>(0.0));
        for (var j = 0u; j < SAMPLE_COUNT; j++) {
            store_reservoir(HISTORY_REGION + write, pixel, j, SAMPLE_NONE, 0.0, 0.0);
        }
        return;
    }
    store_vec3(keep, s.position);
    store_vec3(keep + 3u, s.ng);
    seed_rng(pixel, 2u);
    let previous = previous_pixel(s, read);
    for (var j = 0u; j < SAMPLE_COUNT; j++) {
        let own = load_reservoir(0u, pixel, j);
        var wsum = 0.0;
        var m = own.m;
        var chosen = SAMPLE_NONE;
        var chosen_t = 0.0;
        if (own.light != SAMPLE_NONE) {
            chosen_t = target_at(pixel, s, own.light);
            wsum = chosen_t * own.w * own.m;
            if (wsum > 0.0) {
                chosen = own.light;
            }
        }
        if (previous != SAMPLE_NONE) {
            let past = load_reservoir(HISTORY_REGION + read, previous, j);
            let past_m = min(past.m, HISTORY_CAP);
            m += past_m;
            if (past.light != SAMPLE_NONE) {
                let t = target_at(pixel, s, past.light);
                let w = t * past.w * past_m;
                wsum += w;
                if (w > 0.0 && rand() * wsum < w) {
                    chosen = past.light;
                    chosen_t = t;
                }
            }
        }
        var weight = 0.0;
        if (chosen != SAMPLE_NONE) {
            weight = wsum / (m * chosen_t);
        }
        store_reservoir(HISTORY_REGION + write, pixel, j, chosen, weight, m);
#if TRACE_TEMPORAL
        if (chosen != SAMPLE_NONE && hidden(s, chosen)) {
            weight = 0.0;
        }
#endif
        store_reservoir(0u, pixel, j, chosen, weight, m);
    }
}
#endif

#if SAMPLE_SPATIAL

@compute @workgroup_size(8, 8, 1)
fn spatial(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (any(gid.xy >= frame.size)) {
        return;
    }
    let pixel = gid.y * frame.size.x + gid.x;
    let s = shadow_surface(gid.xy);
    if (!s.valid) {
        for (var j = 0u; j < SAMPLE_COUNT; j++) {
            store_reservoir(1u, pixel, j, SAMPLE_NONE, 0.0, 0.0);
        }
        return;
    }
    seed_rng(pixel, 1u);
    let depth = view_depth(s.position);
    for (var j = 0u; j < SAMPLE_COUNT; j++) {
        // This pixel's reservoir, then the neighbours' (pixel index and surface kept for Z).
        var taken: array<u32, SPATIAL_NEIGHBOURS + 1u>;
        var taken_s: array<ShadowSurface, SPATIAL_NEIGHBOURS + 1u>;
        taken[0] = pixel;
        taken_s[0] = s;
        var n = 1u;
        for (var q = 0u; q < SPATIAL_NEIGHBOURS; q++) {
            let angle = 6.2831853 * rand();
            let radius = f32(SPATIAL_RADIUS) * sqrt(rand());
            let at = vec2<f32>(gid.xy) + radius * vec2<f32>(cos(angle), sin(angle));
            let xy = vec2<i32>(round(at));
            if (any(xy < vec2<i32>(0)) || any(xy >= vec2<i32>(frame.size))) {
                continue;
            }
            let qxy = vec2<u32>(xy);
            let qpixel = qxy.y * frame.size.x + qxy.x;
            if (qpixel == pixel) {
                continue;
            }
            let qs = shadow_surface(qxy);
            if (!qs.valid || abs(view_depth(qs.position) - depth) > 0.1 * depth || dot(qs.ng, s.ng) < 0.9) {
                continue;
            }
            taken[n] = qpixel;
            taken_s[n] = qs;
            n += 1u;
        }
        var wsum = 0.0;
        var m = 0.0;
        var chosen = SAMPLE_NONE;
        var chosen_t = 0.0;
        for (var q = 0u; q < n; q++) {
            let r = load_reservoir(0u, taken[q], j);
            m += r.m;
            if (r.light == SAMPLE_NONE) {
                continue;
            }
            let t = target_at(pixel, s, r.light);
            let w = t * r.w * r.m;
            wsum += w;
            if (w > 0.0 && rand() * wsum < w) {
                chosen = r.light;
                chosen_t = t;
            }
        }
        var weight = 0.0;
        if (chosen != SAMPLE_NONE) {
#if SPATIAL_UNBIASED
            var z = 0.0;
            for (var q = 0u; q < n; q++) {
                if (q == 0u || target_at(taken[q], taken_s[q], chosen) > 0.0) {
                    z += load_reservoir(0u, taken[q], j).m;
                }
            }
#else
            let z = m;
#endif
            weight = wsum / (z * chosen_t);
            if (hidden(s, chosen)) {
                weight = 0.0;
            }
        }
        store_reservoir(1u, pixel, j, chosen, weight, m);
    }
}
#endif

@compute @workgroup_size(1, 1, 1)
fn advance() {
    light_samples[0] += 1u;
    for (var c = 0u; c < 4u; c++) {
        for (var r = 0u; r < 4u; r++) {
            light_samples[4u + c * 4u + r] = bitcast<u32>(frame.view_proj[c][r]);
        }
    }
}
