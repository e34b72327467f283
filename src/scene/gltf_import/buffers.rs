//! Buffers: GLB chunk, data URIs and external files, read and bounds-checked.

use super::encoding::{base64_decode, percent_decode};
use super::{named, Importer};
use crate::scene::error::SceneError;

impl Importer {
    pub(super) fn load_buffers(&mut self, gltf: &gltf::Gltf) -> Result<(), SceneError> {
        for buffer in gltf.buffers() {
            let element = named("buffer", buffer.index(), buffer.name());
            let declared = buffer.length() as u64;
            self.limit(
                &element,
                "byteLength",
                declared,
                self.limits.max_buffer_bytes,
            )?;
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => match &gltf.blob {
                    Some(b) => b.clone(),
                    None => {
                        return Err(self.err(
                            element,
                            "refers to the GLB binary chunk, but the file has none",
                        ))
                    }
                },
                gltf::buffer::Source::Uri(uri) => self.read_uri(uri, &element)?,
            };
            if (data.len() as u64) < declared {
                return Err(self.err(
                    element,
                    format!("holds {} bytes but byteLength says {declared}", data.len()),
                ));
            }
            self.buffers.push(data);
        }
        Ok(())
    }

    pub(super) fn read_uri(&self, uri: &str, element: &str) -> Result<Vec<u8>, SceneError> {
        if let Some(rest) = uri.strip_prefix("data:") {
            let Some((header, payload)) = rest.split_once(',') else {
                return Err(self.err(element, "malformed data URI (no ',')"));
            };
            if !header.ends_with(";base64") {
                return Err(self.err(element, "data URI is not base64-encoded"));
            }
            return base64_decode(payload)
                .map_err(|e| self.err(element, format!("bad base64 in data URI: {e}")));
        }
        if uri.contains("://") {
            return Err(self.err(element, format!("unsupported URI scheme in \"{uri}\"")));
        }
        let path = self.base_dir.join(percent_decode(uri));
        // Recorded even if the read fails: fixing the file should trigger a reload.
        self.files_read.borrow_mut().push(path.clone());
        crate::files::read_bytes(&path, crate::files::caps::GLTF)
            .map_err(|e| self.err(element, format!("cannot read \"{}\": {e}", path.display())))
    }

    /// The bytes of a buffer view, bounds-checked.
    pub(super) fn view_bytes(
        &self,
        view: &gltf::buffer::View,
        element: &str,
    ) -> Result<&[u8], SceneError> {
        let buf = &self.buffers[view.buffer().index()];
        let (off, len) = (view.offset() as u64, view.length() as u64);
        if off + len > buf.len() as u64 {
            return Err(self.err(
                element,
                format!(
                    "bufferView {} (offset {off}, length {len}) is out of bounds of buffer {} ({} bytes)",
                    view.index(),
                    view.buffer().index(),
                    buf.len()
                ),
            ));
        }
        Ok(&buf[off as usize..(off + len) as usize])
    }
}
