// A throughput probe, not a renderer: every light at every pixel in a compute shader,
// Lambert with the normal facing the camera. It exists to compare compute and fragment
// shading throughput on one GPU (on H100 only a few SMs run fragment shaders), and it
// shows a generic Compute pass reading the depth buffer and writing a storage texture.
#include "common/types.wgsl"
#include "common/lighting.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> light_geometry: array<LightGeometry>;
@group(0) @binding(2) var<storage, read> light_properties: array<LightProperties>;
@group(0) @binding(3) var depth: texture_depth_2d;
@group(0) @binding(4) var hdr: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= frame.size)) {
        return;
    }
    let d = textureLoad(depth, id.xy, 0);
    var color = vec3<f32>(0.0);
    if (d < 1.0) {
        let size = vec2<f32>(frame.size);
        let pixel = vec2<f32>(id.xy) + 0.5;
        let ndc = vec2<f32>(pixel.x / size.x * 2.0 - 1.0, 1.0 - pixel.y / size.y * 2.0);
        let h = frame.inv_proj * vec4<f32>(ndc, d, 1.0);
        let p = h.xyz / h.w;
        let n = normalize(-p);
        for (var i = 0u; i < frame.light_count; i++) {
            var g = light_geometry[i];
            g.position = (frame.view * vec4<f32>(g.position, 1.0)).xyz;
            g.direction = (frame.view * vec4<f32>(g.direction, 0.0)).xyz;
            let inc = incident_light(g, light_properties[i], p);
            color += inc.radiance * (0.5 * 0.31830988 * max(dot(n, inc.dir), 0.0));
        }
    }
    textureStore(hdr, id.xy, vec4<f32>(color, 1.0));
}
