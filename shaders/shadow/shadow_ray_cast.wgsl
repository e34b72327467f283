// Ray-cast shadows: one invocation per job (pixel, light, caster number), an any-hit
// ray from the pixel's offset position towards the light against the scene BVH; a hit
// sets the caster's bit in the pixel's mask. Dispatched indirectly from the job count.
// The pixel's surface is the one job creation read (from the G-buffer or the visibility
// buffer) and stored after the jobs, once a pixel for all its rays.
// Defines: JOB_CAPACITY, SHADOW_NORMAL_OFFSET.

#include "common/types.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> light_geometry: array<LightGeometry>;
@group(0) @binding(2) var<storage, read> shadow_jobs: array<u32>;
@group(0) @binding(5) var<storage, read> bvh_nodes: array<BvhNode>;
@group(0) @binding(6) var<storage, read> bvh_triangles: array<BvhTriangle>;
#if BVH_ALPHA_TEST
@group(0) @binding(8) var<storage, read> bvh_alpha: array<u32>;
#endif
@group(0) @binding(7) var<storage, read_write> shadow_mask: array<atomic<u32>>;

#include "shadow/bvh.wgsl"
#include "common/shadows.wgsl"

@compute @workgroup_size(SHADOW_CAST_GROUP, 1, 1)
fn main(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let job = (group.y * groups.x + group.x) * SHADOW_CAST_GROUP + local;
    if (job >= min(shadow_jobs[0], JOB_CAPACITY)) {
        return;
    }
    let pixel = shadow_jobs[JOB_HEADER_WORDS + JOB_WORDS * job];
    let packed = shadow_jobs[JOB_HEADER_WORDS + JOB_WORDS * job + 1u];
    let light = packed & 0xffffffu;
    let caster = packed >> 24u;
    let at = JOB_HEADER_WORDS + JOB_WORDS * JOB_CAPACITY + JOB_SURFACE_WORDS * pixel;
    let position = bitcast<vec3<f32>>(vec3<u32>(shadow_jobs[at], shadow_jobs[at + 1u], shadow_jobs[at + 2u]));
    let ng = bitcast<vec3<f32>>(vec3<u32>(shadow_jobs[at + 3u], shadow_jobs[at + 4u], shadow_jobs[at + 5u]));
    let origin = shadow_origin(position, ng);
    let light_pos = light_geometry[light].position;
    if (bvh_occluded(origin, light_pos - origin, shadow_t_max(origin, light_pos))) {
        atomicOr(&shadow_mask[pixel * SHADOW_MASK_WORDS + caster / 32u], 1u << (caster % 32u));
    }
}
