// View-space reconstruction from the frame uniform, for compute passes that read a depth
// buffer (the including shader binds `frame`).

// Positive view-space distance along -z of a depth-buffer value.
fn view_depth(d: f32) -> f32 {
    let p = frame.inv_proj * vec4<f32>(0.0, 0.0, d, 1.0);
    return -p.z / p.w;
}

// View-space point on the far plane through a framebuffer position.
fn view_ray(pixel: vec2<f32>) -> vec3<f32> {
    let size = vec2<f32>(frame.size);
    let ndc = vec2<f32>(pixel.x / size.x * 2.0 - 1.0, 1.0 - pixel.y / size.y * 2.0);
    let p = frame.inv_proj * vec4<f32>(ndc, 1.0, 1.0);
    return p.xyz / p.w;
}
