// Every sample of `hdr_msaa` side by side, for tests and inspection: a Fullscreen pass
// into a target `samples` times as wide, pixel (x, y) sample s at (x * samples + s, y).
@group(0) @binding(0) var hdr_msaa: texture_multisampled_2d<f32>;

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let n = textureNumSamples(hdr_msaa);
    let q = vec2<u32>(pos.xy);
    return textureLoad(hdr_msaa, vec2<u32>(q.x / n, q.y), q.x % n);
}
