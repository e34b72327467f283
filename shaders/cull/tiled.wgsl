// Tiled light culling (Forward+, seed 000): one workgroup per tile and list. The
// workgroup finds the tile's depth range with atomics on the float bits (depths are
// non-negative, so their bits order like integers), tests every light against the
// tile's frustum, builds the list in workgroup memory in ascending light order, then
// reserves room in the shared pool with one global atomic.
// Defines: TILE (8 or 16), CAPACITY, VARIANT (see types.wgsl).

#include "common/types.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> light_geometry: array<LightGeometry>;
@group(0) @binding(2) var depth: texture_depth_2d;
@group(0) @binding(3) var<storage, read_write> light_lists: array<atomic<u32>>;
@group(0) @binding(4) var<uniform> list_params: ListParams;

const THREADS: u32 = TILE * TILE;
const MASK_WORDS: u32 = THREADS / 32u;
const FAR_BITS: u32 = 0x7f7fffffu;

var<workgroup> z_min_bits: atomic<u32>;
var<workgroup> z_max_bits: atomic<u32>;
var<workgroup> depth_mask: atomic<u32>;
var<workgroup> hits: array<atomic<u32>, MASK_WORDS>;
var<workgroup> list: array<u32, CAPACITY>;
var<workgroup> list_len: u32;
var<workgroup> pool_base: u32;

// Positive view-space distance along -z of a depth-buffer value.
fn view_depth(d: f32) -> f32 {
    let p = frame.inv_proj * vec4<f32>(0.0, 0.0, d, 1.0);
    return -p.z / p.w;
}

// View-space point on the far plane through a framebuffer position.
fn view_ray(pixel: vec2<f32>) -> vec3<f32> {
    let size = vec2<f32>(frame.size);
    let ndc = vec2<f32>(pixel.x / size.x * 2.0 - 1.0, 1.0 - pixel.y / size.y * 2.0);
    let p = frame.inv_proj * vec4<f32>(ndc, 1.0, 1.0);
    return p.xyz / p.w;
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

@compute @workgroup_size(TILE, TILE, 1)
fn main(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(local_invocation_id) lid: vec3<u32>,
) {
    if (local == 0u) {
        atomicStore(&z_min_bits, FAR_BITS);
        atomicStore(&z_max_bits, 0u);
        atomicStore(&depth_mask, 0u);
        list_len = 0u;
    }
    workgroupBarrier();

    // 1. The tile's depth range, over pixels that hold geometry.
    let pixel = group.xy * TILE + lid.xy;
    var z = -1.0;
    if (all(pixel < frame.size)) {
        let d = textureLoad(depth, pixel, 0);
        if (d < 1.0) {
            z = view_depth(d);
            atomicMin(&z_min_bits, bitcast<u32>(z));
            atomicMax(&z_max_bits, bitcast<u32>(z));
        }
    }
    workgroupBarrier();
    let tile_min = bitcast<f32>(atomicLoad(&z_min_bits));
    let tile_max = bitcast<f32>(atomicLoad(&z_max_bits));
    let empty_tile = atomicLoad(&z_max_bits) == 0u;

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
    if (VARIANT == VARIANT_DEPTH_MASK && z >= 0.0) {
        atomicOr(&depth_mask, 1u << cell_of(z, tile_min, tile_max));
    }

    // 3. Side planes through the eye and the tile's edges (normals point inwards).
    let size = vec2<f32>(frame.size);
    let x0 = f32(group.x * TILE);
    let y0 = f32(group.y * TILE);
    let x1 = min(x0 + f32(TILE), size.x);
    let y1 = min(y0 + f32(TILE), size.y);
    let c00 = view_ray(vec2<f32>(x0, y0));
    let c10 = view_ray(vec2<f32>(x1, y0));
    let c11 = view_ray(vec2<f32>(x1, y1));
    let c01 = view_ray(vec2<f32>(x0, y1));
    let planes = array<vec3<f32>, 4>(
        normalize(cross(c00, c10)),
        normalize(cross(c10, c11)),
        normalize(cross(c11, c01)),
        normalize(cross(c01, c00)),
    );
    // Bounding sphere of the tile's frustum slice [lo, hi], for the cone test.
    var tile_center = vec3<f32>(0.0);
    var tile_radius = 0.0;
    if (!empty) {
        var corners: array<vec3<f32>, 8>;
        let rays = array<vec3<f32>, 4>(c00, c10, c11, c01);
        for (var i = 0u; i < 4u; i++) {
            corners[i] = rays[i] * (lo / -rays[i].z);
            corners[i + 4u] = rays[i] * (hi / -rays[i].z);
            tile_center += corners[i] + corners[i + 4u];
        }
        tile_center /= 8.0;
        for (var i = 0u; i < 8u; i++) {
            tile_radius = max(tile_radius, distance(tile_center, corners[i]));
        }
    }
    workgroupBarrier();
    let tile_mask = atomicLoad(&depth_mask);

    // 4. Lights in batches of THREADS; ranks within a batch from a bit mask keep the
    //    list in ascending light order.
    let count = frame.light_count;
    var total = 0u;
    for (var base = 0u; base < count; base += THREADS) {
        if (local < MASK_WORDS) {
            atomicStore(&hits[local], 0u);
        }
        workgroupBarrier();
        let i = base + local;
        var hit = false;
        if (!empty && i < count) {
            hit = light_touches_tile(light_geometry[i], planes, lo, hi, tile_center, tile_radius, tile_mask, tile_min, tile_max);
        }
        if (hit) {
            atomicOr(&hits[local / 32u], 1u << (local % 32u));
        }
        workgroupBarrier();
        if (hit) {
            var rank = 0u;
            let word = local / 32u;
            for (var w = 0u; w < word; w++) {
                rank += countOneBits(atomicLoad(&hits[w]));
            }
            rank += countOneBits(atomicLoad(&hits[word]) & ((1u << (local % 32u)) - 1u));
            let slot = total + rank;
            if (slot < CAPACITY) {
                list[slot] = i;
            }
        }
        var batch = 0u;
        for (var w = 0u; w < MASK_WORDS; w++) {
            batch += countOneBits(atomicLoad(&hits[w]));
        }
        total += batch;
        workgroupBarrier();
    }

    // 5. Reserve room in the pool, publish the entry, copy the list out.
    let list_index = (group.y * list_params.tiles_x + group.x) * list_params.lists_per_tile + group.z;
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
    for (var k = local; k < kept; k += THREADS) {
        atomicStore(&light_lists[base_word + k], list[k]);
    }
}

// Conservative: a light that reaches any point of the tile between lo and hi is kept.
fn light_touches_tile(
    g: LightGeometry,
    planes: array<vec3<f32>, 4>,
    lo: f32,
    hi: f32,
    tile_center: vec3<f32>,
    tile_radius: f32,
    tile_mask: u32,
    tile_min: f32,
    tile_max: f32,
) -> bool {
    let pos = (frame.view * vec4<f32>(g.position, 1.0)).xyz;
    let dir = (frame.view * vec4<f32>(g.direction, 0.0)).xyz;
    let is_spot = g.cos_outer > -1.0;
    // Bounding sphere of the light's volume: the range sphere, or for a spot the
    // tighter sphere around its cone and cap.
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
    radius = radius * 1.0001 + 1e-5;
    let z = -center.z;
    if (z + radius < lo || z - radius > hi) {
        return false;
    }
    for (var p = 0u; p < 4u; p++) {
        if (dot(planes[p], center) < -radius) {
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
    if (is_spot) {
        // Cone against the tile's bounding sphere.
        let v = tile_center - pos;
        let v_len_sq = dot(v, v);
        let v1 = dot(v, dir);
        let c = g.cos_outer;
        let s = sqrt(max(1.0 - c * c, 0.0));
        let closest = c * sqrt(max(v_len_sq - v1 * v1, 0.0)) - v1 * s;
        let r = tile_radius * 1.0001 + 1e-5;
        if (closest > r || v1 > r + g.range || v1 < -r) {
            return false;
        }
    }
    return true;
}
