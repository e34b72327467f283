// One invocation a workgroup: a per-light dispatch of over 65,535 lights is too wide.
@group(0) @binding(0) var<storage, read_write> scratch: array<u32>;
@compute @workgroup_size(1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    scratch[0] = id.x;
}
