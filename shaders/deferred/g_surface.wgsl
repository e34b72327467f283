// The G-buffer's surface target (g_surface): what the material's code reads from the
// shading point besides position and normal, so deferred shading can run the same
// material_setup as forward shading. x, y: the uv; z: the tangent's angle about the
// normal; w: the tangent's handedness as its sign, and the vertex colour's rgb, 8 bits a
// channel, as the integer 1 + r + 256 g + 65536 b (at most 2^24: exact in an f32). The
// colour's alpha is not kept: the G-buffer pass has already alpha-tested, and shading
// reads no alpha.
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

fn encode_surface(n: vec3<f32>, tangent: vec4<f32>, uv: vec2<f32>, color: vec3<f32>) -> vec4<f32> {
    let f = surface_frame(n);
    let t = lg_tangent(n, tangent);
    let angle = atan2(dot(t, f[1]), dot(t, f[0]));
    let c = vec3<u32>(round(clamp(color, vec3<f32>(0.0), vec3<f32>(1.0)) * 255.0));
    let packed = f32(1u + c.r + (c.g << 8u) + (c.b << 16u));
    return vec4<f32>(uv, angle, select(packed, -packed, tangent.w < 0.0));
}

// The tangent (with its handedness in w) a shading point takes from texel `s`.
fn surface_tangent(n: vec3<f32>, s: vec4<f32>) -> vec4<f32> {
    let f = surface_frame(n);
    return vec4<f32>(f[0] * cos(s.z) + f[1] * sin(s.z), select(1.0, -1.0, s.w < 0.0));
}

// The vertex colour (alpha 1) of texel `s`.
fn surface_color(s: vec4<f32>) -> vec4<f32> {
    let v = u32(abs(s.w)) - 1u;
    let c = vec3<u32>(v, v >> 8u, v >> 16u) & vec3<u32>(255u);
    return vec4<f32>(vec3<f32>(c) / 255.0, 1.0);
}
