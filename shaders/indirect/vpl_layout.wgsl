// How VplVisibility's buffer is laid out, for the pass that writes it
// (indirect/vpl_visibility.wgsl) and the light loops that read it
// (indirect/vpl_lookup.wgsl): VPL_WORDS words of bits a VPL_BLOCK×VPL_BLOCK block, row by
// row, then each block's point in 4 words (its position's f32 bits, then its geometric
// normal pack4x8snorm'd with w = 1, or 0 where nothing covers the block).
// src/graph/kinds/layout.rs sizes it.

// Blocks across and down the frame.
fn vpl_blocks() -> vec2<u32> {
    return (frame.size + VPL_BLOCK - 1u) / VPL_BLOCK;
}

// The first of block `block`'s 4 point words.
fn vpl_point_word(block: u32) -> u32 {
    let blocks = vpl_blocks();
    return blocks.x * blocks.y * VPL_WORDS + 4u * block;
}
