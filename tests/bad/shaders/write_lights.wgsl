@group(0) @binding(0) var<storage, read_write> lg: array<vec4<f32>>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) { lg[id.x] = vec4<f32>(0.0); }
