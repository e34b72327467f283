// The light loops' side of VplVisibility (indirect/vpl_visibility.wgsl): whether a VPL
// sees the shaded pixel, from the bits of a block near it. Included by shading passes
// that read `vpl_visibility` (define VPL_VISIBILITY, with VPL_BLOCK and VPL_WORDS as the
// visibility pass laid the bits out), after they declare the binding
//     var<storage, read> vpl_visibility: array<u32>;
// The loop calls vpl_select with the shaded point before walking its lights.

#include "indirect/vpl_layout.wgsl"

var<private> vpl_block: u32;

// A block's point: the surface its rays left from (indirect/vpl_visibility.wgsl).
struct VplPoint {
    valid: bool,
    position: vec3<f32>,
    normal: vec3<f32>,
};

fn vpl_point(block: u32) -> VplPoint {
    let at = vpl_point_word(block);
    let packed = vpl_visibility[at + 3u];
    let position = vec3<f32>(
        bitcast<f32>(vpl_visibility[at]),
        bitcast<f32>(vpl_visibility[at + 1u]),
        bitcast<f32>(vpl_visibility[at + 2u]),
    );
    return VplPoint(packed != 0u, position, unpack4x8snorm(packed).xyz);
}

// Whether a block's point lies on the shaded point p's surface (normal n): off p's plane
// by at most 5% of its distance and half a pixel's width at p (`pixel_width`: a plane
// parallel to p's but a step behind it, met far off to the side, is another surface),
// its normal within about 25° of n.
fn vpl_point_fits(q: VplPoint, p: vec3<f32>, n: vec3<f32>, pixel_width: f32) -> bool {
    let d = q.position - p;
    let off = abs(dot(n, d));
    return q.valid && off <= 0.05 * length(d) && off <= 0.5 * pixel_width && dot(n, q.normal) >= 0.9;
}

// The block whose bits the pixel takes. A block's point is one pixel of it: where the
// block spans two surfaces (an edge, a silhouette), the pixels on the other surface see
// what a point on theirs sees far more often than what it sees. So the pixel keeps its
// own block when that block's point lies on its surface, else takes the nearest of the
// three blocks next to it on its side of the block's centre (of the four whose centres
// surround it) whose point does, else keeps its own. Only a point on the pixel's surface
// replaces its own: a nearer point on another surface (a box's front face for a pixel of
// its top seen edge-on) sees another half of the scene. Keeping the own block whenever it
// fits leaves no tie between equally near neighbours for rounding to decide (the
// compute-first and Forward+ paths rebuild the same point a rounding apart).
fn vpl_select(pixel: vec2<u32>, p: vec3<f32>, n: vec3<f32>) {
    let blocks = vpl_blocks();
    let own = pixel / VPL_BLOCK;
    vpl_block = own.y * blocks.x + own.x;
    if (VPL_BLOCK == 1u) {
        return;
    }
    // The width of a pixel at p (the distance to the eye stands for the view depth).
    let eye = frame.camera_pos.xyz - p;
    let pixel_width = 2.0 * length(eye) / (frame.proj[1][1] * f32(frame.size.y));
    if (vpl_point_fits(vpl_point(vpl_block), p, n, pixel_width)) {
        return;
    }
    var nearest = 3.4e38;
    let inner = pixel % VPL_BLOCK;
    let step = select(vec2<i32>(-1), vec2<i32>(1), 2u * inner + 1u >= vec2<u32>(VPL_BLOCK));
    for (var c = 1u; c < 4u; c++) {
        let o = vec2<i32>(own) + step * vec2<i32>(vec2<u32>(c & 1u, c >> 1u));
        if (any(o < vec2<i32>(0)) || any(o >= vec2<i32>(blocks))) {
            continue;
        }
        let b = u32(o.y) * blocks.x + u32(o.x);
        let q = vpl_point(b);
        let dist = distance(q.position, p);
        if (vpl_point_fits(q, p, n, pixel_width) && dist < nearest) {
            nearest = dist;
            vpl_block = b;
        }
    }
}

// Lights that are not VPLs, and VPLs past the bits' room, are always visible.
fn vpl_visible(props: LightProperties) -> bool {
    let k = props._pad0;
    if ((props.flags & LIGHT_VPL) == 0u || k >= VPL_WORDS * 32u) {
        return true;
    }
    let word = vpl_visibility[vpl_block * VPL_WORDS + k / 32u];
    return (word & (1u << (k % 32u))) != 0u;
}
