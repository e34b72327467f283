// Column 0 overflows f32 (p.y * 1e40 at run time): render must count it, not hide it.
@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    var v = 0.25;
    if p.x < 1.0 {
        v = p.y * 1e38 * 100.0;
    }
    return vec4<f32>(v, 0.5, 1.0, 1.0);
}
