// Ray-cast shadows, shared by job creation (shadow/shadow_ray_jobs.wgsl), casting
// (shadow/shadow_ray_cast.wgsl) and the light loop, so all of them number casters,
// offset origins and test facing the same way.
//
// A pixel's shadow-casting lights are numbered in the order its light list visits them,
// counting only those that reach it (radiance > 0): caster c is bit c of the pixel's
// 128-bit mask (4 words), set when the light is hidden. Casters past the 128th are lit
// unshadowed and counted by job creation (ShadowReport::overflow_pixels).
//
// Defines: SHADOW_NORMAL_OFFSET (origin offset along the geometric normal, relative to
// the position's magnitude), and in the light loop SHADOW_MASK (read the mask) or
// SHADOW_TRACE (cast in the loop: the naive variant; needs the BVH and `shadow_ng`).

const LIGHT_CASTS_SHADOW: u32 = 1u;
const SHADOW_MAX_CASTERS: u32 = 128u;
const SHADOW_MASK_WORDS: u32 = 4u;
// Jobs a workgroup of the casting pass (its dispatch is written by job creation).
const SHADOW_CAST_GROUP: u32 = 64u;

// The shadow ray's origin: off the surface along its geometric normal, by an amount that
// scales with the position's magnitude (float positions are that much less precise).
fn shadow_origin(p: vec3<f32>, ng: vec3<f32>) -> vec3<f32> {
    let scale = max(max(abs(p.x), abs(p.y)), max(abs(p.z), 1.0));
    return p + ng * (SHADOW_NORMAL_OFFSET * scale);
}

// A light behind the surface's face is hidden by the surface itself.
fn shadow_faces(p: vec3<f32>, ng: vec3<f32>, light_pos: vec3<f32>) -> bool {
    return dot(ng, light_pos - p) > 0.0;
}

#if SHADOW_MASK
fn shadow_visible(pixel_index: u32, caster: u32, light_pos: vec3<f32>, p: vec3<f32>) -> bool {
    if (caster >= SHADOW_MAX_CASTERS) {
        return true;
    }
    let word = shadow_mask[pixel_index * SHADOW_MASK_WORDS + caster / 32u];
    return (word & (1u << (caster % 32u))) == 0u;
}
#endif

#if SHADOW_TRACE
// The fragment's geometric normal, set by the fragment shader before shading.
var<private> shadow_ng: vec3<f32>;

fn shadow_visible(pixel_index: u32, caster: u32, light_pos: vec3<f32>, p: vec3<f32>) -> bool {
    if (!shadow_faces(p, shadow_ng, light_pos)) {
        return false;
    }
    let origin = shadow_origin(p, shadow_ng);
    return !bvh_occluded(origin, light_pos - origin, 1.0);
}
#endif
