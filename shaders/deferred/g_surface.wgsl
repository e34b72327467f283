// The G-buffer's surface target (g_surface): what the material's code reads from the
// shading point besides position and normal, so deferred shading can run the same
// material_setup as forward shading. x, y: the uv; z: the tangent's angle about the
// normal; w: the tangent's handedness (±1).
//
// The tangent is stored as the material uses it: lg_tangent's unit tangent
// perpendicular to the normal (material/lobes.wgsl), measured from lg_tangent's own
// frame of the normal alone, so one number holds it and any normal has a frame. Both
// passes build that frame from the same normal texel. Needs the material code (for
// lg_tangent) included before it.

// The unit vector perpendicular to `n` that angles are measured from, and the one 90°
// on.
fn surface_frame(n: vec3<f32>) -> mat2x3<f32> {
    let e0 = lg_tangent(n, vec4<f32>(0.0));
    return mat2x3<f32>(e0, cross(n, e0));
}

fn encode_surface(n: vec3<f32>, tangent: vec4<f32>, uv: vec2<f32>) -> vec4<f32> {
    let f = surface_frame(n);
    let t = lg_tangent(n, tangent);
    let angle = atan2(dot(t, f[1]), dot(t, f[0]));
    return vec4<f32>(uv, angle, select(1.0, -1.0, tangent.w < 0.0));
}

// The tangent (with its handedness in w) a shading point takes from texel `s`.
fn surface_tangent(n: vec3<f32>, s: vec4<f32>) -> vec4<f32> {
    let f = surface_frame(n);
    return vec4<f32>(f[0] * cos(s.z) + f[1] * sin(s.z), s.w);
}
