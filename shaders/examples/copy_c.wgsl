// Copies texture 'c' to the render target.
@group(0) @binding(0) var c: texture_2d<f32>;
@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    return textureLoad(c, vec2<u32>(p.xy), 0);
}
