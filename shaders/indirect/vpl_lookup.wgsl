// The light loops' side of VplVisibility (indirect/vpl_visibility.wgsl): whether a VPL
// sees the shaded pixel, from its block's bits. Included by shading passes that read
// `vpl_visibility` (define VPL_VISIBILITY, with VPL_BLOCK and VPL_WORDS as the
// visibility pass laid the bits out), after they declare the binding
//     var<storage, read> vpl_visibility: array<u32>;
// The loop sets vpl_pixel to the shaded pixel before walking its lights.

var<private> vpl_pixel: vec2<u32>;

// Lights that are not VPLs, and VPLs past the bits' room, are always visible.
fn vpl_visible(props: LightProperties) -> bool {
    let k = props._pad0;
    if ((props.flags & LIGHT_VPL) == 0u || k >= VPL_WORDS * 32u) {
        return true;
    }
    let b = vpl_pixel / VPL_BLOCK;
    let blocks_x = (frame.size.x + VPL_BLOCK - 1u) / VPL_BLOCK;
    let word = vpl_visibility[(b.y * blocks_x + b.x) * VPL_WORDS + k / 32u];
    return (word & (1u << (k % 32u))) != 0u;
}
