@group(0) @binding(0) var<storage, read> scratch: array<u32>;
@compute @workgroup_size(1)
fn main() { let x = scratch[0]; }
