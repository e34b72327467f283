@group(0) @binding(0) var hdr: texture_2d<f32>;
@group(0) @binding(1) var depth: texture_2d<f32>;
@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    return textureLoad(hdr, vec2<u32>(p.xy), 0) * textureLoad(depth, vec2<u32>(p.xy), 0).r;
}
