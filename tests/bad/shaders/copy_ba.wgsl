@group(0) @binding(0) var<storage, read> scratch: array<u32>;
@group(0) @binding(1) var<storage, read_write> lists: array<u32>;
@compute @workgroup_size(1)
fn main() { lists[0] = scratch[0]; }
