// Light linked list build (Bezrati, "Real-Time Lighting via Light Linked List") in compute: one invocation per list pixel (a
// SCALE×SCALE block of the output). The seed rasterises light shells (front faces give
// the near depth, back faces the far depth and a link); here the list pixel's centre
// ray is intersected with each light's bounding sphere directly, which gives the same
// span without shell tessellation, without a bounds buffer, and without the near-plane
// case (a span that starts behind the eye starts at 0). The software depth test is the
// seed's: a light whose span starts behind the block's farthest depth (the max
// downsample) gets no link.
// Candidates are the lights of the block's tile list (LIGHT_LISTS) or every light.
// Links keep the candidates' ascending order. Each invocation counts its links, the
// workgroup sums them and reserves one run of the pool with one global atomic; links
// past the pool are dropped and counted (header: wanted, dropped, pixels that lost
// links, longest list wanted).
// Defines: SCALE (1, 2, 4 or 8), LIGHT_LISTS, FLOAT_DEPTH (the depth is R32Float: a
// compute resolve's, read as texture_2d<f32>).

#include "common/types.wgsl"
#include "common/view_space.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> light_geometry: array<LightGeometry>;
#if FLOAT_DEPTH
@group(0) @binding(2) var depth: texture_2d<f32>;
#else
@group(0) @binding(2) var depth: texture_depth_2d;
#endif
#if LIGHT_LISTS
@group(0) @binding(3) var<storage, read> light_lists: array<u32>;
@group(0) @binding(4) var<uniform> list_params: ListParams;
#endif
@group(0) @binding(5) var<storage, read_write> light_links: array<atomic<u32>>;
@group(0) @binding(6) var<uniform> link_params: LinkParams;

#include "common/light_lists.wgsl"

var<workgroup> group_links: atomic<u32>;
var<workgroup> group_base: u32;

// Largest finite f16.
const F16_MAX: f32 = 65504.0;

// f16 bits of the largest f16 at most x (x >= 0): spans only ever grow by rounding.
fn f16_down(x: f32) -> u32 {
    let b = pack2x16float(vec2<f32>(min(x, F16_MAX), 0.0)) & 0xffffu;
    let back = unpack2x16float(b).x;
    return select(b, b - 1u, back > x && b > 0u);
}

// f16 bits of the smallest f16 at least x (x >= 0); infinity past F16_MAX.
fn f16_up(x: f32) -> u32 {
    if (x > F16_MAX) {
        return 0x7c00u;
    }
    let b = pack2x16float(vec2<f32>(x, 0.0)) & 0xffffu;
    let back = unpack2x16float(b).x;
    return select(b, b + 1u, back < x);
}

// The view-depth span [near, far] where the ray t·dir (dir.z = -1, so t is the view
// depth) crosses light `i`'s bounding sphere; near > far if it misses.
fn light_span(i: u32, dir: vec3<f32>) -> vec2<f32> {
    let g = light_geometry[i];
    let pos = (frame.view * vec4<f32>(g.position, 1.0)).xyz;
    var center = pos;
    var radius = g.range;
    if (g.cos_outer > -1.0) {
        // A spot's tighter sphere around its cone and cap (as light culling bounds it).
        let axis = (frame.view * vec4<f32>(g.direction, 0.0)).xyz;
        let c = max(g.cos_outer, 0.0);
        let s = sqrt(max(1.0 - c * c, 0.0));
        if (c < 0.70710678) {
            center = pos + axis * (g.range * c);
            radius = g.range * s;
        } else {
            radius = g.range / (2.0 * c);
            center = pos + axis * radius;
        }
    }
    // Float slack, as culling's: a surface point a rounding off the ray, or just inside
    // the range, keeps its light.
    radius = radius * 1.0001 + 1e-5 + 1e-4 * length(center);
    let a = dot(dir, dir);
    let b = dot(dir, center);
    let disc = b * b - a * (dot(center, center) - radius * radius);
    if (disc < 0.0) {
        return vec2<f32>(1.0, 0.0);
    }
    let root = sqrt(disc);
    return vec2<f32>((b - root) / a, (b + root) / a);
}

@compute @workgroup_size(8, 8, 1)
fn main(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    if (local == 0u) {
        atomicStore(&group_links, 0u);
    }
    workgroupBarrier();
    // Every invocation reaches the barriers; those outside the lists count no links.
    let inside = id.x < link_params.width && id.y < link_params.height;
    let origin = id.xy * SCALE;
    let block = vec2<f32>(min(vec2<u32>(SCALE), frame.size - min(origin, frame.size)));
    // 1. The block's farthest depth (the seed's max downsample), and its centre ray.
    var z_max = 0.0;
    if (inside) {
        for (var y = 0u; y < SCALE; y++) {
            for (var x = 0u; x < SCALE; x++) {
                let p = origin + vec2<u32>(x, y);
                if (all(p < frame.size)) {
#if FLOAT_DEPTH
                    z_max = max(z_max, view_depth(textureLoad(depth, p, 0).x));
#else
                    z_max = max(z_max, view_depth(textureLoad(depth, p, 0)));
#endif
                }
            }
        }
    }
    let ray = view_ray(vec2<f32>(origin) + 0.5 * block);
    let dir = ray / -ray.z;
    var r = LightRange(0u, 0u);
    if (inside) {
        r = light_range(vec2<f32>(origin) + 0.5, z_max);
    }
    // 2. Count this pixel's links.
    var n = 0u;
    for (var k = 0u; k < r.count; k++) {
        let span = light_span(light_at(r, k), dir);
        if (span.x <= span.y && span.y >= 0.0 && span.x <= z_max) {
            n += 1u;
        }
    }
    // 3. One reservation per workgroup.
    let offset = atomicAdd(&group_links, n);
    workgroupBarrier();
    if (local == 0u) {
        group_base = atomicAdd(&light_links[0], atomicLoad(&group_links));
    }
    let base = workgroupUniformLoad(&group_base) + offset;
    if (!inside) {
        return;
    }
    let pool = link_params.pool;
    let kept = min(n, select(0u, pool - base, base < pool));
    if (kept < n) {
        atomicAdd(&light_links[1], n - kept);
        atomicAdd(&light_links[2], 1u);
    }
    atomicMax(&light_links[3], n);
    atomicStore(&light_links[LINK_HEADER_WORDS + id.y * link_params.width + id.x], select(LINK_END, base, kept > 0u));
    // 4. The links, in candidate order, each pointing at the next.
    var j = 0u;
    for (var k = 0u; k < r.count && j < kept; k++) {
        let i = light_at(r, k);
        let span = light_span(i, dir);
        if (span.x <= span.y && span.y >= 0.0 && span.x <= z_max) {
            let w = link_params.pool_offset + LINK_WORDS * (base + j);
            let depths = f16_down(max(span.x, 0.0)) | (f16_up(span.y) << 16u);
            atomicStore(&light_links[w], depths);
            atomicStore(&light_links[w + 1u], i);
            atomicStore(&light_links[w + 2u], select(LINK_END, base + j + 1u, j + 1u < kept));
            j += 1u;
        }
    }
}
