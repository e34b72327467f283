// A constant colour: the simplest Fullscreen pass.
@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    return vec4<f32>(0.25, 0.5, 1.0, 1.0);
}
