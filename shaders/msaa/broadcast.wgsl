// A resolved colour copied into every sample of a multisampled target, as a Fullscreen
// pass into that target: deferred MSAA shades and resolves in one compute pass, and glass
// at 4× (graphs/tiled_deferred_msaa_transparent.ron) then blends over each sample of this
// copy. The fragment runs once per pixel and its colour lands in all covered samples.
@group(0) @binding(0) var hdr_opaque: texture_2d<f32>;

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    return textureLoad(hdr_opaque, vec2<u32>(pos.xy), 0);
}
