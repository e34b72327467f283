// A hardware fallback with an R32Float depth (the compute rasterizer's, the transparent
// depth's): the depth its draws left in an internal
// Depth32Float texture, copied texel by texel into the pass's R32Float depth of the same
// size (a load of a depth texture gives its stored f32 unchanged, so the copy is
// bit-exact). One invocation a texel, in 8×8 tiles.

@group(0) @binding(1) var drawn_depth: texture_depth_2d;
@group(0) @binding(2) var depth: texture_storage_2d<r32float, write>;

@compute @workgroup_size(8, 8, 1)
fn copy_depth(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= textureDimensions(depth))) {
        return;
    }
    textureStore(depth, id.xy, vec4<f32>(textureLoad(drawn_depth, id.xy, 0), 0.0, 0.0, 0.0));
}
