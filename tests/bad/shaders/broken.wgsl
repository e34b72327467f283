// A compute pass with a type error on line 6.
@group(0) @binding(0) var<storage, read_write> scratch: array<u32>;

@compute @workgroup_size(1)
fn main() {
    scratch[0] = 1.5 + vec2<f32>(1.0);
}
