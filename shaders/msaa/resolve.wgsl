// MSAA resolve as a Fullscreen pass: the mean of every sample of `hdr_msaa` (a box
// filter, what a hardware resolve does), into the pass's single-sample colour target.
// A shader resolve because Rgba32Float has no guaranteed hardware resolve in WebGPU.
@group(0) @binding(0) var hdr_msaa: texture_multisampled_2d<f32>;

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let p = vec2<u32>(pos.xy);
    let n = textureNumSamples(hdr_msaa);
    var sum = vec4<f32>(0.0);
    for (var s = 0u; s < n; s++) {
        sum += textureLoad(hdr_msaa, p, s);
    }
    return sum / f32(n);
}
