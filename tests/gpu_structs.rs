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
            _pad0,
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
