//! The binary buffer: bufferViews over it and the accessors that read them.

use super::{index, position, GltfWriter};
use glam::{Vec2, Vec3, Vec4};
use gltf::json;
use gltf::json::accessor::{ComponentType, GenericComponentType, Type};
use gltf::json::validation::Checked::Valid;

impl GltfWriter {
    /// Appends `bytes` to the buffer (4-byte aligned, as accessors of 4-byte components
    /// need) and adds a bufferView of them; returns the view's index.
    pub(super) fn push_view(
        &mut self,
        bytes: &[u8],
        target: Option<json::buffer::Target>,
    ) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        position(self.root.push(json::buffer::View {
            buffer: index(0),
            byte_length: bytes.len().into(),
            byte_offset: Some(offset.into()),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: Default::default(),
        }))
    }

    fn accessor(
        &mut self,
        view: usize,
        count: usize,
        component: ComponentType,
        ty: Type,
        bounds: Option<(Vec<f32>, Vec<f32>)>,
    ) -> usize {
        let (min, max) = bounds.map_or((None, None), |(lo, hi)| (Some(lo.into()), Some(hi.into())));
        position(self.root.push(json::Accessor {
            buffer_view: Some(index(view)),
            byte_offset: None,
            count: count.into(),
            component_type: Valid(GenericComponentType(component)),
            extensions: None,
            extras: Default::default(),
            type_: Valid(ty),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        }))
    }

    fn float_accessor(&mut self, data: &[f32], ty: Type, bounds: bool) -> usize {
        let comps = ty.multiplicity();
        let view = self.push_view(
            bytemuck::cast_slice(data),
            Some(json::buffer::Target::ArrayBuffer),
        );
        let count = data.len() / comps;
        let bounds = (bounds && count > 0)
            .then(|| component_bounds(data, comps))
            .filter(|(lo, hi)| lo.iter().chain(hi).all(|v| v.is_finite()));
        self.accessor(view, count, ComponentType::F32, ty, bounds)
    }

    /// Adds a VEC3 float accessor with min/max (as glTF requires for `POSITION`); returns
    /// its index.
    pub fn add_positions(&mut self, p: &[Vec3]) -> usize {
        self.float_accessor(bytemuck::cast_slice(p), Type::Vec3, true)
    }
    /// Adds a VEC3 float accessor (normals); returns its index.
    pub fn add_vec3(&mut self, v: &[Vec3]) -> usize {
        self.float_accessor(bytemuck::cast_slice(v), Type::Vec3, false)
    }
    /// Adds a VEC2 float accessor (texture coordinates); returns its index.
    pub fn add_vec2(&mut self, v: &[Vec2]) -> usize {
        self.float_accessor(bytemuck::cast_slice(v), Type::Vec2, false)
    }
    /// Adds a VEC4 float accessor (tangents); returns its index.
    pub fn add_vec4(&mut self, v: &[Vec4]) -> usize {
        self.float_accessor(bytemuck::cast_slice(v), Type::Vec4, false)
    }

    /// Index accessor: u16 when every index fits, else u32 (glTF forbids a type's largest
    /// value as an index: it is primitive restart).
    pub fn add_indices(&mut self, idx: &[u32]) -> usize {
        let (bytes, component): (Vec<u8>, _) = if idx.iter().all(|&i| i < 65535) {
            let v: Vec<u16> = idx.iter().map(|&i| i as u16).collect();
            (bytemuck::cast_slice(&v).to_vec(), ComponentType::U16)
        } else {
            (bytemuck::cast_slice(idx).to_vec(), ComponentType::U32)
        };
        let view = self.push_view(&bytes, Some(json::buffer::Target::ElementArrayBuffer));
        self.accessor(view, idx.len(), component, Type::Scalar, None)
    }
}

/// Per-component minimum and maximum of `data`'s `comps`-wide elements.
fn component_bounds(data: &[f32], comps: usize) -> (Vec<f32>, Vec<f32>) {
    let mut lo = vec![f32::INFINITY; comps];
    let mut hi = vec![f32::NEG_INFINITY; comps];
    for e in data.chunks_exact(comps) {
        for c in 0..comps {
            lo[c] = lo[c].min(e[c]);
            hi[c] = hi[c].max(e[c]);
        }
    }
    (lo, hi)
}
