// VplVisibility: which VPLs each block of VPL_BLOCK×VPL_BLOCK pixels sees. One
// workgroup a block: the covered pixel nearest the block's centre stands for the block;
// its surface (shadow/surface_source.wgsl: a G-buffer or the visibility buffer, as the
// ray-cast shadow passes read it) casts one any-hit ray against the shadow BVH to every
// VPL whose range reaches it. Bit k of the block's VPL_WORDS words is set when VPL k (its
// number in LightProperties._pad0, written by VplSpawn) is visible: in range and
// unoccluded, or out of the point's range (it adds nothing near there; left lit). A VPL
// behind the point's geometric normal is hidden (its light cannot reach that surface).
// VPLs are the lights after the scene's: the last light's number tells how many there are.
// After every block's bits, each block's point: its position and geometric normal, so a
// shading pixel can take the bits of the nearby block whose point lies on its own surface
// (indirect/vpl_lookup.wgsl; the layout: indirect/vpl_layout.wgsl).
// Defines: VPL_BLOCK, VPL_WORDS, SHADOW_NORMAL_OFFSET, VISIBILITY_IDS.

#include "common/types.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> light_geometry: array<LightGeometry>;
@group(0) @binding(2) var<storage, read> light_properties: array<LightProperties>;
@group(0) @binding(5) var<storage, read> bvh_nodes: array<BvhNode>;
@group(0) @binding(6) var<storage, read> bvh_triangles: array<BvhTriangle>;
#if BVH_ALPHA_TEST
@group(0) @binding(8) var<storage, read> bvh_alpha: array<u32>;
#endif
@group(0) @binding(7) var<storage, read_write> vpl_visibility: array<u32>;

#include "shadow/bvh.wgsl"
#include "common/shadows.wgsl"
#include "shadow/surface_source.wgsl"
#include "indirect/vpl_layout.wgsl"

const LIGHT_VPL: u32 = 4u;
// How far off its surface a ray aims at a VPL, in units of its distance clamp: on the
// Cornell box at 64×48 with a ray per pixel (n = 8), relative MSE 0.060 at 0, 0.053 at
// 0.5, 0.054 at 1.
const VPL_TARGET_OFFSET: f32 = 0.5;
const GROUP: u32 = 64u;
const NO_PIXEL: u32 = 0xffffffffu;

var<workgroup> nearest: atomic<u32>;
var<workgroup> bits: array<atomic<u32>, VPL_WORDS>;

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    if (lane == 0u) {
        atomicStore(&nearest, NO_PIXEL);
    }
    for (var w = lane; w < VPL_WORDS; w += GROUP) {
        atomicStore(&bits[w], 0u);
    }
    workgroupBarrier();
    // The covered pixel nearest the centre (squared distance in half pixels, then the
    // pixel's place in the block, so ties go one way).
    let corner = group.xy * VPL_BLOCK;
    for (var k = lane; k < VPL_BLOCK * VPL_BLOCK; k += GROUP) {
        let xy = corner + vec2<u32>(k % VPL_BLOCK, k / VPL_BLOCK);
        if (all(xy < frame.size) && shadow_surface(xy).valid) {
            let d = vec2<i32>(2u * vec2<u32>(k % VPL_BLOCK, k / VPL_BLOCK)) - vec2<i32>(i32(VPL_BLOCK) - 1);
            atomicMin(&nearest, (u32(dot(d, d)) << 16u) | k);
        }
    }
    let found = workgroupUniformLoad(&nearest);
    let block = group.y * vpl_blocks().x + group.x;
    let point = vpl_point_word(block);
    if (found == NO_PIXEL) {
        // Nothing covers the block: no pixel reads its bits, and its point is none.
        if (lane == 0u) {
            vpl_visibility[point + 3u] = 0u;
        }
        return;
    }
    let k = found & 0xffffu;
    let s = shadow_surface(corner + vec2<u32>(k % VPL_BLOCK, k / VPL_BLOCK));
    if (lane == 0u) {
        vpl_visibility[point] = bitcast<u32>(s.position.x);
        vpl_visibility[point + 1u] = bitcast<u32>(s.position.y);
        vpl_visibility[point + 2u] = bitcast<u32>(s.position.z);
        // w = 1: a point (its byte 127, never 0).
        vpl_visibility[point + 3u] = pack4x8snorm(vec4<f32>(s.ng, 1.0));
    }
    let origin = shadow_origin(s.position, s.ng);
    let count = frame.light_count;
    var vpls = 0u;
    if (count > 0u && (light_properties[count - 1u].flags & LIGHT_VPL) != 0u) {
        vpls = light_properties[count - 1u]._pad0 + 1u;
    }
    let first = count - vpls;
    for (var v = lane; v < min(vpls, VPL_WORDS * 32u); v += GROUP) {
        let g = light_geometry[first + v];
        let d = g.position - s.position;
        var visible = dot(d, d) >= g.range * g.range;
        // The ray ends off the VPL's surface, along its normal, by VPL_TARGET_OFFSET times
        // its distance clamp (about the size of patch it stands for): a VPL averaged over
        // a block of map texels that folds round a convex edge lies inside the solid, and
        // a ray to its centre would be hidden by the surface it stands for.
        let aim = g.position + g.direction * (VPL_TARGET_OFFSET * light_properties[first + v].cos_inner);
        if (!visible && shadow_faces(s.position, s.ng, aim)) {
            visible = !bvh_occluded(origin, aim - origin, shadow_t_max(origin, aim));
        }
        if (visible) {
            atomicOr(&bits[v / 32u], 1u << (v % 32u));
        }
    }
    workgroupBarrier();
    let base = block * VPL_WORDS;
    // Only the words of VPLs that exist: no lookup reads past them.
    for (var w = lane; w < min((vpls + 31u) / 32u, VPL_WORDS); w += GROUP) {
        vpl_visibility[base + w] = atomicLoad(&bits[w]);
    }
}


