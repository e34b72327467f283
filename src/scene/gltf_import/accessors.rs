//! Accessors: typed, bounds-checked reads of vertex attributes and indices.

use super::Importer;
use crate::scene::error::SceneError;
use gltf::accessor::{DataType, Dimensions};
use std::borrow::Cow;

impl Importer {
    /// Reads an accessor into `count` rows of `N` components as f32 (normalized integers are
    /// mapped to [0, 1] / [-1, 1]).
    pub(super) fn read_f32<const N: usize>(
        &self,
        acc: &gltf::Accessor,
        element: &str,
        allowed: &[DataType],
    ) -> Result<Vec<[f32; N]>, SceneError> {
        let dims = match N {
            1 => Dimensions::Scalar,
            2 => Dimensions::Vec2,
            3 => Dimensions::Vec3,
            _ => Dimensions::Vec4,
        };
        if acc.dimensions() != dims {
            return Err(self.err(
                element,
                format!("expected {dims:?}, found {:?}", acc.dimensions()),
            ));
        }
        let dt = acc.data_type();
        if !allowed.contains(&dt) || (dt != DataType::F32 && !acc.normalized()) {
            return Err(self.err(
                element,
                format!(
                    "unsupported component type {dt:?} (normalized: {})",
                    acc.normalized()
                ),
            ));
        }
        let (bytes, stride, count) = self.accessor_layout(acc, element)?;
        let cs = dt.size();
        let mut out = Vec::with_capacity(count);
        for i in 0..count {
            let e = &bytes[i * stride..];
            let mut v = [0f32; N];
            for (c, slot) in v.iter_mut().enumerate() {
                let b = &e[c * cs..c * cs + cs];
                *slot = match dt {
                    DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                    DataType::U8 => b[0] as f32 / 255.0,
                    DataType::I8 => (b[0] as i8 as f32 / 127.0).max(-1.0),
                    DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0,
                    DataType::I16 => (i16::from_le_bytes([b[0], b[1]]) as f32 / 32767.0).max(-1.0),
                    DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
                };
            }
            out.push(v);
        }
        Ok(out)
    }

    pub(super) fn read_indices(
        &self,
        acc: &gltf::Accessor,
        element: &str,
    ) -> Result<Vec<u32>, SceneError> {
        if acc.dimensions() != Dimensions::Scalar {
            return Err(self.err(
                element,
                format!("indices must be SCALAR, found {:?}", acc.dimensions()),
            ));
        }
        let dt = acc.data_type();
        if !matches!(dt, DataType::U8 | DataType::U16 | DataType::U32) {
            return Err(self.err(
                element,
                format!("index component type {dt:?} is not unsigned"),
            ));
        }
        let (bytes, stride, count) = self.accessor_layout(acc, element)?;
        Ok((0..count)
            .map(|i| {
                let b = &bytes[i * stride..];
                match dt {
                    DataType::U8 => b[0] as u32,
                    DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
                    _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                }
            })
            .collect())
    }

    /// (bytes from the first element, stride, count), with every element proven in bounds.
    /// Sparse accessors and those without a bufferView come back as a dense copy.
    fn accessor_layout<'s>(
        &'s self,
        acc: &gltf::Accessor,
        element: &str,
    ) -> Result<(Cow<'s, [u8]>, usize, usize), SceneError> {
        let count = acc.count() as u64;
        self.limit(
            element,
            "accessor count",
            count,
            self.limits.max_accessor_count,
        )?;
        let base = self.view_layout(acc, element)?;
        match (acc.sparse(), base) {
            (None, Some((bytes, stride))) => Ok((Cow::Borrowed(bytes), stride, count as usize)),
            (sparse, base) => {
                let dense = self.dense_accessor(acc, element, base, sparse.as_ref())?;
                Ok((Cow::Owned(dense), acc.size(), count as usize))
            }
        }
    }

    /// The accessor's elements in its bufferView, if it has one: (bytes from the first
    /// element, stride), every element proven in bounds.
    pub(super) fn view_layout<'s>(
        &'s self,
        acc: &gltf::Accessor,
        element: &str,
    ) -> Result<Option<(&'s [u8], usize)>, SceneError> {
        let count = acc.count() as u64;
        let Some(view) = acc.view() else {
            return Ok(None);
        };
        if let Some(problem) = super::alignment::misalignment(acc, &view) {
            return Err(self.err(element, problem));
        }
        let elem = acc.size() as u64;
        let stride = view.stride().map(|s| s as u64).unwrap_or(elem);
        if stride < elem {
            return Err(self.err(
                element,
                format!("byteStride {stride} is smaller than the element size {elem}"),
            ));
        }
        let bytes = self.view_bytes(&view, element)?;
        let off = acc.offset() as u64;
        let needed = if count == 0 {
            0
        } else {
            off + stride * (count - 1) + elem
        };
        if needed > bytes.len() as u64 {
            return Err(self.err(
                element,
                format!(
                    "accessor out of bounds: {count} elements at offset {off} with stride {stride} need {needed} bytes, bufferView {} has {}",
                    view.index(),
                    bytes.len()
                ),
            ));
        }
        Ok(Some((
            &bytes[off.min(bytes.len() as u64) as usize..],
            stride as usize,
        )))
    }
}
