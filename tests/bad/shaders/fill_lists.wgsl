@group(0) @binding(0) var<storage, read_write> light_lists: array<u32>;
@compute @workgroup_size(1)
fn main() { light_lists[0] = 0u; }
