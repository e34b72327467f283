// The setup dispatch (SETUP) of the compute rasterizer, included by
// visibility/compute_raster.wgsl (whose header tells the whole pass). A thread per
// triangle clips, snaps and culls it, then draws each fan triangle by one of three
// paths, chosen by its pixel box:
// - PATH_SMALL, a box of at most `small_pixels()` (16) pixels: covered here, in this thread, with
//   the per-pixel code every path runs (`cover`). No record, no list entry.
// - PATH_BLOCKS, a box within 2×2 blocks: a record, and an entry per block of those its
//   edges may reach appended to the block list here (no tile entry, no bin).
// - PATH_TILES, any other box: a record and an entry per tile of its box; bin lists the
//   blocks.
// Appends are reserved a workgroup at a time: each thread adds what it needs to a
// workgroup counter, one thread adds the workgroup's sum to the global counter, so a
// workgroup of 64 triangles costs each list's counter one same-address atomic instead
// of up to 64. Every path draws a pixel with `cover`, and an atomic min is order-
// independent: the image is the same bit for bit whichever path drew it (the test hook's
// `direct=0` sends every fan triangle down PATH_TILES, for tests to compare with).

// How setup draws a fan triangle (`Fan.path`); PATH_NONE: rejected, or none this round.
const PATH_NONE: u32 = 0u;
const PATH_SMALL: u32 = 1u;
const PATH_BLOCKS: u32 = 2u;
const PATH_TILES: u32 = 3u;
// Tiles a fan triangle reserves without checking the count first (see `reserve_many_tiles`).
const UNCHECKED_TILES: u32 = 16u;

// A fan triangle set up, and how it is drawn: `blocks`, on PATH_BLOCKS, bit k set for
// block k (x + 2y) of the 2×2 blocks from its box's first one when its edges may reach
// the block's pixels within the box.
struct Fan {
    t: Tri,
    path: u32,
    blocks: u32,
};

fn store_record(r: u32, t: Tri) {
    let i = 4u * r;
    records[i] = bitcast<vec4<u32>>(vec4<i32>(t.a, t.b));
    records[i + 1u] = vec4<u32>(bitcast<vec2<u32>>(t.c), pack_point(t.box.xy), pack_point(t.box.zw));
    records[i + 2u] = vec4<u32>(bitcast<vec3<u32>>(t.sa), bitcast<u32>(t.dz.x));
    records[i + 3u] = vec4<u32>(bitcast<u32>(t.dz.y), t.id, t.flags, t.member);
}

fn clip_position(v: u32) -> vec4<f32> {
    let b = VERTEX_FLOATS * v;
    let p = vec3<f32>(vertices[b], vertices[b + 1u], vertices[b + 2u]);
    return frame.view_proj * vec4<f32>(p, 1.0);
}

#if GLASS
fn glass_clip_position(v: u32) -> vec4<f32> {
    let b = VERTEX_FLOATS * v;
    let p = vec3<f32>(glass_vertices[b], glass_vertices[b + 1u], glass_vertices[b + 2u]);
    return frame.view_proj * vec4<f32>(p, 1.0);
}
#endif

// Framebuffer position (x right, y down, pixels) and depth, as the viewport transform.
fn to_screen(c: vec4<f32>) -> vec3<f32> {
    let ndc = c.xyz * (1.0 / c.w);
    let half = vec2<f32>(raster_params.zw) * 0.5;
    return vec3<f32>(ndc.x * half.x + half.x, ndc.y * -half.y + half.y, ndc.z);
}

// Pixels whose centres lie in [lo, hi] (fixed point), clamped to the viewport; empty
// when x > z or y > w.
fn pixel_box(lo: vec2<i32>, hi: vec2<i32>) -> vec4<i32> {
    // ceil((lo - 128) / 256) and floor((hi - 128) / 256), with arithmetic shifts.
    let first = -((vec2<i32>(HALF_PIXEL) - lo) >> vec2<u32>(8u));
    let last = (hi - vec2<i32>(HALF_PIXEL)) >> vec2<u32>(8u);
    let size = vec2<i32>(raster_params.zw);
    return vec4<i32>(max(first, vec2<i32>(0)), min(last, size - 1));
}

fn within_linear_range(p: vec2<i32>) -> bool {
    return all(abs(p) < vec2<i32>(LINEAR_RANGE));
}

// Whether setup lists the blocks of fan triangles within 2×2 blocks itself (bit 0 of
// list_capacity.w; off under the test hook's `direct=0`).
fn blocks_direct() -> bool {
    return (list_capacity.w & 1u) != 0u;
}

// Most pixels in the box of a fan triangle its setup thread covers itself (the rest of
// list_capacity.w): SMALL_PIXELS of compute_raster/prepare.rs, 16 (0 under `direct=0`;
// the test hook's `small=N` sets it, to measure). Listed, such a triangle costs a
// 64-byte record, two or three same-address atomics and a 64-thread raster block for
// each 8×8 block its box touches (one to four for a box of a few pixels: 64 to 256
// invocations for its 1 to 16 pixels), plus a 64-thread slice of a bin workgroup on the
// tiled path. Here it costs at most 16 pixel tests in one thread. A warp's lanes run
// together, so a warp of small triangles takes as long as its largest box: 16 steps for
// 32 triangles where listing them costs at least 64 warp-steps of raster (one block
// each). At 64 pixels (an 8×8 box) the serial walk would cost a warp as much as the best
// case of listing, without its parallelism: 16 keeps a 4× margin for warps whose boxes
// differ. The walk's loop runs at most 16 iterations a fan triangle (256 at the hook's
// most), far from lavapipe's loop limit (see `raster_region`).
fn small_pixels() -> i32 {
    return i32(list_capacity.w >> 1u);
}

// The blocks of `t`'s 2×2 from its box's first block that lie in the box and that its
// edges may reach (bin's test), as `Fan.blocks`.
fn reached_blocks(t: Tri) -> u32 {
    let first = vec2<u32>(t.box.xy) / BLOCK;
    var mask = 0u;
    for (var k = 0u; k < 4u; k++) {
        let region = cell_region(t.box, first + vec2<u32>(k & 1u, k >> 1u), BLOCK);
        if (region.x <= region.z && region.y <= region.w && may_cover(t, region)) {
            mask |= 1u << k;
        }
    }
    return mask;
}

// One fan triangle set up: rejected (PATH_NONE), or ready with the path that draws it.
fn prepare_fan(ca: vec4<f32>, cb: vec4<f32>, cc: vec4<f32>, id: u32, cull_back: bool) -> Fan {
    var fan: Fan;
    fan.path = PATH_NONE;
    let s = snap_triangle(to_screen(ca), to_screen(cb), to_screen(cc));
    if (s.facing == 0 || (s.facing > 0 && cull_back)) {
        return fan;
    }
    let a = s.a;
    let b = s.b;
    let c = s.c;
    let box = pixel_box(min(a, min(b, c)), max(a, max(b, c)));
    if (box.x > box.z || box.y > box.w) {
        return fan;
    }
    var t: Tri;
    t.a = a;
    t.b = b;
    t.c = c;
    // Edge biases: a centre exactly on an edge counts only on top and left edges.
    t.flags = select(1u, 0u, top_left(b, c)) | select(2u, 0u, top_left(c, a)) | select(4u, 0u, top_left(a, b));
    if (within_linear_range(a) && within_linear_range(b) && within_linear_range(c)) {
        t.flags |= RECORD_LINEAR;
    }
    t.bias = -vec3<i32>(vec3<u32>(t.flags, t.flags >> 1u, t.flags >> 2u) & vec3<u32>(1u));
    t.sa = s.sa;
    // Depth plane from the unsnapped positions.
    t.dz = depth_slopes(s);
    t.box = box;
    t.id = id;
    fan.t = t;
    fan.path = PATH_TILES;
    // Width and height first: their product could wrap for a viewport-sized box.
    let size = box.zw - box.xy + vec2<i32>(1);
    let small = small_pixels();
    let blocks = vec2<u32>(box.zw) / BLOCK - vec2<u32>(box.xy) / BLOCK;
    if (all(size <= vec2<i32>(small)) && size.x * size.y <= small) {
        fan.path = PATH_SMALL;
    } else if (blocks_direct() && all(blocks <= vec2<u32>(1u))) {
        fan.blocks = reached_blocks(t);
        // No pixel centre inside: nothing to list.
        fan.path = select(PATH_NONE, PATH_BLOCKS, fan.blocks != 0u);
    }
    return fan;
}

// Setup's reservations, shared by the workgroup: what each thread needs of each counter
// (`group_need`, its offset in the workgroup's share returned by `group_add`), then the
// share's first slot (`group_first`), written by thread 0 with one global atomic.
var<workgroup> group_need: array<atomic<u32>, 8>;
var<workgroup> group_first: array<u32, 8>;

fn group_add(counter: u32, n: u32) -> u32 {
    var offset = 0u;
    if (n > 0u) {
        offset = atomicAdd(&group_need[counter], n);
    }
    return offset;
}

// Thread 0, between the barriers: the workgroup's need of `counter` added to it (and the
// need cleared for the next round). Returns the share's first slot and size.
fn group_commit(counter: u32) -> vec2<u32> {
    let n = atomicExchange(&group_need[counter], 0u);
    var first = 0u;
    if (n > 0u) {
        first = atomicAdd(&counters[counter], n);
    }
    group_first[counter] = first;
    return vec2<u32>(first, n);
}

// Enough bin workgroups for every tile entry below min(first + n, capacity).
fn grow_tile_args(first: u32, n: u32) {
    let end = min(first + n, list_capacity.y);
    if (end > first) {
        let size = dispatch_size(end, TILES_PER_GROUP);
        atomicMax(&tile_args[0], size.x);
        atomicMax(&tile_args[1], size.y);
    }
}

// Enough raster workgroups for every block entry below min(first + n, capacity).
fn grow_block_args(first: u32, n: u32) {
    let end = min(first + n, list_capacity.z);
    if (end > first) {
        let size = dispatch_size(end, BLOCKS_PER_GROUP);
        atomicMax(&block_args[0], size.x);
        atomicMax(&block_args[1], size.y);
    }
}

// The first round of a fan triangle's reservations, every thread of the workgroup
// together: a record slot where `path` lists the triangle (the returned slot; at or past
// the capacity: no room), and the counts of the direct paths. The record counter grows
// by at most 6 per triangle (fan triangles of a triangle clipped by five planes), and
// compute_raster.rs refuses scenes of over 2^32 / 8 triangles: it never wraps, nor do
// the direct paths' counts.
fn reserve_record(path: u32, local: u32) -> u32 {
    let offset = group_add(RECORDS, u32(path == PATH_BLOCKS || path == PATH_TILES));
    _ = group_add(SMALL_TRIANGLES, u32(path == PATH_SMALL));
    _ = group_add(BLOCK_TRIANGLES, u32(path == PATH_BLOCKS));
    workgroupBarrier();
    if (local == 0u) {
        _ = group_commit(RECORDS);
        _ = group_commit(SMALL_TRIANGLES);
        _ = group_commit(BLOCK_TRIANGLES);
    }
    return workgroupUniformLoad(&group_first[RECORDS]) + offset;
}

// The second round: `tiles` tile entries and `blocks` block entries; their first slots
// (at or past a capacity: no room). Only fan triangles with a record ask, at most
// UNCHECKED_TILES tiles or 4 blocks each, and records are at most 2^22
// (compute_raster.rs): setup adds under 2^26 tiles and 2^24 blocks, and bin at most 64
// blocks per tile entry with room (under 2^24): no counter wraps.
fn reserve_entries(tiles: u32, blocks: u32, local: u32) -> vec2<u32> {
    let offset = vec2<u32>(group_add(TILES, tiles), group_add(BLOCKS, blocks));
    workgroupBarrier();
    if (local == 0u) {
        let t = group_commit(TILES);
        grow_tile_args(t.x, t.y);
        let b = group_commit(BLOCKS);
        grow_block_args(b.x, b.y);
    }
    workgroupBarrier();
    return vec2<u32>(group_first[TILES], group_first[BLOCKS]) + offset;
}

// `n` (over UNCHECKED_TILES) tile entries reserved by this thread alone, only while the
// count is below the capacity (compare-exchange): it adds at most 2^20 tiles (65,536²
// pixels) to a count under 2^26, so it never wraps. Returns the first slot (the capacity
// where there was no room).
fn reserve_many_tiles(n: u32) -> u32 {
    let capacity = list_capacity.y;
    var first = capacity;
    var old = atomicLoad(&counters[TILES]);
    loop {
        if (old >= capacity) {
            break;
        }
        let swap = atomicCompareExchangeWeak(&counters[TILES], old, old + n);
        if (swap.exchanged) {
            first = old;
            break;
        }
        old = swap.old_value;
    }
    grow_tile_args(first, n);
    return first;
}

// The tiles of `t`'s box listed for record `r` from slot `slot` on; those without room
// rasterized here, counted.
fn list_tiles(t: Tri, r: u32, slot: u32) {
    let first = vec2<u32>(t.box.xy) / TILE_PIXELS;
    let last = vec2<u32>(t.box.zw) / TILE_PIXELS;
    let capacity = list_capacity.y;
    var s = slot;
    var serial = 0u;
    for (var ty = first.y; ty <= last.y; ty++) {
        for (var tx = first.x; tx <= last.x; tx++) {
            if (s < capacity) {
                tiles[s] = vec2<u32>(r, tx | (ty << 16u));
                s++;
            } else {
                serial++;
                raster_region(t, cell_region(t.box, vec2<u32>(tx, ty), TILE_PIXELS));
            }
        }
    }
    if (serial > 0u) {
        atomicAdd(&counters[SERIAL_TILES], serial);
    }
}

// The blocks of `mask` (`Fan.blocks`) listed for record `r` from slot `slot` on; those
// without room rasterized here, counted, as bin does.
fn list_blocks(t: Tri, r: u32, mask: u32, slot: u32) {
    let first = vec2<u32>(t.box.xy) / BLOCK;
    let capacity = list_capacity.z;
    var s = slot;
    var serial = 0u;
    for (var k = 0u; k < 4u; k++) {
        if ((mask & (1u << k)) == 0u) {
            continue;
        }
        let block = first + vec2<u32>(k & 1u, k >> 1u);
        if (s < capacity) {
            blocks[s] = vec2<u32>(r, block.x | (block.y << 16u));
        } else {
            serial++;
            raster_region(t, cell_region(t.box, block, BLOCK));
        }
        s++;
    }
    if (serial > 0u) {
        atomicAdd(&counters[SERIAL_BLOCKS], serial);
    }
}

// Draws or lists `fan` (PATH_NONE: nothing). Every thread of the workgroup calls it
// together: the reservations' barriers are shared.
fn draw_fan(fan: Fan, local: u32) {
    let t = fan.t;
    var path = fan.path;
    if (path == PATH_SMALL) {
        raster_region(t, t.box);
    }
    let r = reserve_record(path, local);
    if (path == PATH_BLOCKS || path == PATH_TILES) {
        if (r < list_capacity.x) {
            store_record(r, t);
        } else {
            // No room for a record: the whole box here, counted.
            atomicAdd(&counters[SERIAL_TRIANGLES], 1u);
            raster_region(t, t.box);
            path = PATH_NONE;
        }
    }
    let tile_span = vec2<u32>(t.box.zw) / TILE_PIXELS - vec2<u32>(t.box.xy) / TILE_PIXELS + vec2<u32>(1u);
    let tile_count = tile_span.x * tile_span.y;
    var tiles = 0u;
    var blocks = 0u;
    if (path == PATH_TILES && tile_count <= UNCHECKED_TILES) {
        tiles = tile_count;
    }
    if (path == PATH_BLOCKS) {
        blocks = countOneBits(fan.blocks);
    }
    let slots = reserve_entries(tiles, blocks, local);
    if (path == PATH_BLOCKS) {
        list_blocks(t, r, fan.blocks, slots.y);
    }
    if (path == PATH_TILES) {
        var first = slots.x;
        if (tile_count > UNCHECKED_TILES) {
            first = reserve_many_tiles(tile_count);
        }
        list_tiles(t, r, first);
    }
}

var<workgroup> group_fans: atomic<u32>;
var<workgroup> group_rounds: u32;

@compute @workgroup_size(GROUP)
fn setup(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    // No early return: every thread reaches the reservations' barriers.
#if FOLDED
    let id = flat_index(wg, groups, local, GROUP);
    let drawn = id < raster_params.x;
    let alpha = drawn && (alpha_tested[id / 32u] & (1u << (id % 32u))) != 0u;
    var member = 0u;
    if (alpha) {
        member = masked_member(0u, id);
    }
#else
#if ALPHA_TEST
    let thread = flat_index(wg, groups, local, GROUP);
    let member = masked_member(1u, thread);
    let id = masked_members[member].x + (thread - masked_members[member].y);
    let drawn = thread < MEMBERS_THREADS;
#else
    let id = flat_index(wg, groups, local, GROUP);
    let drawn = id < raster_params.x && (alpha_tested[id / 32u] & (1u << (id % 32u))) == 0u;
#endif
#endif
    var a = vec4<f32>(0.0);
    var b = vec4<f32>(0.0);
    var c = vec4<f32>(0.0);
    var cull_back = false;
    var fans = 0u;
    var clipped = false;
    var poly: Polygon;
#if GLASS
    // Threads past the opaque triangles take the blended ones, both faces.
    let glass = id >= raster_params.x && id - raster_params.x < glass_params.x;
    if (glass) {
        let t = 3u * (id - raster_params.x);
        a = glass_clip_position(glass_triangles[t]);
        b = glass_clip_position(glass_triangles[t + 1u]);
        c = glass_clip_position(glass_triangles[t + 2u]);
    }
    if (drawn || glass) {
#else
    if (drawn) {
#endif
        if (drawn) {
            let t = 3u * id;
            a = clip_position(triangles[t]);
            b = clip_position(triangles[t + 1u]);
            c = clip_position(triangles[t + 2u]);
            cull_back = (single_sided[id / 32u] & (1u << (id % 32u))) != 0u;
        }
        if (!needs_clipping(a, b, c)) {
            fans = 1u;
        } else if (!outside_one_plane(a, b, c)) {
            // (Wholly outside one plane, the clipper would leave nothing.)
            poly = clip_triangle(a, b, c);
            clipped = true;
            fans = max(poly.n, 2u) - 2u;
        }
    }
    // A round per fan triangle: one unless a triangle of the workgroup is clipped.
    atomicMax(&group_fans, fans);
    workgroupBarrier();
    if (local == 0u) {
        group_rounds = atomicLoad(&group_fans);
    }
    let rounds = workgroupUniformLoad(&group_rounds);
    for (var k = 0u; k < rounds; k++) {
        var fan: Fan;
        fan.path = PATH_NONE;
        if (k < fans) {
            if (clipped) {
                fan = prepare_fan(poly.v[0], poly.v[k + 1u], poly.v[k + 2u], id, cull_back);
            } else {
                fan = prepare_fan(a, b, c, id, cull_back);
            }
#if ALPHA_TEST
            fan.t.member = member;
#endif
#if FOLDED
            fan.t.flags |= select(0u, RECORD_ALPHA, alpha);
#endif
#if GLASS
            fan.t.flags |= select(0u, RECORD_GLASS, glass);
#endif
        }
        draw_fan(fan, local);
    }
}
