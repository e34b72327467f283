// Light statistics per pixel: how many lights its list holds, and how many lights
// really reach it (non-zero range and cone attenuation at its position), so false
// positives are listed / exact. Background pixels count neither.

#include "common/types.wgsl"
#include "common/lighting.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> light_geometry: array<LightGeometry>;
@group(0) @binding(2) var<storage, read> light_properties: array<LightProperties>;
#if MSAA
// Multisampled: each pixel's first sample (the level argument below is then the sample).
@group(0) @binding(3) var depth: texture_depth_multisampled_2d;
#else
@group(0) @binding(3) var depth: texture_depth_2d;
#endif
@group(0) @binding(5) var<storage, read_write> counts: array<vec2<u32>>;
@group(0) @binding(6) var<uniform> inv_view_proj: mat4x4<f32>;
#if LIGHT_LISTS
@group(0) @binding(7) var<storage, read> light_lists: array<u32>;
@group(0) @binding(4) var<uniform> list_params: ListParams;
#endif
#if LINKED_LISTS
@group(0) @binding(7) var<storage, read> light_lists: array<u32>;
@group(0) @binding(4) var<uniform> link_params: LinkParams;
#endif

#include "common/light_lists.wgsl"

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= frame.size)) {
        return;
    }
    let index = id.y * frame.size.x + id.x;
    let d = textureLoad(depth, id.xy, 0);
    if (d >= 1.0) {
        counts[index] = vec2<u32>(0u, 0u);
        return;
    }
    let size = vec2<f32>(frame.size);
    let pixel = vec2<f32>(id.xy) + 0.5;
    let ndc = vec2<f32>(pixel.x / size.x * 2.0 - 1.0, 1.0 - pixel.y / size.y * 2.0);
    let h = inv_view_proj * vec4<f32>(ndc, d, 1.0);
    let world = h.xyz / h.w;
    let view_z = -(frame.view * vec4<f32>(world, 1.0)).z;
    var listed = 0u;
    for (var c = light_first(pixel, view_z); light_valid(c); c = light_next(c, view_z)) {
        listed += 1u;
    }
    var exact = 0u;
    for (var i = 0u; i < frame.light_count; i++) {
        let inc = incident_light(light_geometry[i], light_properties[i], world);
        if (any(inc.radiance > vec3<f32>(0.0))) {
            exact += 1u;
        }
    }
    counts[index] = vec2<u32>(listed, exact);
}
