// Tiled light culling (Harada, McKee, Yang, "Forward+"): one workgroup per tile and list. The
// workgroup finds the tile's depth range as the min and max of the float bits (depths
// are non-negative, so their bits order like integers), tests every light against the
// tile's frustum, builds the list in workgroup memory in ascending light order, then
// reserves room in the shared pool with one global atomic.
// With COARSE > 1 a first dispatch (`coarse`) culls every light against coarse tiles of
// COARSE×COARSE tiles; each tile then tests only its coarse tile's lights. Reading every
// light in every tile is what bounds culling at high light counts (memory traffic).
// The coarse test is the same conservative test on a larger frustum and depth range,
// so the tiles' lists are exactly those without it.
// WIDE_STAGE (wide > 1): before it, the same code (WIDE_PASS) culls every light against
// wide tiles of WIDE×WIDE coarse tiles by their side planes alone (no depth read), and
// each coarse tile then tests only its wide tile's lights: the same coarse lists.
// MSAA: the depth is multisampled and every one of its SAMPLES samples bounds the tile.
// FLOAT_DEPTH: the depth is single-sample R32Float (a compute resolve's; the same values
// a depth texture holds), read as texture_2d<f32>. Not with MSAA. FLOAT_TRANSPARENT: the
// same for the transparent depth (rasterized in compute). TRANSPARENT_FAR: the farthest
// transparent depth (R32Float) ends a transparent range where nearer than the opaque.
// TRANSPARENT: lists for transparent surfaces (AMD's TiledLighting11 sample). A sample where a transparent
// surface lies in front of the opaque one contributes the range from the nearest
// transparent depth to the opaque depth (the far plane over the background): every
// visible transparent fragment lies in it. Samples without one contribute nothing.
// COMPACT: lists that never overflow (count → prefix sum → fill). `main` runs twice with
// the same pipeline, so both runs test every light with the same machine code:
// `compact.phase` 0 counts each list (entry count, depth range, block sums) and writes
// its first `compact.scratch` indices to the list's scratch slot; 1 fills the lists
// longer than their slot (the other workgroups return at once). Between them
// `scan_lists` (a workgroup per SCAN_BLOCK lists) points each list that fits its slot
// there, and prefix-sums the longer lists' counts into offsets in the pool after the
// slots. A list runs past the index array's end
// (`list_params.pool_indices`, the graph's max_indices) only when the long lists
// together want more than the pool: its count is cut to what fits, and the cut is counted.
// Every light's view-space bounds are found once a frame (`bounds`, the first dispatch):
// the tests of the coarse and fine tiles (tiles × lights of them) read a 16-byte sphere
// instead of transforming the light and finding its sphere again each time; the coarse
// stage loads each light's sphere a step ahead. (Loading the fine tiles' first batch
// before the depth range was measured slower on the H200: 0.123 against 0.117 ms.)
// SUBGROUPS (the device has wgpu's SUBGROUP): the tile's depth range by subgroup
// reductions, one barrier instead of two (naga 30 takes subgroup built-ins without an
// `enable subgroups;`, and refuses that directive).
// Defines: TILE (8, 16 or 32), CAPACITY, VARIANT (see types.wgsl), COARSE, COARSE_CAPACITY,
// WIDE, WIDE_CAPACITY, WIDE_STAGE, WIDE_PASS, SAMPLES, MSAA, FLOAT_DEPTH, TRANSPARENT,
// TRANSPARENT_FAR, COMPACT, SCAN_BLOCK.

#include "common/types.wgsl"
#include "common/view_space.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> light_geometry: array<LightGeometry>;
#if MSAA
@group(0) @binding(2) var depth: texture_depth_multisampled_2d;
#else
#if FLOAT_DEPTH
@group(0) @binding(2) var depth: texture_2d<f32>;
#else
@group(0) @binding(2) var depth: texture_depth_2d;
#endif
#endif
@group(0) @binding(3) var<storage, read_write> light_lists: array<atomic<u32>>;
@group(0) @binding(4) var<uniform> list_params: ListParams;
// Per coarse tile: its light count, then up to COARSE_CAPACITY light indices ascending.
// A count over the capacity sends its tiles back to testing every light.
@group(0) @binding(5) var<storage, read_write> coarse_lists: array<u32>;
#if WIDE_STAGE
// Per wide tile (WIDE × WIDE coarse tiles): its light count, then up to WIDE_CAPACITY
// light indices ascending, the candidates of its coarse tiles (WIDE_PASS writes them).
// A count over the capacity sends its coarse tiles back to testing every light.
@group(0) @binding(11) var<storage, read_write> wide_lists: array<u32>;
const WIDE_STRIDE: u32 = WIDE_CAPACITY + 1u;
var<workgroup> wide_count: u32;
// A coarse workgroup's wide list (its first word) and whether it holds the candidates.
var<private> wide_base: u32;
var<private> from_wide: bool;
#endif
#if TRANSPARENT
#if MSAA
@group(0) @binding(6) var transparent_depth: texture_depth_multisampled_2d;
#else
#if FLOAT_TRANSPARENT
@group(0) @binding(6) var transparent_depth: texture_2d<f32>;
#else
@group(0) @binding(6) var transparent_depth: texture_depth_2d;
#endif
#endif
#endif
#if TRANSPARENT_FAR
// The farthest transparent depth (R32Float): the range's far end where nearer than d.
@group(0) @binding(10) var transparent_far: texture_2d<f32>;
#endif
// What the tile tests need of the lights, in view space (`bounds` writes it, the tests
// read it), four arrays of `capacity` = arrayLength / 4 vec4s:
//   [i]               the bounding sphere of light i's volume (its range sphere, or for a
//                     spot the tighter sphere around its cone and cap), the radius with
//                     the tests' float slack and negated for a spot;
//   [capacity + i]    the same sphere for the coarse stage, widened by COARSE_REACH of
//                     its distance;
//   [2 capacity + 2i] a spot's position and range, [.. + 1] its direction and cos_outer.
// Hot and cold apart: the tests read 16 bytes a light, a spot's cone 32 more.
@group(0) @binding(9) var<storage, read_write> light_bounds: array<vec4<f32>>;

fn bounds_capacity() -> u32 {
    return arrayLength(&light_bounds) / 4u;
}

#if COMPACT
// Per scan block of SCAN_BLOCK lists: the sum of the counts of its lists longer than
// their scratch slot and whether the sum wrapped past u32.
@group(0) @binding(7) var<storage, read_write> list_block_sums: array<atomic<u32>>;
@group(0) @binding(8) var<uniform> compact: CompactParams;

struct CompactParams {
    // 0 count, 1 fill.
    phase: u32,
    // Light indices of each list's scratch slot (`ListLayout::scratch_per_list`): slot l
    // is words l·scratch.. of the index array; the pool follows all slots.
    scratch: u32,
    _pad0: u32,
    _pad1: u32,
};
#endif

// The coarse stage's workgroup: TILE × TILE invocations up to 16 × 16 (the most every
// device runs), each folding COARSE_FOLD × COARSE_FOLD pixels of its coarse tile.
const COARSE_SIDE: u32 = min(TILE, 16u);
const COARSE_FOLD: u32 = TILE / COARSE_SIDE * COARSE;
const THREADS: u32 = COARSE_SIDE * COARSE_SIDE;
// The tiles' pass (`main`) folds MAIN_STEP × MAIN_STEP pixels an invocation, so a tile
// is a workgroup of MAIN_THREADS: more tiles fit an SM at once, and a tile's chain of
// dependent steps (depth, range, candidates, hits, list) overlaps more of the others'.
const MAIN_STEP: u32 = 2u;
const MAIN_SIDE: u32 = TILE / MAIN_STEP;
const MAIN_THREADS: u32 = MAIN_SIDE * MAIN_SIDE;
// Words of a batch's hit bits: one bit a `main` invocation.
const MASK_WORDS: u32 = (MAIN_THREADS + 31u) / 32u;
const FAR_BITS: u32 = 0x7f7fffffu;

#if SUBGROUPS
// The tile's (min, max) view-depth bits, the min kept inverted so that zero (workgroup
// memory starts zeroed) holds nothing (see `workgroup_depth_range`).
var<workgroup> depth_inverted_min: atomic<u32>;
var<workgroup> depth_max: atomic<u32>;
#else
// Per invocation, then per column of invocations: (min, max) view-depth bits (see
// `workgroup_depth_range`).
var<workgroup> depth_partial: array<vec2<u32>, THREADS>;
#endif
var<workgroup> depth_mask: atomic<u32>;
// Hit bits of a batch of candidates, two sets: a batch clears the next batch's set while
// it reads its own, so a batch needs two barriers, not three.
var<workgroup> hits: array<array<atomic<u32>, MASK_WORDS>, 2>;
var<workgroup> coarse_count: u32;
// The coarse stage's hit bits for a chunk of COARSE_CHUNK lights (8 KB).
const COARSE_CHUNK_WORDS: u32 = 2048u;
const COARSE_CHUNK: u32 = COARSE_CHUNK_WORDS * 32u;
const COARSE_WORDS_PER_THREAD: u32 = COARSE_CHUNK_WORDS / THREADS;
var<workgroup> coarse_hits: array<atomic<u32>, COARSE_CHUNK_WORDS>;
#if COMPACT
// The fill's list entry: (offset, kept count), and the light after its slot's last.
var<workgroup> fill_entry: vec2<u32>;
var<workgroup> fill_below: u32;
const PHASE_FILL: u32 = 1u;
#else
var<workgroup> list: array<u32, CAPACITY>;
var<workgroup> pool_base: u32;
#endif

const COARSE_STRIDE: u32 = COARSE_CAPACITY + 1u;
// 1e-4 of the distance: a thousand times the rounding it covers, and still far below
// a tile's width at any distance (a 64-pixel coarse tile spans ~5e-2 of it at 60°).
const COARSE_REACH: f32 = 1e-4;

#include "cull/tile_depth.wgsl"

@compute @workgroup_size(MAIN_SIDE, MAIN_SIDE, 1)
fn main(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(local_invocation_id) lid: vec3<u32>,
) {
    let list_index = (group.y * list_params.tiles_x + group.x) * list_params.lists_per_tile + group.z;
#if COMPACT
    // Where the hits go: counting, the first `scratch` to the list's scratch slot;
    // filling, the `kept` the scan gave the list, from its offset.
    let filling = compact.phase == PHASE_FILL;
    var start = list_index * compact.scratch;
    var kept = compact.scratch;
    if (filling) {
        if (local == 0u) {
            let e = HEADER_WORDS + ENTRY_WORDS * list_index;
            fill_entry = vec2<u32>(atomicLoad(&light_lists[e]), atomicLoad(&light_lists[e + 1u]));
        }
        let entry = workgroupUniformLoad(&fill_entry);
        start = entry.x;
        kept = entry.y;
        // A list in its scratch slot is whole since the count; an empty one, or one
        // with no room left under the bound, has nothing to place.
        if (kept == 0u || start < compact.scratch * list_count()) {
            return;
        }
    }
    let offset = list_params.pool_offset + start;
#endif
    // Ordered before their first use by the depth range's barriers. The coarse tile's
    // count is read now, so the read overlaps the depth's instead of following it.
    let coarse_x = (list_params.tiles_x + COARSE - 1u) / COARSE;
    let coarse_base = ((group.y / COARSE) * coarse_x + group.x / COARSE) * COARSE_STRIDE;
    if (local == 0u) {
        atomicStore(&depth_mask, 0u);
        if (COARSE > 1u) {
            coarse_count = coarse_lists[coarse_base];
        }
    }
    if (local < MASK_WORDS) {
        atomicStore(&hits[0][local], 0u);
    }

    // 1. The tile's depth range, over the samples that hold geometry.
    let pixel = group.xy * TILE + lid.xy * MAIN_STEP;
    let range = workgroup_depth_range(local, MAIN_SIDE, block_depth_range(pixel, MAIN_STEP));
    let tile_min = bitcast<f32>(range.x);
    let tile_max = bitcast<f32>(range.y);
    let empty_tile = range.y == 0u;

    // 2. This list's depth range.
    var lo = tile_min;
    var hi = tile_max;
    if (VARIANT == VARIANT_HALF_Z) {
        let mid = 0.5 * (tile_min + tile_max);
        if (group.z == 0u) { hi = mid; } else { lo = mid; }
    } else if (VARIANT == VARIANT_CLUSTERED) {
        lo = max(lo, slice_bound(group.z, list_params.lists_per_tile));
        hi = min(hi, slice_bound(group.z + 1u, list_params.lists_per_tile));
        // The last slice reaches to the far plane and beyond (clamped in shading).
        if (group.z + 1u == list_params.lists_per_tile) { hi = tile_max; }
        if (group.z == 0u) { lo = tile_min; }
    }
    let empty = empty_tile || lo > hi;

    // 3. Side planes and bounding sphere of the tile's frustum slice, and (DepthMask)
    //    the cells of the tile's depth range its samples occupy.
    let bounds = tile_bounds(group.xy * TILE, TILE, lo, hi, empty);
    var tile_mask = 0u;
    if (VARIANT == VARIANT_DEPTH_MASK) {
        if (!empty_tile) {
            for (var dy = 0u; dy < MAIN_STEP; dy++) {
                for (var dx = 0u; dx < MAIN_STEP; dx++) {
                    add_depth_cells(pixel + vec2<u32>(dx, dy), tile_min, tile_max);
                }
            }
        }
        workgroupBarrier();
        tile_mask = atomicLoad(&depth_mask);
    }

    // 4. Candidates: the coarse tile's lights, or every light. In batches of MAIN_THREADS;
    //    ranks within a batch from a bit mask keep the list in ascending light order.
    var count = frame.light_count;
    var from_coarse = false;
    if (COARSE > 1u) {
        let n = workgroupUniformLoad(&coarse_count);
        if (n <= COARSE_CAPACITY) {
            count = n;
            from_coarse = true;
        }
    }
    var total = 0u;
    // Candidates from `first` on; lights below `below` are not tested.
    var first = 0u;
    var below = 0u;
#if COMPACT
    if (filling && compact.scratch > 0u) {
        // A pooled list's first `scratch` lights are in its slot since the count: copied,
        // and only the candidates after the last of them are tested again. Candidates
        // ascend, so the first `scratch` of them (of all lights: `below`) come no later.
        let slot_word = list_params.pool_offset + list_index * compact.scratch;
        for (var k = local; k < min(compact.scratch, kept); k += MAIN_THREADS) {
            atomicStore(&light_lists[offset + k], atomicLoad(&light_lists[slot_word + k]));
        }
        if (local == 0u) {
            fill_below = atomicLoad(&light_lists[slot_word + compact.scratch - 1u]) + 1u;
        }
        below = workgroupUniformLoad(&fill_below);
        total = compact.scratch;
        first = select(below, compact.scratch, from_coarse);
    }
#endif
    var h = 0u;
    for (var base = first; base < count; base += MAIN_THREADS) {
        let k = base + local;
        var i = k;
        var hit = false;
        if (!empty && k < count) {
            i = candidate(from_coarse, coarse_base, k);
            hit = i >= below && light_touches_tile(i, light_sphere(i, false), bounds, lo, hi, tile_mask, tile_min, tile_max, 0.0);
        }
        if (hit) {
            atomicOr(&hits[h][local / 32u], 1u << (local % 32u));
        }
        workgroupBarrier();
        let slot = total + rank_in_batch(h, local);
#if COMPACT
        if (hit && slot < kept) {
            atomicStore(&light_lists[offset + slot], i);
        }
#else
        if (hit && slot < CAPACITY) {
            list[slot] = i;
        }
#endif
        total += close_batch(h, local, base + MAIN_THREADS < count);
        h = 1u - h;
    }

#if COMPACT
    // 5. Counting: publish the count and depth range; a list longer than its scratch
    //    slot adds its count to its scan block's (it takes room in the pool). Filling:
    //    check that the count found now gives the kept count the scan wrote from the
    //    first run's count.
    if (local == 0u) {
        let e = HEADER_WORDS + ENTRY_WORDS * list_index;
        if (filling) {
            if (min(total, list_params.pool_indices - start) != kept) {
                atomicAdd(&light_lists[3], 1u);
            }
        } else {
            atomicStore(&light_lists[e + 1u], total);
            atomicStore(&light_lists[e + 2u], bitcast<u32>(select(lo, 0.0, empty)));
            atomicStore(&light_lists[e + 3u], bitcast<u32>(select(hi, 0.0, empty)));
            atomicMax(&light_lists[2], total);
            if (total > compact.scratch) {
                let b = 2u * (list_index / SCAN_BLOCK);
                let before = atomicAdd(&list_block_sums[b], total);
                if (before + total < before) {
                    atomicStore(&list_block_sums[b + 1u], 1u);
                }
            }
        }
    }
#else
    // 5. Reserve room in the pool, publish the entry, copy the list out.
    let kept = min(total, CAPACITY);
    if (local == 0u) {
        pool_base = atomicAdd(&light_lists[0], kept);
        if (total > CAPACITY) {
            atomicAdd(&light_lists[1], 1u);
        }
        atomicMax(&light_lists[2], total);
        let e = HEADER_WORDS + ENTRY_WORDS * list_index;
        atomicStore(&light_lists[e], pool_base);
        atomicStore(&light_lists[e + 1u], kept);
        atomicStore(&light_lists[e + 2u], bitcast<u32>(select(lo, 0.0, empty)));
        atomicStore(&light_lists[e + 3u], bitcast<u32>(select(hi, 0.0, empty)));
    }
    workgroupBarrier();
    let base_word = list_params.pool_offset + workgroupUniformLoad(&pool_base);
    for (var k = local; k < kept; k += MAIN_THREADS) {
        atomicStore(&light_lists[base_word + k], list[k]);
    }
#endif
}

// Candidate k of a tile: entry k of its coarse tile's list, or light k.
fn candidate(from_coarse: bool, coarse_base: u32, k: u32) -> u32 {
    if (from_coarse) {
        return coarse_lists[coarse_base + 1u + k];
    }
    return k;
}

// Side planes through the eye and a (coarse) tile's edges, normals pointing inwards, and
// the bounding sphere of its frustum slice [lo, hi] (for the cone test).
struct TileBounds {
    planes: array<vec3<f32>, 4>,
    center: vec3<f32>,
    radius: f32,
}

fn tile_bounds(origin: vec2<u32>, span: u32, lo: f32, hi: f32, empty: bool) -> TileBounds {
    let size = vec2<f32>(frame.size);
    let x0 = f32(origin.x);
    let y0 = f32(origin.y);
    let x1 = min(x0 + f32(span), size.x);
    let y1 = min(y0 + f32(span), size.y);
    let c00 = view_ray(vec2<f32>(x0, y0));
    let c10 = view_ray(vec2<f32>(x1, y0));
    let c11 = view_ray(vec2<f32>(x1, y1));
    let c01 = view_ray(vec2<f32>(x0, y1));
    var b: TileBounds;
    b.planes = array<vec3<f32>, 4>(
        normalize(cross(c00, c10)),
        normalize(cross(c10, c11)),
        normalize(cross(c11, c01)),
        normalize(cross(c01, c00)),
    );
    b.center = vec3<f32>(0.0);
    b.radius = 0.0;
    if (!empty) {
        var corners: array<vec3<f32>, 8>;
        let rays = array<vec3<f32>, 4>(c00, c10, c11, c01);
        for (var i = 0u; i < 4u; i++) {
            corners[i] = rays[i] * (lo / -rays[i].z);
            corners[i + 4u] = rays[i] * (hi / -rays[i].z);
            b.center += corners[i] + corners[i + 4u];
        }
        b.center /= 8.0;
        for (var i = 0u; i < 8u; i++) {
            b.radius = max(b.radius, distance(b.center, corners[i]));
        }
    }
    return b;
}

// How many lights before this invocation's in the batch hit (its place in the list);
// `h` is the batch's set of hit bits.
fn rank_in_batch(h: u32, local: u32) -> u32 {
    var rank = 0u;
    let word = local / 32u;
    for (var w = 0u; w < word; w++) {
        rank += countOneBits(atomicLoad(&hits[h][w]));
    }
    return rank + countOneBits(atomicLoad(&hits[h][word]) & ((1u << (local % 32u)) - 1u));
}

// Ends a batch of hit set `h`: its hit count. Clears the next batch's set (last read
// before the previous barrier) and, when another batch follows (`more`, uniform), waits
// for every invocation to be done with this one's; after the last batch nothing reads or
// clears the sets again.
fn close_batch(h: u32, local: u32, more: bool) -> u32 {
    let n = hits_in_batch(h);
    if (local < MASK_WORDS) {
        atomicStore(&hits[1u - h][local], 0u);
    }
    if (more) {
        workgroupBarrier();
    }
    return n;
}

fn hits_in_batch(h: u32) -> u32 {
    var n = 0u;
    for (var w = 0u; w < MASK_WORDS; w++) {
        n += countOneBits(atomicLoad(&hits[h][w]));
    }
    return n;
}

// Light i's view-space bounds (see light_bounds), once a frame, one invocation a light;
// the grid folds into y past 65,535 workgroups.
@compute @workgroup_size(64, 1, 1)
fn bounds(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.y * groups.x * 64u + id.x;
    let capacity = bounds_capacity();
    if (i >= frame.light_count || i >= capacity) {
        return;
    }
    let g = light_geometry[i];
    let pos = (frame.view * vec4<f32>(g.position, 1.0)).xyz;
    let dir = (frame.view * vec4<f32>(g.direction, 0.0)).xyz;
    let is_spot = g.cos_outer > -1.0;
    var center = pos;
    var radius = g.range;
    if (is_spot) {
        let c = max(g.cos_outer, 0.0);
        let s = sqrt(max(1.0 - c * c, 0.0));
        if (c < 0.70710678) {
            center = pos + dir * (g.range * c);
            radius = g.range * s;
        } else {
            radius = g.range / (2.0 * c);
            center = pos + dir * radius;
        }
    }
    // Float slack so rounding never culls a light that touches the boundary.
    let fine = radius * 1.0001 + 1e-5;
    let coarse = fine + COARSE_REACH * length(center);
    light_bounds[i] = vec4<f32>(center, select(fine, -fine, is_spot));
    light_bounds[capacity + i] = vec4<f32>(center, select(coarse, -coarse, is_spot));
    light_bounds[2u * capacity + 2u * i] = vec4<f32>(pos, g.range);
    light_bounds[2u * capacity + 2u * i + 1u] = vec4<f32>(dir, g.cos_outer);
}

// Light i's sphere for the fine tiles (coarse false) or the coarse stage.
fn light_sphere(i: u32, coarse: bool) -> vec4<f32> {
    return light_bounds[select(i, bounds_capacity() + i, coarse)];
}

// Conservative: a light that reaches any point of the tile between lo and hi is kept.
// `sphere` is light i's (light_sphere). `reach` widens the tile's sphere for the cone
// test by that fraction of its distance from the eye (the light's sphere is widened in
// `bounds`): the coarse stage's planes are the same planes as its tiles' edges, but
// computed from other corners, so they round differently (about 1e-7 of the distance).
fn light_touches_tile(
    i: u32,
    sphere: vec4<f32>,
    bounds: TileBounds,
    lo: f32,
    hi: f32,
    tile_mask: u32,
    tile_min: f32,
    tile_max: f32,
    reach: f32,
) -> bool {
    let center = sphere.xyz;
    let radius = abs(sphere.w);
    let z = -center.z;
    if (z + radius < lo || z - radius > hi) {
        return false;
    }
    for (var p = 0u; p < 4u; p++) {
        if (dot(bounds.planes[p], center) < -radius) {
            return false;
        }
    }
    if (VARIANT == VARIANT_DEPTH_MASK) {
        let a = cell_of(z - radius, tile_min, tile_max);
        let b = cell_of(z + radius, tile_min, tile_max);
        if ((cells_between(a, b) & tile_mask) == 0u) {
            return false;
        }
    }
    if (sphere.w < 0.0) {
        // Cone against the tile's bounding sphere.
        let cone = 2u * bounds_capacity() + 2u * i;
        let pos_range = light_bounds[cone];
        let dir_cos = light_bounds[cone + 1u];
        let c = dir_cos.w;
        let v = bounds.center - pos_range.xyz;
        let v_len_sq = dot(v, v);
        let v1 = dot(v, dir_cos.xyz);
        let s = sqrt(max(1.0 - c * c, 0.0));
        let closest = c * sqrt(max(v_len_sq - v1 * v1, 0.0)) - v1 * s;
        let r = bounds.radius * 1.0001 + 1e-5 + reach * length(bounds.center);
        if (closest > r || v1 > r + pos_range.w || v1 < -r) {
            return false;
        }
    }
    return true;
}

#include "cull/coarse_stage.wgsl"
#include "cull/list_scan.wgsl"
