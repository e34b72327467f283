// Exponential fog by view depth, as a Fullscreen pass: `hdr` and `depth` are bound by
// name from the graph's reads; `frame` is always available.
#include "common/types.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var hdr: texture_2d<f32>;
@group(0) @binding(2) var depth: texture_depth_2d;

const FOG_COLOR: vec3<f32> = vec3<f32>(0.02, 0.025, 0.03);
const FOG_DENSITY: f32 = 0.02;

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let p = vec2<u32>(pos.xy);
    let c = textureLoad(hdr, p, 0);
    let d = textureLoad(depth, p, 0);
    let v = frame.inv_proj * vec4<f32>(0.0, 0.0, d, 1.0);
    let z = -v.z / v.w;
    let f = exp(-FOG_DENSITY * z);
    return vec4<f32>(mix(FOG_COLOR, c.rgb, f), c.a);
}
