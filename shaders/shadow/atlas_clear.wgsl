// Clears one shadow-atlas tile to the far depth: a triangle over the viewport at depth 1,
// drawn before the tile's casters (ShadowAtlas pass). Clearing only the tiles in use costs
// their area, not the atlas's: a whole 16384² atlas is a gigabyte.

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 1.0, 1.0);
}
