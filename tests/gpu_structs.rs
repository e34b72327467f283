//! Every GPU struct has one definition on each side; naga's layout of the WGSL struct
//! must match Rust's #[repr(C)] offsets and sizes exactly.

use lightgraph::gpu::structs::*;
use lightgraph::shader::{struct_layout, ShaderLibrary};
use std::collections::BTreeMap;
use std::mem::{offset_of, size_of};

fn wgsl_layout(name: &str) -> (Vec<(String, u32, u32)>, u32) {
    let c = ShaderLibrary::builtin()
        .compose("common/types.wgsl", &BTreeMap::new(), &BTreeMap::new())
        .unwrap();
    let module = c.validate().unwrap();
    struct_layout(&module, name).unwrap_or_else(|| panic!("no struct {name}"))
}

macro_rules! check {
    ($ty:ty, $name:literal, [$($field:ident),*]) => {{
        let (fields, size) = wgsl_layout($name);
        assert_eq!(size as usize, size_of::<$ty>(), "size of {}", $name);
        let rust: Vec<(&str, usize)> = vec![$((stringify!($field), offset_of!($ty, $field))),*];
        assert_eq!(fields.len(), rust.len(), "{} member count", $name);
        for ((wname, woff, _), (rname, roff)) in fields.iter().zip(&rust) {
            assert_eq!(wname, rname, "{} member order", $name);
            assert_eq!(*woff as usize, *roff, "{}.{} offset", $name, wname);
        }
    }};
}

#[test]
fn frame_matches() {
    check!(
        GpuFrame,
        "Frame",
        [
            view,
            proj,
            view_proj,
            inv_proj,
            camera_pos,
            ambient,
            size,
            light_count,
            caster_end,
            near,
            far,
            _pad1
        ]
    );
}

#[test]
fn light_geometry_matches() {
    check!(
        GpuLightGeometry,
        "LightGeometry",
        [position, range, direction, cos_outer]
    );
}

#[test]
fn light_properties_matches() {
    let (fields, size) = wgsl_layout("LightProperties");
    assert_eq!(size as usize, size_of::<GpuLightProperties>());
    let offsets: Vec<u32> = fields.iter().map(|f| f.1).collect();
    // Rust keeps the two pad words as one array.
    assert_eq!(offsets, [0, 12, 16, 20, 24, 28]);
    assert_eq!(offset_of!(GpuLightProperties, cos_inner), 12);
    assert_eq!(offset_of!(GpuLightProperties, flags), 16);
    assert_eq!(offset_of!(GpuLightProperties, material_mask), 20);
    assert_eq!(offset_of!(GpuLightProperties, _pad), 24);
}

#[test]
fn list_params_match() {
    check!(
        GpuListParams,
        "ListParams",
        [
            tiles_x,
            tiles_y,
            tile,
            lists_per_tile,
            capacity,
            variant,
            pool_offset,
            pool_indices
        ]
    );
}

#[test]
fn link_params_match() {
    check!(
        GpuLinkParams,
        "LinkParams",
        [scale, width, height, pool_offset, pool, _pad0, _pad1, _pad2]
    );
}

/// The array stride naga's layouter gives WGSL struct `name` (its size rounded up to its
/// alignment): how far apart elements of a storage array of it lie.
fn wgsl_stride(module: &naga::Module, name: &str) -> u32 {
    let (handle, _) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name}"));
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    layouter[handle].to_stride()
}

fn types_module() -> naga::Module {
    ShaderLibrary::builtin()
        .compose("common/types.wgsl", &BTreeMap::new(), &BTreeMap::new())
        .unwrap()
        .validate()
        .unwrap()
}

#[test]
fn light_arrays_are_strided_as_light_bytes() {
    let module = types_module();
    // Both light arrays are indexed by light and sized LIGHT_BYTES a light on the CPU.
    assert_eq!(wgsl_stride(&module, "LightGeometry") as u64, LIGHT_BYTES);
    assert_eq!(wgsl_stride(&module, "LightProperties") as u64, LIGHT_BYTES);
    assert_eq!(size_of::<GpuLightGeometry>() as u64, LIGHT_BYTES);
    assert_eq!(size_of::<GpuLightProperties>() as u64, LIGHT_BYTES);
}

/// The u32 value of WGSL constant `name`.
fn wgsl_const(module: &naga::Module, name: &str) -> u32 {
    let (_, c) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no constant {name}"));
    match module.global_expressions[c.init] {
        naga::Expression::Literal(naga::Literal::U32(v)) => v,
        ref e => panic!("{name} is not a u32 literal: {e:?}"),
    }
}

#[test]
fn merged_vertices_are_strided_as_gpu_vertex() {
    use lightgraph::render::visibility_geometry::VERTEX_FLOATS;
    // visibility/surface.wgsl fetches vertices from a float array, VERTEX_FLOATS apart;
    // composed after the types and the bindings it reads.
    let lib = ShaderLibrary::builtin();
    let none = BTreeMap::new();
    let types = lib.compose("common/types.wgsl", &none, &none).unwrap();
    let surface = lib
        .compose("visibility/surface.wgsl", &none, &none)
        .unwrap();
    let text = format!(
        "{}\n\
         @group(0) @binding(0) var<uniform> frame: Frame;\n\
         @group(0) @binding(1) var<storage, read> vertices: array<f32>;\n\
         @group(0) @binding(2) var<storage, read> triangles: array<u32>;\n{}",
        types.text, surface.text
    );
    let module = naga::front::wgsl::parse_str(&text).unwrap();
    assert_eq!(wgsl_const(&module, "VERTEX_FLOATS"), VERTEX_FLOATS);
    assert_eq!(VERTEX_FLOATS as usize * 4, size_of::<GpuVertex>());
}
