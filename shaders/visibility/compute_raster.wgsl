// Compute rasterizer (ComputeRaster): the merged opaque triangles into a per-pixel u64,
// (depth bits << 32) | ~id, kept with a 64-bit atomic min. Depths are non-negative
// floats, so their bits order like integers; on equal depth the larger id has the
// smaller ~id and wins, as the render pipelines' LessEqual keeps the later draw.
// Per triangle, as the hardware does: clip space with the vertex shader's own expression
// (frame.view_proj * position), clipped against the near plane z >= 0 and the viewport's
// sides (only where a vertex lies outside them), vertices snapped to 1/256 pixel, back
// faces of single-sided materials culled (front is counter-clockwise in NDC), pixel
// centres tested with exact 64-bit edge functions and the top-left rule, depth from the
// triangle's plane in screen space, pixels past the far plane (depth > 1) dropped.
//
// Four dispatches, each spreading its work over threads so that no thread walks many
// pixels (the GPU waits for its slowest thread):
// - `clear` (CLEAR): the buffer to all ones; list counters and indirect arguments reset.
// - `setup` (SETUP, visibility/compute_raster_setup.wgsl), one thread per triangle:
//   clip, snap, cull, then per fan triangle of the clipped polygon by its pixel box: a
//   box of at most 16 pixels covered in the thread; else one 64-byte record (snapped
//   vertices, top-left biases, depth plane, pixel box, id) and, for a box within 2×2
//   blocks, an entry per block its edges may reach, or else one entry per TILE_PIXELS²
//   tile of its box. Reserved a workgroup at a time (one global atomic a workgroup).
// - `bin` (BIN), a thread per BLOCK² block of a tile entry (TILES_PER_GROUP a workgroup):
//   blocks inside the box that no edge rejects (tested at the block's corner where the
//   edge function is largest: exact, as the function is linear) become block entries.
// - `raster` (RASTER), a thread per pixel of a block entry (BLOCKS_PER_GROUP a
//   workgroup): the edge tests, the depth and the atomic min. No loops, no division.
// Tiles and blocks are two levels so that setup writes at most a viewport's tiles
// (510 at 1080p) for a screen-filling triangle instead of its 32,400 blocks. Both are
// dispatched indirectly over x and y (flattened here), the arguments grown with atomicMax
// as entries are appended. A list that is full loses nothing: setup rasterizes a fan
// triangle without a record, or a tile or block without an entry, in its own thread; bin
// a block without an entry. Each is counted (`counters`), as are the fan triangles of
// setup's direct paths, read back for the pass's report. Every
// path runs the same per-pixel code (`cover`), and an atomic min is order-independent,
// so the image does not depend on which path drew a pixel.
// RESOLVE: the full-screen draw writing the id and frag_depth.
//
// Alpha-masked materials: setup, bin and raster run once for the opaque triangles (those
// marked in `alpha_tested` skipped), then once per group of masked materials that share
// their code (ALPHA_TEST, with the group's `masked_members` and its material code, the
// constants read from material_constants where SHARED_CODE): its triangles only, each
// covered pixel nearer than what the buffer holds rebuilt (visibility/surface.wgsl, as
// visibility shading rebuilds it) and kept only where its material's alpha reaches that
// material's cutoff, as the depth prepass discards. A masked run starts from a lists-only
// clear (LISTS_ONLY), keeping the buffer. Each run counts into its own `counters`.
// FOLDED (with ALPHA_TEST): the opaque run draws the first group's triangles too, its
// setup flagging them (RECORD_ALPHA) for the alpha test, so that group costs no run.
// GLASS: the opaque run also draws the blended triangles (glass_triangles, after the
// opaque ones in setup's threads, both faces), flagged RECORD_GLASS: their pixels keep
// the nearest depth alone (a 32-bit atomic min in glass_depth), which the resolve writes
// into the transparent depth, as TransparentDepth's own run would. One run instead of two.
// GLASS_FAR (with GLASS): their farthest depth too (a 32-bit atomic max in the word after
// each pixel's nearest in glass_depth, so no binding more), the far end of the
// transparent culling range.

#include "common/types.wgsl"
#include "common/triangle_setup.wgsl"

// Triangle count, workgroups per dispatch dimension, width, height.
@group(0) @binding(1) var<uniform> raster_params: vec4<u32>;
#if RESOLVE
@group(0) @binding(2) var<storage, read> vis: array<vec2<u32>>;
#else
// Capacities (entries) of the record, tile and block lists; setup's direct paths (see
// its `blocks_direct` and `small_pixels`).
@group(0) @binding(12) var<uniform> list_capacity: vec4<u32>;
#if CLEAR
@group(0) @binding(7) var<storage, read_write> vis: array<vec2<u32>>;
@group(0) @binding(8) var<storage, read_write> counters: array<u32, 8>;
@group(0) @binding(9) var<storage, read_write> tile_args: array<u32, 4>;
@group(0) @binding(10) var<storage, read_write> block_args: array<u32, 4>;
#if GLASS
@group(0) @binding(15) var<storage, read_write> glass_depth: array<u32>;
#endif
#else
#if GLASS
// The blended triangles' nearest depth bits per pixel (all ones where none).
@group(0) @binding(15) var<storage, read_write> glass_depth: array<atomic<u32>>;
#endif
// Words per pixel in glass_depth: the nearest, and with GLASS_FAR the farthest (zero
// where none).
#if GLASS_FAR
const GLASS_WORDS: u32 = 2u;
#else
const GLASS_WORDS: u32 = 1u;
#endif
@group(0) @binding(7) var<storage, read_write> vis: array<atomic<u64>>;
// Four vec4<u32> per record (see `store_record`).
#if SETUP
@group(0) @binding(5) var<storage, read_write> records: array<vec4<u32>>;
#else
@group(0) @binding(5) var<storage, read> records: array<vec4<u32>>;
#endif
#if RASTER
@group(0) @binding(8) var<storage, read> counters: array<u32, 8>;
@group(0) @binding(11) var<storage, read> blocks: array<vec2<u32>>;
#else
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>, 8>;
#endif
#if SETUP
@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(2) var<storage, read> vertices: array<f32>;
@group(0) @binding(3) var<storage, read> triangles: array<u32>;
@group(0) @binding(4) var<storage, read> single_sided: array<u32>;
#if GLASS
// The blended meshes' own merge (vertices as `vertices`), and its triangle count in x.
@group(0) @binding(16) var<storage, read> glass_vertices: array<f32>;
@group(0) @binding(17) var<storage, read> glass_triangles: array<u32>;
@group(0) @binding(18) var<uniform> glass_params: vec4<u32>;
#endif
// Bit t set: triangle t is alpha-tested, drawn by its material group's own run (or, with
// FOLDED, flagged by this one).
#if FOLDED
@group(0) @binding(14) var<storage, read> alpha_tested: array<u32>;
#else
#if ALPHA_TEST
#else
@group(0) @binding(14) var<storage, read> alpha_tested: array<u32>;
#endif
#endif
#else
#if ALPHA_TEST
@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(2) var<storage, read> vertices: array<f32>;
@group(0) @binding(3) var<storage, read> triangles: array<u32>;
#endif
#endif
#if ALPHA_TEST
// The run's MEMBERS_COUNT materials, ascending: (first triangle, its setup thread, first
// constant in material_constants, alpha cutoff's bits). Setup's threads take the
// members' triangles one after another, MEMBERS_THREADS in all.
@group(0) @binding(13) var<storage, read> masked_members: array<vec4<u32>>;
#endif
#if SETUP
@group(0) @binding(6) var<storage, read_write> tiles: array<vec2<u32>>;
// The bin dispatch's arguments (so the bin dispatch, which reads them, binds nothing it
// could write them with).
@group(0) @binding(9) var<storage, read_write> tile_args: array<atomic<u32>, 4>;
// Setup lists the blocks of fan triangles within 2×2 blocks itself.
@group(0) @binding(11) var<storage, read_write> blocks: array<vec2<u32>>;
@group(0) @binding(10) var<storage, read_write> block_args: array<atomic<u32>, 4>;
#endif
#if BIN
@group(0) @binding(6) var<storage, read> tiles: array<vec2<u32>>;
@group(0) @binding(11) var<storage, read_write> blocks: array<vec2<u32>>;
@group(0) @binding(10) var<storage, read_write> block_args: array<atomic<u32>, 4>;
#endif
#endif
#endif

const NO_TRIANGLE: u32 = 0xffffffffu;
// Half a pixel in snapped (1/SUBPIXEL) units: pixel centres.
const HALF_PIXEL: i32 = 128;
// Counter slots: entries appended to each list (past the capacity too), then fan
// triangles, tiles and blocks rasterized serially because their list was full, then
// fan triangles setup drew itself (small ones) and whose blocks it listed itself.
const RECORDS: u32 = 0u;
const TILES: u32 = 1u;
const BLOCKS: u32 = 2u;
const SERIAL_TRIANGLES: u32 = 3u;
const SERIAL_TILES: u32 = 4u;
const SERIAL_BLOCKS: u32 = 5u;
const SMALL_TRIANGLES: u32 = 6u;
const BLOCK_TRIANGLES: u32 = 7u;
// Record flags: bits 0-2, edge k is not a top or left edge (bias -1); RECORD_LINEAR, the
// snapped coordinates are small enough for the edge functions to be exactly linear.
const RECORD_LINEAR: u32 = 8u;
// RECORD_ALPHA: the folded group's triangle, alpha-tested (FOLDED).
const RECORD_ALPHA: u32 = 16u;
// RECORD_GLASS: a blended triangle, into glass_depth (GLASS).
const RECORD_GLASS: u32 = 32u;
// Snapped coordinates up to this (2^29 fixed point, 2^21 pixels) keep every difference
// the edge functions take within i32 (pixel centres are under 2^22 for viewports up to
// 16,384 pixels), so an edge function is exactly the linear function of the pixel.
const LINEAR_RANGE: i32 = 536870912;

fn flat_index(wg: vec3<u32>, groups: vec3<u32>, local: u32, size: u32) -> u32 {
    return (wg.y * groups.x + wg.x) * size + local;
}

#if RESOLVE
@vertex
fn resolve_vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

struct Resolved {
    @location(0) id: u32,
    @builtin(frag_depth) depth: f32,
};

@fragment
fn resolve_fs(@builtin(position) pos: vec4<f32>) -> Resolved {
    let p = vec2<u32>(pos.xy);
    // Little-endian: x holds ~id, y the depth bits.
    let v = vis[p.y * raster_params.z + p.x];
    var out: Resolved;
    if (v.y == 0xffffffffu) {
        out.id = NO_TRIANGLE;
        out.depth = 1.0;
    } else {
        out.id = ~v.x;
        out.depth = bitcast<f32>(v.y);
    }
    return out;
}
#else
// Pixels per side of a tile (BLOCK pixels per block, TILE_BLOCKS blocks per tile side).
const TILE_PIXELS: u32 = BLOCK * TILE_BLOCKS;
// Threads per block (one a pixel) and per tile (one a block).
const BLOCK_THREADS: u32 = BLOCK * BLOCK;
const TILE_THREADS: u32 = TILE_BLOCKS * TILE_BLOCKS;

// Indirect dispatch size (x, y) for `entries` list entries, `per_group` a workgroup: x up
// to the per-dimension limit, y as many rows of those as needed (flattened back by the
// dispatch).
fn dispatch_size(entries: u32, per_group: u32) -> vec2<u32> {
    let groups = (entries + per_group - 1u) / per_group;
    let row = raster_params.y;
    return vec2<u32>(min(groups, row), (groups + row - 1u) / row);
}
#if CLEAR

@compute @workgroup_size(CLEAR_GROUP)
fn clear(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let i = flat_index(wg, groups, local, CLEAR_GROUP);
    if (i < 8u) {
        counters[i] = 0u;
    }
    if (i < 4u) {
        // Zero workgroups: (0, 1, 1); the appenders grow x and y.
        let arg = select(1u, 0u, i == 0u);
        tile_args[i] = arg;
        block_args[i] = arg;
    }
#if LISTS_ONLY
#else
    if (i < raster_params.z * raster_params.w) {
        vis[i] = vec2<u32>(0xffffffffu, 0xffffffffu);
#if GLASS
#if GLASS_FAR
        glass_depth[2u * i] = 0xffffffffu;
        glass_depth[2u * i + 1u] = 0u;
#else
        glass_depth[i] = 0xffffffffu;
#endif
#endif
    }
#endif
}
#else

// A fan triangle ready to rasterize: oriented with positive area (clockwise on screen).
struct Tri {
    // Snapped vertices (1/256 pixel).
    a: vec2<i32>,
    b: vec2<i32>,
    c: vec2<i32>,
    // Added to the edge functions of b -> c, c -> a, a -> b: -1 where a centre exactly
    // on the edge is not covered (not a top or left edge), else 0.
    bias: vec3<i32>,
    // The first vertex unsnapped (x, y in pixels, depth) and the depth's slopes.
    sa: vec3<f32>,
    dz: vec2<f32>,
    // Pixels whose centres lie in the vertices' box, within the viewport: x0, y0, x1, y1.
    box: vec4<i32>,
    id: u32,
    flags: u32,
    // Its entry in masked_members (ALPHA_TEST): whose material tests its alpha.
    member: u32,
};

#if ALPHA_TEST
#include "visibility/surface.wgsl"
#include <material>

// The last member whose component `c` (0: first triangle, 1: first setup thread) is not
// over `at`: the member holding that triangle or thread (both ascend with the members).
// Setup finds it once a triangle (the records carry it), not every pixel.
fn masked_member(c: u32, at: u32) -> u32 {
    var lo = 0u;
    var hi = MEMBERS_COUNT;
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (masked_members[mid][c] <= at) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// Whether `t`'s material keeps pixel (px, py): its alpha there reaches the material's
// cutoff (forward.wgsl's prepass discards below it).
fn alpha_keeps(t: Tri, px: i32, py: i32) -> bool {
    let member = masked_members[t.member];
#if SHARED_CODE
    material_constant_base = member.z;
#endif
    let p = surface_point(vec2<u32>(u32(px), u32(py)), t.id);
    return material_alpha(material_setup(p)) >= bitcast<f32>(member.w);
}
#endif

// The pixel (px, py) of `t`, if its centre is covered and its depth within the far plane.
fn cover(t: Tri, px: i32, py: i32) {
    let p = vec2<i32>(px, py) * 256 + vec2<i32>(HALF_PIXEL);
    if (edge(t.b, t.c, p) + i64(t.bias.x) < 0 || edge(t.c, t.a, p) + i64(t.bias.y) < 0 || edge(t.a, t.b, p) + i64(t.bias.z) < 0) {
        return;
    }
    let centre = vec2<f32>(f32(px) + 0.5, f32(py) + 0.5);
    let z = t.sa.z + t.dz.x * (centre.x - t.sa.x) + t.dz.y * (centre.y - t.sa.y);
    if (!(z <= 1.0)) {
        return;
    }
    let at = u32(py) * raster_params.z + u32(px);
#if GLASS
    if ((t.flags & RECORD_GLASS) != 0u) {
        atomicMin(&glass_depth[GLASS_WORDS * at], bitcast<u32>(max(z, 0.0)));
#if GLASS_FAR
        atomicMax(&glass_depth[GLASS_WORDS * at + 1u], bitcast<u32>(max(z, 0.0)));
#endif
        return;
    }
#endif
    let key = (u64(bitcast<u32>(max(z, 0.0))) << 32u) | u64(~t.id);
#if ALPHA_TEST
#if FOLDED
    let tested = (t.flags & RECORD_ALPHA) != 0u;
#else
    let tested = true;
#endif
    // The material only where it could win: behind what the buffer holds, the min
    // would keep that anyway.
    if (tested && (atomicLoad(&vis[at]) <= key || !alpha_keeps(t, px, py))) {
        return;
    }
#endif
    atomicMin(&vis[at], key);
}

// Pixels x..x+7 of row y, those up to `last`.
fn cover_span(t: Tri, x: i32, y: i32, last: i32) {
    cover(t, x, y);
    if (x + 1 <= last) { cover(t, x + 1, y); }
    if (x + 2 <= last) { cover(t, x + 2, y); }
    if (x + 3 <= last) { cover(t, x + 3, y); }
    if (x + 4 <= last) { cover(t, x + 4, y); }
    if (x + 5 <= last) { cover(t, x + 5, y); }
    if (x + 6 <= last) { cover(t, x + 6, y); }
    if (x + 7 <= last) { cover(t, x + 7, y); }
}

// Every pixel of `region` (x0, y0, x1, y1, inclusive) in this thread: the fallback when
// a list is full. Exact; slow for large regions. Eight pixels a loop iteration:
// llvmpipe (lavapipe) ends all loops of an invocation after 65,535 iterations in total
// (LP_MAX_TGSI_LOOP_ITERATIONS), which one pixel an iteration reaches with a
// screen-filling triangle at 333×197; eight keep it exact there up to ~500,000 pixels
// a thread.
fn raster_region(t: Tri, region: vec4<i32>) {
    for (var y = region.y; y <= region.w; y++) {
        for (var x = region.x; x <= region.z; x += 8) {
            cover_span(t, x, y, region.z);
        }
    }
}

// The pixels of cell `cell` (`size` pixels a side) within the triangle's box.
fn cell_region(box: vec4<i32>, cell: vec2<u32>, size: u32) -> vec4<i32> {
    let lo = vec2<i32>(cell * size);
    let hi = lo + vec2<i32>(i32(size) - 1);
    return vec4<i32>(max(lo, box.xy), min(hi, box.zw));
}

fn pack_point(p: vec2<i32>) -> u32 {
    return u32(p.x) | (u32(p.y) << 16u);
}

fn unpack_point(v: u32) -> vec2<u32> {
    return vec2<u32>(v & 0xffffu, v >> 16u);
}

fn load_record(r: u32) -> Tri {
    let i = 4u * r;
    let w0 = records[i];
    let w1 = records[i + 1u];
    let w2 = records[i + 2u];
    let w3 = records[i + 3u];
    var t: Tri;
    t.a = bitcast<vec2<i32>>(w0.xy);
    t.b = bitcast<vec2<i32>>(w0.zw);
    t.c = bitcast<vec2<i32>>(w1.xy);
    t.box = vec4<i32>(vec2<i32>(unpack_point(w1.z)), vec2<i32>(unpack_point(w1.w)));
    t.sa = bitcast<vec3<f32>>(w2.xyz);
    t.dz = vec2<f32>(bitcast<f32>(w2.w), bitcast<f32>(w3.x));
    t.id = w3.y;
    t.flags = w3.z;
    t.member = w3.w;
    t.bias = -vec3<i32>(vec3<u32>(t.flags, t.flags >> 1u, t.flags >> 2u) & vec3<u32>(1u));
    return t;
}

// Whether some pixel centre of `region` may lie inside edge a -> b: its edge function
// (plus bias) is not negative at the corner where the function is largest, the one its
// gradient (-(b.y - a.y), b.x - a.x) points to.
fn edge_reaches(a: vec2<i32>, b: vec2<i32>, bias: i32, lo: vec2<i32>, hi: vec2<i32>) -> bool {
    let p = vec2<i32>(select(lo.x, hi.x, b.y < a.y), select(lo.y, hi.y, b.x > a.x));
    return edge(a, b, p) + i64(bias) >= 0;
}

// False only if every pixel centre of `region` is outside an edge. Skipped (true) for
// coordinates so large that the edge functions wrap in i32 and stop being linear.
fn may_cover(t: Tri, region: vec4<i32>) -> bool {
    if ((t.flags & RECORD_LINEAR) == 0u) {
        return true;
    }
    let lo = region.xy * 256 + vec2<i32>(HALF_PIXEL);
    let hi = region.zw * 256 + vec2<i32>(HALF_PIXEL);
    return edge_reaches(t.b, t.c, t.bias.x, lo, hi) && edge_reaches(t.c, t.a, t.bias.y, lo, hi) && edge_reaches(t.a, t.b, t.bias.z, lo, hi);
}

#if SETUP
#include "visibility/compute_raster_setup.wgsl"
#endif
#if BIN

var<workgroup> kept: atomic<u32>;
var<workgroup> kept_first: u32;

// TILES_PER_GROUP tiles a workgroup, a thread per block.
@compute @workgroup_size(TILE_THREADS * TILES_PER_GROUP)
fn bin(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let i = (wg.y * raster_params.y + wg.x) * TILES_PER_GROUP + local / TILE_THREADS;
    let in_tile = local % TILE_THREADS;
    let capacity = list_capacity.z;
    var keep = false;
    var r = 0u;
    var t: Tri;
    var block = vec2<u32>(0u);
    var region = vec4<i32>(0);
    // No early return: every thread reaches the barriers.
    if (i < min(atomicLoad(&counters[TILES]), list_capacity.y)) {
        let entry = tiles[i];
        r = entry.x;
        t = load_record(r);
        block = unpack_point(entry.y) * TILE_BLOCKS + vec2<u32>(in_tile % TILE_BLOCKS, in_tile / TILE_BLOCKS);
        region = cell_region(t.box, block, BLOCK);
        keep = region.x <= region.z && region.y <= region.w && may_cover(t, region);
    }
    // One append for the workgroup: a slot within it per kept block, then its first.
    var slot = 0u;
    if (keep) {
        slot = atomicAdd(&kept, 1u);
    }
    workgroupBarrier();
    if (local == 0u) {
        let n = atomicLoad(&kept);
        var first = 0u;
        if (n > 0u) {
            // At most one per block of the workgroup's tile entries, which are at most
            // 2^24 (compute_raster.rs): the counter stays under 2^30.
            first = atomicAdd(&counters[BLOCKS], n);
            let end = min(first + n, capacity);
            if (end > first) {
                let size = dispatch_size(end, BLOCKS_PER_GROUP);
                atomicMax(&block_args[0], size.x);
                atomicMax(&block_args[1], size.y);
            }
        }
        kept_first = first;
    }
    let first = workgroupUniformLoad(&kept_first);
    if (keep) {
        let s = first + slot;
        if (s < capacity) {
            blocks[s] = vec2<u32>(r, block.x | (block.y << 16u));
        } else {
            atomicAdd(&counters[SERIAL_BLOCKS], 1u);
            raster_region(t, region);
        }
    }
}
#endif
#if RASTER

// BLOCKS_PER_GROUP blocks a workgroup, a thread per pixel.
@compute @workgroup_size(BLOCK_THREADS * BLOCKS_PER_GROUP)
fn raster(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let i = (wg.y * raster_params.y + wg.x) * BLOCKS_PER_GROUP + local / BLOCK_THREADS;
    if (i >= min(counters[BLOCKS], list_capacity.z)) {
        return;
    }
    let entry = blocks[i];
    let t = load_record(entry.x);
    let in_block = local % BLOCK_THREADS;
    let p = vec2<i32>(unpack_point(entry.y) * BLOCK + vec2<u32>(in_block % BLOCK, in_block / BLOCK));
    // The pixels the serial walk visits: the box (within the viewport).
    if (all(p >= t.box.xy) && all(p <= t.box.zw)) {
        cover(t, p.x, p.y);
    }
}
#endif
#endif
#endif
