// Where the ray-cast shadow passes take a pixel's surface from: the G-buffer's world
// position and geometric normal (g_position, g_geometric), or with VISIBILITY_IDS the
// visibility buffer's triangle id, rebuilt at the pixel centre by visibility/surface.wgsl
// exactly as visibility shading rebuilds the point it shades (the triangle's normal,
// facing the eye, is the geometric normal). Job creation and casting read it alike.

// The surface's bindings, declared here for every pass that includes this file (bound by
// name; numbers clear of the including shaders' own).
#if VISIBILITY_IDS
@group(0) @binding(14) var visibility: texture_2d<u32>;
@group(0) @binding(15) var<storage, read> vertices: array<f32>;
@group(0) @binding(16) var<storage, read> triangles: array<u32>;
#else
@group(0) @binding(14) var g_position: texture_2d<f32>;
@group(0) @binding(15) var g_geometric: texture_2d<f32>;
#endif

struct ShadowSurface {
    valid: bool,
    position: vec3<f32>,
    ng: vec3<f32>,
};

#if VISIBILITY_IDS
#include "visibility/surface.wgsl"

// The visibility buffer's id where nothing was drawn (src/render/visibility_geometry.rs).
const NO_TRIANGLE: u32 = 0xffffffffu;

fn shadow_surface(xy: vec2<u32>) -> ShadowSurface {
    var s: ShadowSurface;
    let tri = textureLoad(visibility, xy, 0).x;
    s.valid = tri != NO_TRIANGLE;
    if (s.valid) {
        let g = surface_geometry(xy, tri);
        s.position = g.position;
        s.ng = g.ng;
    }
    return s;
}
#else
fn shadow_surface(xy: vec2<u32>) -> ShadowSurface {
    let g = textureLoad(g_position, xy, 0);
    // w = -1 where nothing was drawn.
    return ShadowSurface(g.w >= 0.0, g.xyz, textureLoad(g_geometric, xy, 0).xyz);
}
#endif
