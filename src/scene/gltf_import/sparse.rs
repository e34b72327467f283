//! Sparse accessors and accessors without a bufferView (glTF 2.0, 3.6.2.3 and 3.6.2.4):
//! a dense, tightly packed copy of the elements, starting from the bufferView's (or zeros)
//! with the sparse elements written over them. Morph targets often use both.

use super::Importer;
use crate::scene::error::SceneError;
use gltf::accessor::sparse::IndexType;

impl Importer {
    /// `base`: the accessor's own elements (bytes from the first, stride), if it has a view.
    pub(super) fn dense_accessor(
        &self,
        acc: &gltf::Accessor,
        element: &str,
        base: Option<(&[u8], usize)>,
        sparse: Option<&gltf::accessor::sparse::Sparse>,
    ) -> Result<Vec<u8>, SceneError> {
        let (count, elem) = (acc.count(), acc.size());
        let mut dense = vec![0u8; count * elem];
        if let Some((bytes, stride)) = base {
            for (i, out) in dense.chunks_exact_mut(elem).enumerate() {
                out.copy_from_slice(&bytes[i * stride..i * stride + elem]);
            }
        }
        let Some(sparse) = sparse else {
            return Ok(dense);
        };
        let n = sparse.count();
        if n > count {
            return Err(self.err(
                element,
                format!("sparse count {n} is larger than the accessor's count {count}"),
            ));
        }
        let indices = sparse.indices();
        let isize = match indices.index_type() {
            IndexType::U8 => 1,
            IndexType::U16 => 2,
            IndexType::U32 => 4,
        };
        let ibytes = self.sparse_slice(
            &indices.view(),
            indices.offset(),
            n * isize,
            element,
            "indices",
        )?;
        let values = sparse.values();
        let vbytes =
            self.sparse_slice(&values.view(), values.offset(), n * elem, element, "values")?;
        let mut previous: Option<usize> = None;
        for k in 0..n {
            let b = &ibytes[k * isize..];
            let index = match isize {
                1 => b[0] as usize,
                2 => u16::from_le_bytes([b[0], b[1]]) as usize,
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
            };
            if index >= count {
                return Err(self.err(
                    element,
                    format!("sparse index {k} is {index}, past the accessor's count {count}"),
                ));
            }
            // The spec requires strictly increasing indices; a repeat would make the
            // result depend on the order of writes.
            if previous.is_some_and(|p| index <= p) {
                return Err(self.err(
                    element,
                    format!("sparse indices must increase strictly; index {k} is {index}"),
                ));
            }
            previous = Some(index);
            dense[index * elem..(index + 1) * elem]
                .copy_from_slice(&vbytes[k * elem..(k + 1) * elem]);
        }
        Ok(dense)
    }

    /// `len` bytes at `offset` in `view`, bounds-checked.
    fn sparse_slice<'s>(
        &'s self,
        view: &gltf::buffer::View,
        offset: usize,
        len: usize,
        element: &str,
        what: &str,
    ) -> Result<&'s [u8], SceneError> {
        let bytes = self.view_bytes(view, element)?;
        if offset as u64 + len as u64 > bytes.len() as u64 {
            return Err(self.err(
                element,
                format!(
                    "sparse {what} out of bounds: {len} bytes at offset {offset}, bufferView {} has {}",
                    view.index(),
                    bytes.len()
                ),
            ));
        }
        Ok(&bytes[offset..offset + len])
    }
}
