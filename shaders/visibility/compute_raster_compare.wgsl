// The compute rasterizer's output beside the hardware depth prepass's, for tests and
// inspection (a Fullscreen pass): r = compute depth, g = prepass depth, b and a = the
// triangle id's low and high 16 bits (exact in f32).

@group(0) @binding(0) var depth_cr: texture_depth_2d;
@group(0) @binding(1) var depth_hw: texture_depth_2d;
@group(0) @binding(2) var visibility: texture_2d<u32>;

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let p = vec2<i32>(pos.xy);
    let id = textureLoad(visibility, p, 0).x;
    return vec4<f32>(
        textureLoad(depth_cr, p, 0),
        textureLoad(depth_hw, p, 0),
        f32(id & 0xffffu),
        f32(id >> 16u),
    );
}
