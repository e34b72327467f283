// Ray-cast shadow jobs (Leo demo, tiled ray-cast shadows): one invocation per pixel walks
// its light list and, for every shadow-casting light that reaches and faces it, emits a
// job (pixel, light, caster number). Jobs are compacted per workgroup: a prefix sum and
// one atomic add per workgroup reserve its range of the job buffer. Within that range the
// jobs are sorted by their light's position in the list (a counting sort through
// workgroup atomics), so the casting pass's neighbouring threads trace rays from
// neighbouring pixels to the same light: coherent rays. (Their order within one light is
// the atomics' order; the mask, ORed, does not depend on it.) Casters behind the surface
// are hidden without a ray: their mask bit is set here, which also clears every pixel's
// mask for the frame. `finalize` then writes the casting pass's indirect dispatch.
//
// Job buffer (src/kinds/shadow_ray_jobs/rules.rs, ShadowJobLayout): words 0..4 jobs wanted,
// jobs dropped (buffer full), pixels with more than 128 casters, unused; 4..8 the
// indirect dispatch (x, y, z, unused); then two words a job.
// Surfaces come from the G-buffer (g_position, g_geometric) or, with VISIBILITY_IDS, from
// a visibility buffer's triangle ids, rebuilt by visibility/surface.wgsl as visibility
// shading rebuilds them.
// With SHADOW_ATLAS_LIGHTS (a ShadowAtlas pass's view table in the pass's reads), lights
// with a map this frame get no job and no bit: the shading samples the atlas for them.
// They keep their caster numbers, so every other light's bit is where it is without
// the atlas.
// Defines: TILE-free; JOB_CAPACITY, LIGHT_LISTS, SHADOW_NORMAL_OFFSET, VISIBILITY_IDS,
// SHADOW_ATLAS_LIGHTS.

#include "common/types.wgsl"
#include "common/lighting.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
// LIGHT_LISTS is always set: tile lists.
#include "common/light_inputs.wgsl"
@group(0) @binding(7) var<storage, read_write> shadow_jobs: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> shadow_mask: array<u32>;
#if SHADOW_ATLAS_LIGHTS
@group(0) @binding(9) var<storage, read> shadow_views: array<vec4<f32>>;
#endif

#include "common/shadows.wgsl"
#include "shadow/surface_source.wgsl"

const GROUP_SIZE: u32 = 256u;
// Workgroups a dispatch dimension may have (WebGPU's limit).
const MAX_GROUPS_X: u32 = 65535u;

var<workgroup> scan: array<u32, 256>;
var<workgroup> group_base: u32;
// Jobs per list position (positions past the last share the last bucket), then the next
// free slot of each within the workgroup's range.
const BUCKETS: u32 = 256u;
var<workgroup> bucket_count: array<atomic<u32>, 256>;
var<workgroup> bucket_next: array<atomic<u32>, 256>;

struct Pixel {
    valid: bool,
    index: u32,
    position: vec3<f32>,
    ng: vec3<f32>,
    range: LightRange,
};

fn load_pixel(xy: vec2<u32>) -> Pixel {
    var px: Pixel;
    px.valid = all(xy < frame.size);
    if (!px.valid) {
        return px;
    }
    let s = shadow_surface(xy);
    px.valid = s.valid;
    px.index = xy.y * frame.size.x + xy.x;
    px.position = s.position;
    px.ng = s.ng;
    let view_z = -(frame.view * vec4<f32>(s.position, 1.0)).z;
    px.range = light_range(vec2<f32>(xy) + 0.5, view_z);
    return px;
}

// A set of 256 bits (list positions below BUCKETS): bit k in word k / 32, words 0-3 in
// lo and 4-7 in hi. Vectors updated by selects: a private array indexed at run time
// would live in local memory.
struct Bits256 {
    lo: vec4<u32>,
    hi: vec4<u32>,
};

const LANES: vec4<u32> = vec4<u32>(0u, 1u, 2u, 3u);

fn bits_set(b: Bits256, k: u32) -> Bits256 {
    let bit = vec4<u32>(1u << (k % 32u));
    let w = vec4<u32>(k / 32u);
    return Bits256(b.lo | select(vec4<u32>(0u), bit, LANES == w), b.hi | select(vec4<u32>(0u), bit, LANES + 4u == w));
}

fn bits_word(b: Bits256, w: u32) -> u32 {
    let v = select(b.lo, b.hi, w >= 4u);
    let j = w % 4u;
    return select(select(v.x, v.y, j == 1u), select(v.z, v.w, j == 3u), j >= 2u);
}

// What the counting walk found, so that the emitting pass writes the pixel's jobs
// without walking its list again: the list positions that emit a job and those that
// take a caster number, the mask bits of the casters behind the surface, the caster
// count, and whether every job's position lies below BUCKETS (else the emitting pass
// walks the list again).
struct Walked {
    jobs: Bits256,
    numbered: Bits256,
    hidden: vec4<u32>,
    casters: u32,
    complete: bool,
};

// Walks the pixel's casters. Without `emit`, counts its jobs into their buckets and
// returns what emit_walked needs; with it, writes each job at its bucket's next slot
// (those past JOB_CAPACITY are dropped, counted by the caller) and the pixel's mask.
fn walk(px: Pixel, emit: bool) -> Walked {
    var w: Walked;
    w.complete = true;
    var caster = 0u;
    for (var k = 0u; k < px.range.count; k++) {
        let i = light_at(px.range, k);
        // The list ascends: no caster past the last one (a scene's unshadowed crowd
        // listed after its casters costs nothing here).
        if (i >= frame.caster_end) {
            break;
        }
        let props = light_properties[i];
        if ((props.flags & LIGHT_CASTS_SHADOW) == 0u) {
            continue;
        }
        let g = light_geometry[i];
        let inc = incident_light(g, props, px.position);
        if (!any(inc.radiance > vec3<f32>(0.0))) {
            continue;
        }
#if SHADOW_ATLAS_LIGHTS
        let rays = shadow_atlas_entry(i) == 0u;
#else
        let rays = true;
#endif
        if (caster < SHADOW_MAX_CASTERS && rays) {
            if (shadow_faces(px.position, px.ng, g.position)) {
                let bucket = min(k, BUCKETS - 1u);
                if (emit) {
                    let slot = group_base + atomicAdd(&bucket_next[bucket], 1u);
                    if (slot < JOB_CAPACITY) {
                        atomicStore(&shadow_jobs[JOB_HEADER_WORDS + JOB_WORDS * slot], px.index);
                        atomicStore(&shadow_jobs[JOB_HEADER_WORDS + JOB_WORDS * slot + 1u], i | (caster << 24u));
                    }
                } else {
                    atomicAdd(&bucket_count[bucket], 1u);
                    if (k < BUCKETS) {
                        w.jobs = bits_set(w.jobs, k);
                    } else {
                        w.complete = false;
                    }
                }
            } else {
                w.hidden |= select(vec4<u32>(0u), vec4<u32>(1u << (caster % 32u)), LANES == vec4<u32>(caster / 32u));
            }
        }
        if (k < BUCKETS) {
            w.numbered = bits_set(w.numbered, k);
        }
        caster += 1u;
    }
    w.casters = caster;
    if (emit) {
        write_mask(px, w);
    }
    return w;
}

// The pixel's hidden casters, and whether it had more than its mask holds.
fn write_mask(px: Pixel, w: Walked) {
    for (var m = 0u; m < SHADOW_MASK_WORDS; m++) {
        shadow_mask[px.index * SHADOW_MASK_WORDS + m] = w.hidden[m];
    }
    if (w.casters > SHADOW_MAX_CASTERS) {
        atomicAdd(&shadow_jobs[2], 1u);
    }
}

// The jobs the counting walk found, written as walk(px, true) writes them: in list
// order, each at its position's bucket, its caster number the count of numbered
// positions before it. Reads one list entry a job instead of every light's data: the
// chairs' jobs at 1280x720 took 0.252 against 0.279 ms walking again, chairs_300k's at
// 1920x1080 0.498 against 0.550 ms (NVIDIA H100 80GB HBM3, two interleaved rounds).
fn emit_walked(px: Pixel, w: Walked) {
    var before = 0u;
    for (var word = 0u; word < BUCKETS / 32u; word++) {
        let numbered = bits_word(w.numbered, word);
        var jobs = bits_word(w.jobs, word);
        while (jobs != 0u) {
            let b = firstTrailingBit(jobs);
            jobs &= jobs - 1u;
            let k = word * 32u + b;
            let caster = before + countOneBits(numbered & ((1u << b) - 1u));
            let i = light_at(px.range, k);
            let slot = group_base + atomicAdd(&bucket_next[k], 1u);
            if (slot < JOB_CAPACITY) {
                atomicStore(&shadow_jobs[JOB_HEADER_WORDS + JOB_WORDS * slot], px.index);
                atomicStore(&shadow_jobs[JOB_HEADER_WORDS + JOB_WORDS * slot + 1u], i | (caster << 24u));
            }
        }
        before += countOneBits(numbered);
    }
    write_mask(px, w);
}

@compute @workgroup_size(16, 16, 1)
fn main(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    atomicStore(&bucket_count[local], 0u);
    workgroupBarrier();
    let px = load_pixel(id.xy);
    var walked: Walked;
    if (px.valid) {
        // The surface every ray of this pixel starts from (shadow_ray_cast.wgsl).
        let at = JOB_HEADER_WORDS + JOB_WORDS * JOB_CAPACITY + JOB_SURFACE_WORDS * px.index;
        let words = array<u32, 6>(bitcast<u32>(px.position.x), bitcast<u32>(px.position.y), bitcast<u32>(px.position.z), bitcast<u32>(px.ng.x), bitcast<u32>(px.ng.y), bitcast<u32>(px.ng.z));
        for (var w = 0u; w < JOB_SURFACE_WORDS; w++) {
            atomicStore(&shadow_jobs[at + w], words[w]);
        }
        walked = walk(px, false);
    } else if (all(id.xy < frame.size)) {
        let base = (id.y * frame.size.x + id.x) * SHADOW_MASK_WORDS;
        for (var w = 0u; w < SHADOW_MASK_WORDS; w++) {
            shadow_mask[base + w] = 0u;
        }
    }
    workgroupBarrier();
    // Inclusive prefix sum of the bucket counts (Hillis-Steele), one bucket a thread.
    let count = atomicLoad(&bucket_count[local]);
    scan[local] = count;
    workgroupBarrier();
    for (var step = 1u; step < GROUP_SIZE; step *= 2u) {
        var add = 0u;
        if (local >= step) {
            add = scan[local - step];
        }
        workgroupBarrier();
        scan[local] += add;
        workgroupBarrier();
    }
    atomicStore(&bucket_next[local], scan[local] - count);
    if (local == GROUP_SIZE - 1u) {
        let total = scan[local];
        let base = atomicAdd(&shadow_jobs[0], total);
        group_base = base;
        let end = base + total;
        if (end > JOB_CAPACITY) {
            atomicAdd(&shadow_jobs[1], end - max(base, JOB_CAPACITY));
        }
    }
    workgroupBarrier();
    if (px.valid) {
        if (walked.complete) {
            emit_walked(px, walked);
        } else {
            _ = walk(px, true);
        }
    }
}

// The casting pass's indirect dispatch: SHADOW_CAST_GROUP jobs a workgroup, in rows of MAX_GROUPS_X.
@compute @workgroup_size(1, 1, 1)
fn finalize() {
    let jobs = min(atomicLoad(&shadow_jobs[0]), JOB_CAPACITY);
    let groups = (jobs + SHADOW_CAST_GROUP - 1u) / SHADOW_CAST_GROUP;
    let x = min(groups, MAX_GROUPS_X);
    let y = select(0u, (groups + MAX_GROUPS_X - 1u) / MAX_GROUPS_X, groups > 0u);
    atomicStore(&shadow_jobs[4], x);
    atomicStore(&shadow_jobs[5], y);
    atomicStore(&shadow_jobs[6], 1u);
}
