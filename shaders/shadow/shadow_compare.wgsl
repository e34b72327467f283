// The shadow atlas against ray-cast shadows (src/kinds/shadow_compare/rules.rs): per
// pixel, every shadow-casting light its list visits that reaches it, numbered as the
// light loop numbers casters, counted where it is in front of the shading normal (the
// pairs the image shows); the ray's answer is the mask bit, the atlas's the filtered
// visibility below one half. Counted per workgroup, then once into the buffer.

#include "common/types.wgsl"
#include "common/lighting.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
// LIGHT_LISTS is always set: tile lists.
#include "common/light_inputs.wgsl"
@group(0) @binding(5) var g_position: texture_2d<f32>;
@group(0) @binding(6) var g_normal: texture_2d<f32>;
@group(0) @binding(7) var<storage, read> shadow_mask: array<u32>;
@group(0) @binding(8) var<storage, read> shadow_views: array<vec4<f32>>;
#if SHADOW_ATLAS_FLOAT
@group(0) @binding(9) var shadow_atlas: texture_2d<f32>;
@group(0) @binding(10) var shadow_gather: sampler;
#else
@group(0) @binding(9) var shadow_atlas: texture_depth_2d;
@group(0) @binding(10) var shadow_sampler: sampler_comparison;
#endif
@group(0) @binding(11) var<storage, read_write> shadow_errors: array<atomic<u32>>;

#include "common/shadows.wgsl"

var<workgroup> counts: array<atomic<u32>, 4>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    var pairs = 0u;
    var wrong_pcf5 = 0u;
    var wrong_2x2 = 0u;
    var penumbra = 0u;
    let g = textureLoad(g_position, min(id.xy, frame.size - 1u), 0);
    if (all(id.xy < frame.size) && g.w >= 0.0) {
        let position = g.xyz;
        let normal = textureLoad(g_normal, id.xy, 0).xyz;
        let view_z = -(frame.view * vec4<f32>(position, 1.0)).z;
        let pixel = vec2<f32>(id.xy) + 0.5;
        let pixel_index = id.y * frame.size.x + id.x;
        var caster = 0u;
        for (var c = light_first(pixel, view_z); light_valid(c); c = light_next(c, view_z)) {
            let i = light_index(c);
            let props = light_properties[i];
            let lg = light_geometry[i];
            let inc = incident_light(lg, props, position);
            if (!any(inc.radiance > vec3<f32>(0.0)) || (props.flags & LIGHT_CASTS_SHADOW) == 0u) {
                continue;
            }
            // Only pairs the image shows: lights in front of the shading normal.
            if (caster < SHADOW_MAX_CASTERS && dot(normal, lg.position - position) > 0.0) {
                let word = shadow_mask[pixel_index * SHADOW_MASK_WORDS + caster / 32u];
                let hidden = (word & (1u << (caster % 32u))) != 0u;
                let tap = shadow_atlas_tap(i, lg.position, position, normal);
                let v5 = shadow_atlas_pcf5(tap);
                let v2 = shadow_atlas_2x2(tap);
                pairs += 1u;
                wrong_pcf5 += u32((v5 < 0.5) != hidden);
                wrong_2x2 += u32((v2 < 0.5) != hidden);
                penumbra += u32(v5 > 0.0 && v5 < 1.0);
            }
            caster += 1u;
        }
    }
    atomicAdd(&counts[0], pairs);
    atomicAdd(&counts[1], wrong_pcf5);
    atomicAdd(&counts[2], wrong_2x2);
    atomicAdd(&counts[3], penumbra);
    workgroupBarrier();
    if (local < 4u) {
        atomicAdd(&shadow_errors[local], atomicLoad(&counts[local]));
    }
}
