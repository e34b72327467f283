// The surface point a material is set up at and lit at (the contract between the shading
// passes and generated material code: `material_setup(p: ShadingPoint)`). Forward,
// deferred and visibility shading, the shadow code and the material tests all take this
// one declaration (src/material/wgsl.rs reads this file as SHADING_POINT_WGSL).
struct ShadingPoint {
    position: vec3<f32>,
    normal: vec3<f32>,
    tangent: vec4<f32>,
    uv: vec2<f32>,
    // The second texture coordinates (glTF TEXCOORD_1; zero without them).
    uv1: vec2<f32>,
    view: vec3<f32>,
    // The interpolated vertex colour (glTF COLOR_0, linear RGBA; white without one), which
    // a material's `Vertex` and `VertexAlpha` read.
    color: vec4<f32>,
};
