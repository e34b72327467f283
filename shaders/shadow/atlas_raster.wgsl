// The shadow atlas's compute raster (ShadowAtlas with raster: Compute): every view's
// casters rasterized in compute, off the raster units (a GH100 runs graphics on a few of
// its SMs and compute on all). Depth only, as the hardware atlas: a 32-bit atomic min of
// the depth's bits per texel (non-negative floats order as their bits), so the result
// does not depend on the order triangles land in.
//
// Per (view, triangle) pair, as the raster pipeline does for a depth-only draw into the
// view's viewport: clip space from the view table's view-projection (the vertex stage's
// expression), clipped against the near plane and the viewport's sides where a vertex
// lies outside, vertices snapped to 1/256 texel in atlas coordinates, both faces drawn,
// texel centres tested with exact 64-bit edge functions and the top-left rule, depth
// from the triangle's plane, texels past the far plane dropped, then the pipeline's
// depth bias (Vulkan's: DEPTH_BIAS units of 2^(e − 23), e the exponent of the largest
// vertex depth, plus SLOPE_BIAS × the larger depth slope) and the clamp to [0, 1].
// (visibility/compute_raster.wgsl is the frame's twin; this one has no ids and draws
// into many small viewports.)
//
// Three dispatches:
// - `setup` (SETUP), a thread per pair: the pair's job found by binary search in `jobs`
//   (runs of one view's consecutive triangles, as the hardware path draws them); clip,
//   snap; a fan triangle whose texel box holds at most SMALL_BOX texels is rasterized in
//   the thread, a larger one recorded with an entry per CELL² cell its edges may reach.
// - `raster` (RASTER, indirect), a workgroup per cell entry, four texels a thread.
// - `store` (STORE), a workgroup per STORE_CELL² piece of a drawn view: the depth
//   buffer's texels into the R32Float atlas, and the buffer back to the far depth, so it
//   is clear for the next frame's views (it starts so).
// A full list loses nothing: the thread rasterizes the triangle or cell itself, counted.
//
// The reflective shadow maps' compute raster (ReflectiveShadowMaps with raster: Compute,
// indirect/rsm_raster.wgsl) runs `setup` and `raster` twice over its views (VIEW_VEC4S
// words a view in its table, no depth bias): first for the depth as here, then with IDS
// for the nearest triangle: each covered texel whose depth bits equal the buffer's
// (the same arithmetic gives the same bits) takes the larger visibility id + 1
// (`tri_ids`: the triangles are in shadow chunk order) by a 32-bit atomic max in `ids`,
// as the raster pipeline's LessEqual test keeps the later draw of equal depth. Two 32-bit passes instead of one 64-bit atomic of (depth, id): no device
// feature needed, and the views are small, so the second pass costs little.
//
// Alpha-masked casters (ALPHA_TEST, with MATERIAL_INDEX and its material code): `setup`
// and `raster` run again per masked material over its triangles only (their own jobs,
// from `params.capacity.z`), after the opaque run. A covered texel nearer than what the
// buffer holds (with IDS: at the depth it holds) is rebuilt as visibility shading
// rebuilds a pixel (visibility/surface.wgsl through the view's view-projection, the
// view's tile as the frame) and kept only where the material's alpha reaches its
// cutoff, as the hardware pass's fragment stage discards below it.

struct Params {
    // Pairs, jobs, workgroups per dispatch dimension, atlas side.
    work: vec4<u32>,
    // Capacities of the record and cell lists; the run's first job; unused.
    capacity: vec4<u32>,
};

@group(0) @binding(0) var<uniform> params: Params;
#if STORE
// Pieces (x, y, side) of the drawn views, side at most STORE_CELL.
@group(0) @binding(5) var<storage, read> pieces: array<vec4<u32>>;
@group(0) @binding(6) var<storage, read_write> depth: array<u32>;
@group(0) @binding(11) var atlas: texture_storage_2d<r32float, write>;
#else
#if IDS
// The first pass's depths (read only) and the nearest triangle's id + 1 (0: none).
@group(0) @binding(6) var<storage, read> depth: array<u32>;
@group(0) @binding(12) var<storage, read_write> ids: array<atomic<u32>>;
#else
@group(0) @binding(6) var<storage, read_write> depth: array<atomic<u32>>;
#endif
#if TRI_IDS
// Setup's, per triangle of `indices`, its visibility id: what `ids` keeps (IDS), the
// triangle of the merged geometry the alpha test rebuilds (ALPHA_TEST).
@group(0) @binding(13) var<storage, read> tri_ids: array<u32>;
#endif
#if ALPHA_TEST
#include "common/types.wgsl"
@group(0) @binding(14) var<storage, read> vertices: array<f32>;
@group(0) @binding(15) var<storage, read> triangles: array<u32>;
#if RASTER
@group(0) @binding(1) var<storage, read> shadow_views: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> rects: array<vec4<u32>>;
#endif
#endif
#if SETUP
@group(0) @binding(1) var<storage, read> shadow_views: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> positions: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> indices: array<u32>;
// (first pair, first triangle, triangles, view), by first pair.
@group(0) @binding(4) var<storage, read> jobs: array<vec4<u32>>;
// Per view: its tile's x, y and side in the atlas.
@group(0) @binding(5) var<storage, read> rects: array<vec4<u32>>;
@group(0) @binding(7) var<storage, read_write> records: array<vec4<u32>>;
@group(0) @binding(8) var<storage, read_write> cells: array<vec2<u32>>;
@group(0) @binding(9) var<storage, read_write> counters: array<atomic<u32>, 4>;
@group(0) @binding(10) var<storage, read_write> args: array<atomic<u32>, 4>;
#endif
#if RASTER
@group(0) @binding(7) var<storage, read> records: array<vec4<u32>>;
@group(0) @binding(8) var<storage, read> cells: array<vec2<u32>>;
@group(0) @binding(9) var<storage, read> counters: array<u32, 4>;
#endif
#endif

#include "common/triangle_setup.wgsl"

// Half a texel in snapped (1/SUBPIXEL) units: texel centres.
const HALF_TEXEL: i32 = 128;
// Texels a fan triangle's box may hold to be rasterized in its setup thread.
const SMALL_BOX: i32 = 64;
// Texels per side of a cell entry (a 256-thread workgroup, four texels a thread).
const CELL: u32 = 32u;
const CELL_THREADS: u32 = 256u;
// Counter slots: records and cells appended (past the capacity too), then fan triangles
// and cells rasterized in setup because their list was full.
const RECORDS: u32 = 0u;
const CELLS: u32 = 1u;
const SERIAL_TRIANGLES: u32 = 2u;
const SERIAL_CELLS: u32 = 3u;
const FAR_BITS: u32 = 0x3f800000u;

#if STORE
@compute @workgroup_size(STORE_CELL, STORE_CELL)
fn store(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_id) local: vec3<u32>,
) {
    let i = wg.y * params.work.z + wg.x;
    if (i >= params.work.x) {
        return;
    }
    let piece = pieces[i];
    if (any(local.xy >= vec2<u32>(piece.z))) {
        return;
    }
    let p = piece.xy + local.xy;
    let at = p.y * params.work.w + p.x;
    textureStore(atlas, vec2<i32>(p), vec4<f32>(bitcast<f32>(depth[at]), 0.0, 0.0, 0.0));
    depth[at] = FAR_BITS;
}
#else

struct Tri {
    // Snapped vertices (1/256 texel, atlas coordinates).
    a: vec2<i32>,
    b: vec2<i32>,
    c: vec2<i32>,
    // -1 on the edges b -> c, c -> a, a -> b that are not top or left edges, else 0.
    bias: vec3<i32>,
    // The first vertex unsnapped (x, y in texels, depth), the depth's slopes.
    sa: vec3<f32>,
    dz: vec2<f32>,
    // The depth bias, added to every texel's depth.
    offset: f32,
    // Texels whose centres lie in the vertices' box, within the view's tile.
    box: vec4<i32>,
    // IDS: the triangle's id (`tri_ids`), what a texel it is nearest in keeps; with
    // ALPHA_TEST also the triangle the alpha test rebuilds, in view `view`.
    id: u32,
    view: u32,
};

#if ALPHA_TEST
// The view's tile stands for the frame in visibility/surface.wgsl: its view-projection
// and size (set per texel before the rebuild).
var<private> frame: Frame;
#include "visibility/surface.wgsl"
#include <material>

// Whether `t`'s material keeps texel (px, py): its alpha there reaches the cutoff.
fn alpha_keeps(t: Tri, px: i32, py: i32) -> bool {
    let rect = rects[t.view];
    let base = 1u + VIEW_VEC4S * t.view;
    frame.view_proj = mat4x4<f32>(shadow_views[base], shadow_views[base + 1u], shadow_views[base + 2u], shadow_views[base + 3u]);
    frame.size = vec2<u32>(rect.z);
    let p = surface_point(vec2<u32>(vec2<i32>(px, py) - vec2<i32>(rect.xy)), t.id);
    return material_alpha(material_setup(p)) >= MATERIAL_ALPHA_CUTOFF;
}
#endif

// Texel (px, py) of `t`, if its centre is covered and its depth within the far plane.
fn cover(t: Tri, px: i32, py: i32) {
    let p = vec2<i32>(px, py) * 256 + vec2<i32>(HALF_TEXEL);
    if (edge(t.b, t.c, p) + i64(t.bias.x) < 0 || edge(t.c, t.a, p) + i64(t.bias.y) < 0 || edge(t.a, t.b, p) + i64(t.bias.z) < 0) {
        return;
    }
    let centre = vec2<f32>(f32(px) + 0.5, f32(py) + 0.5);
    let z = t.sa.z + t.dz.x * (centre.x - t.sa.x) + t.dz.y * (centre.y - t.sa.y);
    if (!(z <= 1.0)) {
        return;
    }
    let d = min(z + t.offset, 1.0);
    // Clamped at 0 (also -0.0, whose bits would order last).
    let bits = select(bitcast<u32>(d), 0u, !(d > 0.0));
    let at = u32(py) * params.work.w + u32(px);
#if IDS
    if (bits != depth[at]) {
        return;
    }
#if ALPHA_TEST
    if (!alpha_keeps(t, px, py)) {
        return;
    }
#endif
    atomicMax(&ids[at], t.id + 1u);
#else
#if ALPHA_TEST
    // The material only where it could win: at or behind what the buffer holds, the
    // min would keep that anyway.
    if (bits >= atomicLoad(&depth[at]) || !alpha_keeps(t, px, py)) {
        return;
    }
#endif
    atomicMin(&depth[at], bits);
#endif
}

// Every texel of `region` (x0, y0, x1, y1, inclusive) in this thread.
fn raster_region(t: Tri, region: vec4<i32>) {
    for (var y = region.y; y <= region.w; y++) {
        for (var x = region.x; x <= region.z; x++) {
            cover(t, x, y);
        }
    }
}

fn pack_point(p: vec2<i32>) -> u32 {
    return u32(p.x) | (u32(p.y) << 16u);
}

fn unpack_point(v: u32) -> vec2<i32> {
    return vec2<i32>(vec2<u32>(v & 0xffffu, v >> 16u));
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
    t.box = vec4<i32>(unpack_point(w1.z), unpack_point(w1.w));
    t.sa = bitcast<vec3<f32>>(w2.xyz);
    t.dz = vec2<f32>(bitcast<f32>(w2.w), bitcast<f32>(w3.x));
    t.offset = bitcast<f32>(w3.y);
    t.bias = -vec3<i32>(vec3<u32>(w3.z, w3.z >> 1u, w3.z >> 2u) & vec3<u32>(1u));
    t.view = w3.z >> 3u;
    t.id = w3.w;
    return t;
}

// The texels of cell `cell` within the triangle's box.
fn cell_region(box: vec4<i32>, cell: vec2<u32>) -> vec4<i32> {
    let lo = vec2<i32>(cell * CELL);
    let hi = lo + vec2<i32>(i32(CELL) - 1);
    return vec4<i32>(max(lo, box.xy), min(hi, box.zw));
}

#if SETUP

fn store_record(r: u32, t: Tri) {
    let i = 4u * r;
    // The top-left biases in bits 0..2, the view above them.
    let flags = u32(-t.bias.x) | (u32(-t.bias.y) << 1u) | (u32(-t.bias.z) << 2u) | (t.view << 3u);
    records[i] = bitcast<vec4<u32>>(vec4<i32>(t.a, t.b));
    records[i + 1u] = vec4<u32>(bitcast<vec2<u32>>(t.c), pack_point(t.box.xy), pack_point(t.box.zw));
    records[i + 2u] = vec4<u32>(bitcast<vec3<u32>>(t.sa), bitcast<u32>(t.dz.x));
    records[i + 3u] = vec4<u32>(bitcast<u32>(t.dz.y), bitcast<u32>(t.offset), flags, t.id);
}



// Atlas position (texels, y down) and depth, as the viewport transform of the view's
// tile: `rect` is (x, y, side).
fn to_screen(c: vec4<f32>, rect: vec4<u32>) -> vec3<f32> {
    let ndc = c.xyz * (1.0 / c.w);
    let half = f32(rect.z) * 0.5;
    let origin = vec2<f32>(rect.xy) + vec2<f32>(half);
    return vec3<f32>(ndc.x * half + origin.x, ndc.y * -half + origin.y, ndc.z);
}

// Texels whose centres lie in [lo, hi] (fixed point), within the tile.
fn texel_box(lo: vec2<i32>, hi: vec2<i32>, rect: vec4<u32>) -> vec4<i32> {
    let first = -((vec2<i32>(HALF_TEXEL) - lo) >> vec2<u32>(8u));
    let last = (hi - vec2<i32>(HALF_TEXEL)) >> vec2<u32>(8u);
    let tile_lo = vec2<i32>(rect.xy);
    let tile_hi = tile_lo + vec2<i32>(i32(rect.z) - 1);
    return vec4<i32>(max(first, tile_lo), min(last, tile_hi));
}

// Whether some texel centre of `region` may lie inside edge a -> b: its function is not
// negative at the corner where it is largest (exact: the function is linear).
fn edge_reaches(a: vec2<i32>, b: vec2<i32>, bias: i32, lo: vec2<i32>, hi: vec2<i32>) -> bool {
    let p = vec2<i32>(select(lo.x, hi.x, b.y < a.y), select(lo.y, hi.y, b.x > a.x));
    return edge(a, b, p) + i64(bias) >= 0;
}

fn may_cover(t: Tri, region: vec4<i32>) -> bool {
    let lo = region.xy * 256 + vec2<i32>(HALF_TEXEL);
    let hi = region.zw * 256 + vec2<i32>(HALF_TEXEL);
    return edge_reaches(t.b, t.c, t.bias.x, lo, hi) && edge_reaches(t.c, t.a, t.bias.y, lo, hi) && edge_reaches(t.a, t.b, t.bias.z, lo, hi);
}

// The pipeline's depth bias for a triangle of vertex depths `z` and slopes `dz`.
fn depth_bias(z: vec3<f32>, dz: vec2<f32>) -> f32 {
    let top = max(abs(z.x), max(abs(z.y), abs(z.z)));
    // 2^(e − 23): the exponent bits of the largest depth, 23 lower.
    let exponent = bitcast<u32>(top) & 0x7f800000u;
    let unit = select(0.0, bitcast<f32>(exponent - (23u << 23u)), exponent > (23u << 23u));
    return DEPTH_BIAS * unit + SLOPE_BIAS * max(abs(dz.x), abs(dz.y));
}

fn setup_triangle(ca: vec4<f32>, cb: vec4<f32>, cc: vec4<f32>, rect: vec4<u32>, id: u32, view: u32) {
    // Both faces: either facing is drawn, ordered clockwise for the edge tests.
    let s = snap_triangle(to_screen(ca, rect), to_screen(cb, rect), to_screen(cc, rect));
    if (s.facing == 0) {
        return;
    }
    let a = s.a;
    let b = s.b;
    let c = s.c;
    let box = texel_box(min(a, min(b, c)), max(a, max(b, c)), rect);
    if (box.x > box.z || box.y > box.w) {
        return;
    }
    var t: Tri;
    t.a = a;
    t.b = b;
    t.c = c;
    t.bias = -vec3<i32>(select(1, 0, top_left(b, c)), select(1, 0, top_left(c, a)), select(1, 0, top_left(a, b)));
    t.sa = s.sa;
    t.dz = depth_slopes(s);
    t.offset = depth_bias(vec3<f32>(s.sa.z, s.sb.z, s.sc.z), t.dz);
    t.box = box;
    t.id = id;
    t.view = view;
    let size = box.zw - box.xy + vec2<i32>(1);
    if (size.x * size.y <= SMALL_BOX) {
        raster_region(t, box);
        return;
    }
    let r = atomicAdd(&counters[RECORDS], 1u);
    if (r >= params.capacity.x) {
        atomicAdd(&counters[SERIAL_TRIANGLES], 1u);
        raster_region(t, box);
        return;
    }
    store_record(r, t);
    let first = vec2<u32>(box.xy) / CELL;
    let last = vec2<u32>(box.zw) / CELL;
    // Count the cells the edges may reach, reserve them at once, then list them.
    var n = 0u;
    for (var cy = first.y; cy <= last.y; cy++) {
        for (var cx = first.x; cx <= last.x; cx++) {
            n += u32(may_cover(t, cell_region(box, vec2<u32>(cx, cy))));
        }
    }
    if (n == 0u) {
        return;
    }
    // Reserved only while the list has room, so the counter passes the capacity by at
    // most the racing threads' reservations and does not wrap.
    let capacity = params.capacity.y;
    var slot = capacity;
    if (atomicLoad(&counters[CELLS]) < capacity) {
        slot = atomicAdd(&counters[CELLS], n);
    }
    let end = min(slot + n, capacity);
    if (end > slot) {
        let groups = vec2<u32>(min(end, params.work.z), (end + params.work.z - 1u) / params.work.z);
        atomicMax(&args[0], groups.x);
        atomicMax(&args[1], groups.y);
        atomicMax(&args[2], 1u);
    }
    var serial = 0u;
    for (var cy = first.y; cy <= last.y; cy++) {
        for (var cx = first.x; cx <= last.x; cx++) {
            let region = cell_region(box, vec2<u32>(cx, cy));
            if (!may_cover(t, region)) {
                continue;
            }
            if (slot < capacity) {
                cells[slot] = vec2<u32>(r, cx | (cy << 16u));
            } else {
                serial++;
                raster_region(t, region);
            }
            slot++;
        }
    }
    if (serial > 0u) {
        atomicAdd(&counters[SERIAL_CELLS], serial);
    }
}

// The job holding pair `i`: the last whose first pair is at most i.
fn find_job(i: u32) -> u32 {
    var lo = params.capacity.z;
    var hi = lo + params.work.y;
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (jobs[mid].x <= i) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

fn clip_position(view_proj: mat4x4<f32>, v: u32) -> vec4<f32> {
    return view_proj * vec4<f32>(positions[v].xyz, 1.0);
}

@compute @workgroup_size(GROUP)
fn setup(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let i = (wg.y * groups.x + wg.x) * GROUP + local;
    if (i >= params.work.x) {
        return;
    }
    let job = jobs[find_job(i)];
    let tri = job.y + (i - job.x);
    let base = 1u + VIEW_VEC4S * job.w;
    let view_proj = mat4x4<f32>(shadow_views[base], shadow_views[base + 1u], shadow_views[base + 2u], shadow_views[base + 3u]);
    let rect = rects[job.w];
    let a = clip_position(view_proj, indices[3u * tri]);
    let b = clip_position(view_proj, indices[3u * tri + 1u]);
    let c = clip_position(view_proj, indices[3u * tri + 2u]);
#if TRI_IDS
    let id = tri_ids[tri];
#else
    let id = 0u;
#endif
    if (!needs_clipping(a, b, c)) {
        setup_triangle(a, b, c, rect, id, job.w);
        return;
    }
    // Most of a view's triangles lie wholly outside it.
    if (outside_one_plane(a, b, c)) {
        return;
    }
    let poly = clip_triangle(a, b, c);
    for (var k = 1u; k + 1u < poly.n; k++) {
        setup_triangle(poly.v[0], poly.v[k], poly.v[k + 1u], rect, id, job.w);
    }
}
#endif
#if RASTER

// A workgroup per cell entry, four rows of texels a thread.
@compute @workgroup_size(CELL_THREADS)
fn raster(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let i = wg.y * params.work.z + wg.x;
    if (i >= min(counters[CELLS], params.capacity.y)) {
        return;
    }
    let entry = cells[i];
    let t = load_record(entry.x);
    let region = cell_region(t.box, vec2<u32>(unpack_point(entry.y)));
    let rows = CELL_THREADS / CELL;
    let x = region.x - region.x % i32(CELL) + i32(local % CELL);
    let y0 = region.y - region.y % i32(CELL) + i32(local / CELL);
    for (var k = 0u; k < CELL / rows; k++) {
        let y = y0 + i32(k * rows);
        if (x >= region.x && x <= region.z && y >= region.y && y <= region.w) {
            cover(t, x, y);
        }
    }
}
#endif
#endif
