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

// The view-depth range sample `s` of a pixel adds to its tile (for a single-sample
// depth, `s` is the mip level 0), or (-1, -1) where it holds nothing to light.
fn sample_range(pixel: vec2<u32>, s: u32) -> vec2<f32> {
    let none = vec2<f32>(-1.0);
    if (any(pixel >= frame.size)) {
        return none;
    }
#if FLOAT_DEPTH
    let d = textureLoad(depth, pixel, s).x;
#else
    let d = textureLoad(depth, pixel, s);
#endif
#if TRANSPARENT
#if FLOAT_TRANSPARENT
    let t = textureLoad(transparent_depth, pixel, s).x;
#else
    let t = textureLoad(transparent_depth, pixel, s);
#endif
    // No transparent surface here, or every one is behind the opaque surface.
    if (t >= 1.0 || t > d) {
        return none;
    }
#if TRANSPARENT_FAR
    // Every transparent surface here lies within [t, far]; those behind d are hidden.
    let far = max(textureLoad(transparent_far, pixel, 0).x, t);
    return vec2<f32>(view_depth(t), view_depth(min(far, d)));
#else
    return vec2<f32>(view_depth(t), view_depth(d));
#endif
#else
    if (d >= 1.0) {
        return none;
    }
    let z = view_depth(d);
    return vec2<f32>(z, z);
#endif
}

// Folds every sample of a pixel into `acc`: the (min, max) float bits of the view
// depths of the samples that hold geometry. Depths are non-negative, so their bits order
// like integers; (FAR_BITS, 0) holds nothing.
fn add_depth_sample(acc: vec2<u32>, pixel: vec2<u32>) -> vec2<u32> {
    var a = acc;
    for (var s = 0u; s < SAMPLES; s++) {
        let r = sample_range(pixel, s);
        if (r.x >= 0.0) {
            a = vec2<u32>(min(a.x, bitcast<u32>(r.x)), max(a.y, bitcast<u32>(r.y)));
        }
    }
    return a;
}

// The (min, max) bits (add_depth_sample) of the step × step pixels from `corner`.
fn block_depth_range(corner: vec2<u32>, step: u32) -> vec2<u32> {
    var acc = vec2<u32>(FAR_BITS, 0u);
    for (var dy = 0u; dy < step; dy++) {
        for (var dx = 0u; dx < step; dx++) {
            acc = add_depth_sample(acc, corner + vec2<u32>(dx, dy));
        }
    }
    return acc;
}

#if SUBGROUPS
// The (min, max) of every invocation's `v`, for every invocation, with one barrier: each
// subgroup reduces its own, and its first active invocation folds that into two
// workgroup words with atomics (a few per word, not one per invocation). Min and max are
// exact in any order, so this is bit for bit the other way's result. The barrier also
// orders what was stored before it.
fn workgroup_depth_range(local: u32, side: u32, v: vec2<u32>) -> vec2<u32> {
    let inverted_min = subgroupMax(~v.x);
    let max_bits = subgroupMax(v.y);
    if (subgroupBroadcastFirst(local) == local) {
        atomicMax(&depth_inverted_min, inverted_min);
        atomicMax(&depth_max, max_bits);
    }
    workgroupBarrier();
    return vec2<u32>(~atomicLoad(&depth_inverted_min), atomicLoad(&depth_max));
}
#else
// The (min, max) of every invocation's `v`, for every invocation of a workgroup of
// side² invocations: each of the first `side` invocations folds a column of `side`
// values, then every invocation folds the `side` column results. Min and max are exact
// in any order, so this is bit for bit what atomics on two workgroup words gave, without
// 2·side² atomics queueing on the same two words. Two barriers; the first also orders
// what was stored before it.
fn workgroup_depth_range(local: u32, side: u32, v: vec2<u32>) -> vec2<u32> {
    depth_partial[local] = v;
    workgroupBarrier();
    if (local < side) {
        // Reads only words side.. and writes only its own word below side.
        var a = v;
        for (var k = 1u; k < side; k++) {
            let b = depth_partial[local + k * side];
            a = vec2<u32>(min(a.x, b.x), max(a.y, b.y));
        }
        depth_partial[local] = a;
    }
    workgroupBarrier();
    var a = depth_partial[0];
    for (var k = 1u; k < side; k++) {
        let b = depth_partial[k];
        a = vec2<u32>(min(a.x, b.x), max(a.y, b.y));
    }
    return a;
}
#endif

// The 2.5D mask's cells every sample of a pixel occupies within [lo, hi].
fn add_depth_cells(pixel: vec2<u32>, lo: f32, hi: f32) {
    var cells = 0u;
    for (var s = 0u; s < SAMPLES; s++) {
        let r = sample_range(pixel, s);
        if (r.x >= 0.0) {
            cells |= cells_between(cell_of(r.x, lo, hi), cell_of(r.y, lo, hi));
        }
    }
    if (cells != 0u) {
        atomicOr(&depth_mask, cells);
    }
}

// Depth cell of z in [lo, hi] for the 2.5D mask: 32 equal cells.
fn cell_of(z: f32, lo: f32, hi: f32) -> u32 {
    let t = (z - lo) / max(hi - lo, 1e-30);
    return u32(clamp(t * 32.0, 0.0, 31.0));
}

fn cells_between(a: u32, b: u32) -> u32 {
    let width = b - a + 1u;
    let ones = select((1u << width) - 1u, 0xffffffffu, width >= 32u);
    return ones << a;
}

// Exponential slice bounds for the clustered variant.
fn slice_bound(k: u32, slices: u32) -> f32 {
    return frame.near * pow(frame.far / frame.near, f32(k) / f32(slices));
}

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

// The coarse stage: one workgroup per coarse tile of COARSE×COARSE tiles; each
// invocation folds COARSE_FOLD × COARSE_FOLD pixels into its part of the depth range. No depth mask:
// every fine tile applies its own. Lights are taken a chunk of COARSE_CHUNK at a time:
// every invocation tests one light a step and sets the hits' bits in workgroup memory,
// with no barrier inside the chunk (per-batch ranks cost two barriers and a dozen
// workgroup loads a batch, which bound this stage at high light counts); then each
// invocation counts the bits of its own run of words, a prefix sum over the invocations
// places the runs, and each writes its hits in ascending light order.
@compute @workgroup_size(COARSE_SIDE, COARSE_SIDE, 1)
fn coarse(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(local_invocation_id) lid: vec3<u32>,
) {
    // Ordered before the first chunk's bits by the depth range's barriers (the wide
    // pass's by the barrier below).
    for (var k = 0u; k < COARSE_WORDS_PER_THREAD; k++) {
        atomicStore(&coarse_hits[local * COARSE_WORDS_PER_THREAD + k], 0u);
    }
    let coarse_x = (list_params.tiles_x + COARSE - 1u) / COARSE;
#if WIDE_PASS
    // A wide tile: its whole frustum between the depths 0 and 1 (no depth read; every
    // range a tile or coarse tile takes lies within it), every light a candidate.
    let span = TILE * COARSE * WIDE;
    let origin = group.xy * span;
    let lo = view_depth(0.0);
    let hi = view_depth(1.0);
    let empty = false;
    let bounds = tile_bounds(origin, span, lo, hi, false);
    let wide_x = (coarse_x + WIDE - 1u) / WIDE;
    let base_word = (group.y * wide_x + group.x) * WIDE_STRIDE;
    let capacity = WIDE_CAPACITY;
    let count = frame.light_count;
    workgroupBarrier();
#else
    let span = TILE * COARSE;
    let origin = group.xy * span;
    let range = workgroup_depth_range(local, COARSE_SIDE, block_depth_range(origin + lid.xy * COARSE_FOLD, COARSE_FOLD));
    let lo = bitcast<f32>(range.x);
    let hi = bitcast<f32>(range.y);
    let empty = range.y == 0u;
    let bounds = tile_bounds(origin, span, lo, hi, empty);
    let base_word = (group.y * coarse_x + group.x) * COARSE_STRIDE;
    let capacity = COARSE_CAPACITY;
#if WIDE_STAGE
    // The candidates: the wide tile's lights where they fit its list.
    let wide_x = (coarse_x + WIDE - 1u) / WIDE;
    wide_base = ((group.y / WIDE) * wide_x + group.x / WIDE) * WIDE_STRIDE;
    if (local == 0u) {
        wide_count = wide_lists[wide_base];
    }
    let listed = workgroupUniformLoad(&wide_count);
    from_wide = listed <= WIDE_CAPACITY;
    let count = select(frame.light_count, listed, from_wide);
#else
    let count = frame.light_count;
#endif
#endif

    var total = 0u;
    // Each step's sphere is loaded a step ahead (COARSE_CHUNK is a multiple of THREADS,
    // so the next step is the same invocation's next candidate across chunks too).
    var next_light = coarse_candidate(local, count);
    var next_sphere = stage_sphere(next_light);
    for (var chunk = 0u; chunk < count; chunk += COARSE_CHUNK) {
        let end = min(count, chunk + COARSE_CHUNK);
        if (!empty) {
            for (var i = chunk + local; i < end; i += THREADS) {
                let light = next_light;
                let sphere = next_sphere;
                if (i + THREADS < count) {
                    next_light = coarse_candidate(i + THREADS, count);
                    next_sphere = stage_sphere(next_light);
                }
                // An all-ones mask: the depth-mask test passes here.
                if (light_touches_tile(light, sphere, bounds, lo, hi, 0xffffffffu, lo, hi, STAGE_REACH)) {
                    let bit = i - chunk;
                    atomicOr(&coarse_hits[bit / 32u], 1u << (bit % 32u));
                }
            }
        }
        workgroupBarrier();
        let first_word = local * COARSE_WORDS_PER_THREAD;
        var mine = 0u;
        for (var k = 0u; k < COARSE_WORDS_PER_THREAD; k++) {
            mine += countOneBits(atomicLoad(&coarse_hits[first_word + k]));
        }
        let placed = exclusive_scan(local, mine, THREADS);
        var slot = total + placed.x;
        for (var k = 0u; k < COARSE_WORDS_PER_THREAD; k++) {
            // Only this invocation reads or clears its words until the next barrier.
            var bits = atomicLoad(&coarse_hits[first_word + k]);
            atomicStore(&coarse_hits[first_word + k], 0u);
            let first = chunk + (first_word + k) * 32u;
            while (bits != 0u) {
                if (slot < capacity) {
                    store_candidate(base_word + 1u + slot, coarse_candidate(first + firstTrailingBit(bits), count));
                }
                slot += 1u;
                bits &= bits - 1u;
            }
        }
        // At most the light count: no overflow.
        total += placed.y;
        // The next chunk sets bits other invocations have just cleared.
        workgroupBarrier();
    }
    if (local == 0u) {
        store_candidate(base_word, total);
    }
}

// Candidate k of the coarse stage (k < count): entry k of its wide tile's list
// (WIDE_STAGE, where the list fits), else light k. Bits and list slots go by k, so lists stay ascending.
// Past `count` it returns k (a prefetch that is never used).
fn coarse_candidate(k: u32, count: u32) -> u32 {
#if WIDE_STAGE
#if WIDE_PASS
#else
    if (from_wide && k < count) {
        return wide_lists[wide_base + 1u + k];
    }
#endif
#endif
    return k;
}

// Where the stage writes: the wide lists (WIDE_PASS) or the coarse lists.
fn store_candidate(word: u32, value: u32) {
#if WIDE_PASS
    wide_lists[word] = value;
#else
    coarse_lists[word] = value;
#endif
}

// The cone test's widening of the stage's tile: twice the coarse stage's for the wide
// pass (as its spheres, below).
#if WIDE_PASS
const STAGE_REACH: f32 = 2.0 * COARSE_REACH;
#else
const STAGE_REACH: f32 = COARSE_REACH;
#endif

// The stage's sphere of light i: the coarse one, and for the wide pass widened again by
// COARSE_REACH of its distance, since a wide tile's planes round differently from its
// coarse tiles' as those do from their tiles' (so every light a coarse tile keeps, its
// wide tile keeps).
fn stage_sphere(i: u32) -> vec4<f32> {
    let s = light_sphere(i, true);
#if WIDE_PASS
    let r = abs(s.w) + COARSE_REACH * length(s.xyz);
    return vec4<f32>(s.xyz, select(r, -r, s.w < 0.0));
#else
    return s;
#endif
}

// Exclusive prefix sum of `v` over the workgroup's `n` invocations (n ≤ SCAN_MAX, a
// power of two: THREADS for the coarse stage, SCAN_THREADS for the list scans;
// Hillis–Steele): (the sum of the invocations' before this one, the sum of all). Sums
// saturate at u32::MAX, which is associative, so a saturated total is still exact below
// the bound (the coarse stage's sums, at most the light count, never saturate). Ends with
// a barrier: the next call may store into scan_sums at once.
const SCAN_MAX: u32 = 256u;
var<workgroup> scan_sums: array<u32, SCAN_MAX>;

fn add_sat(a: u32, b: u32) -> u32 {
    let s = a + b;
    return select(s, 0xffffffffu, s < a);
}

fn exclusive_scan(local: u32, v: u32, n: u32) -> vec2<u32> {
    scan_sums[local] = v;
    workgroupBarrier();
    for (var d = 1u; d < n; d *= 2u) {
        var add = 0u;
        if (local >= d) {
            add = scan_sums[local - d];
        }
        workgroupBarrier();
        scan_sums[local] = add_sat(scan_sums[local], add);
        workgroupBarrier();
    }
    var before = 0u;
    if (local > 0u) {
        before = scan_sums[local - 1u];
    }
    let total = scan_sums[n - 1u];
    workgroupBarrier();
    return vec2<u32>(before, total);
}

#if COMPACT
// The prefix sum between the two runs of `main`: blocked, not decoupled look-back (WGSL
// promises no forward progress between workgroups, so a workgroup spinning on another's
// flag may never see it), and not one workgroup over every list (at 1920×1080 with 16
// clusters that is 130,560 lists in one workgroup's loop); `exclusive_scan` above.
const SCAN_THREADS: u32 = 256u;
const SCAN_PER_THREAD: u32 = SCAN_BLOCK / SCAN_THREADS;

fn list_count() -> u32 {
    return list_params.tiles_x * list_params.tiles_y * list_params.lists_per_tile;
}

// Block b's sum of the counts of its lists longer than their slot, saturated where it
// wrapped.
fn block_sum(b: u32) -> u32 {
    if (atomicLoad(&list_block_sums[2u * b + 1u]) != 0u) {
        return 0xffffffffu;
    }
    return atomicLoad(&list_block_sums[2u * b]);
}

// A workgroup per block of SCAN_BLOCK lists, SCAN_PER_THREAD consecutive lists an
// invocation: each list's offset and the count it keeps under the bound. Each workgroup
// sums the blocks before its own itself (a few at most: 8 at 1920×1080 with 16-pixel
// tiles, 128 with 16 clusters), so no dispatch scans the blocks first (saturating sums
// are associative: the same offsets in any order); the first writes header word 0, the
// indices the lists longer than their scratch slot want (all lists' without scratch). A list that
// fits its scratch slot (1..=scratch lights) stays there, whole; the others lie in the
// pool after every slot, back to back in list order (empty ones too, holding nothing,
// so that without scratch every offset is the sum of the counts before it).
@compute @workgroup_size(SCAN_THREADS, 1, 1)
fn scan_lists(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let lists = list_count();
    let scratch = compact.scratch;
    let first = group.x * SCAN_BLOCK + local * SCAN_PER_THREAD;
    var counts: array<u32, SCAN_PER_THREAD>;
    var sum = 0u;
    for (var j = 0u; j < SCAN_PER_THREAD; j++) {
        let l = first + j;
        var c = 0u;
        if (l < lists) {
            c = atomicLoad(&light_lists[HEADER_WORDS + ENTRY_WORDS * l + 1u]);
        }
        counts[j] = c;
        if (c > scratch) {
            sum = add_sat(sum, c);
        }
    }
    let before = exclusive_scan(local, sum, SCAN_THREADS).x;
    let blocks = (lists + SCAN_BLOCK - 1u) / SCAN_BLOCK;
    var earlier = 0u;
    var every = 0u;
    for (var b = local; b < blocks; b += SCAN_THREADS) {
        let v = block_sum(b);
        every = add_sat(every, v);
        if (b < group.x) {
            earlier = add_sat(earlier, v);
        }
    }
    let block_start = exclusive_scan(local, earlier, SCAN_THREADS).y;
    let wanted = exclusive_scan(local, every, SCAN_THREADS).y;
    if (group.x == 0u && local == 0u) {
        atomicStore(&light_lists[0], wanted);
    }
    // At most half the index array (`ListLayout::scratch_per_list`): no overflow.
    let pool_start = scratch * lists;
    var offset = add_sat(block_start, before);
    let pool = list_params.pool_indices;
    for (var j = 0u; j < SCAN_PER_THREAD; j++) {
        let l = first + j;
        let c = counts[j];
        if (l < lists) {
            let e = HEADER_WORDS + ENTRY_WORDS * l;
            if (c > 0u && c <= scratch) {
                atomicStore(&light_lists[e], l * scratch);
            } else {
                let start = min(add_sat(pool_start, offset), pool);
                let kept = min(c, pool - start);
                atomicStore(&light_lists[e], start);
                atomicStore(&light_lists[e + 1u], kept);
                if (kept < c) {
                    atomicAdd(&light_lists[1], 1u);
                }
            }
        }
        if (c > scratch) {
            offset = add_sat(offset, c);
        }
    }
}
#endif
