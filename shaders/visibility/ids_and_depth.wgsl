// A visibility buffer made readable (tests, inspection; a generic Compute pass): per pixel
// the visibility pass's depth, a depth prepass's depth and the triangle id as a float
// (exact below 2^24; -1 for NO_TRIANGLE).
#include "common/types.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var depth: texture_depth_2d;
@group(0) @binding(2) var prepass_depth: texture_depth_2d;
@group(0) @binding(3) var visibility: texture_2d<u32>;
@group(0) @binding(4) var ids: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= frame.size)) {
        return;
    }
    let t = textureLoad(visibility, id.xy, 0).x;
    let tri = select(f32(t), -1.0, t == 0xffffffffu);
    textureStore(ids, id.xy, vec4<f32>(textureLoad(depth, id.xy, 0), textureLoad(prepass_depth, id.xy, 0), tri, 1.0));
}
