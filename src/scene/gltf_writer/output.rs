//! The document as JSON text, and the .gltf and .glb files (with their .bin and images).

use super::desc::BufferStorage;
use super::GltfWriter;
use gltf::json;
use std::borrow::Cow;
use std::io;
use std::path::Path;

impl GltfWriter {
    /// The JSON text; `buffer_uri` is the buffer's URI (`None` for GLB's binary chunk).
    pub fn to_json(&self, buffer_uri: Option<&str>) -> String {
        let mut root = self.root.clone();
        root.asset.generator = Some("lightgraph gltf_writer".into());
        if !self.bin.is_empty() {
            root.push(json::Buffer {
                byte_length: self.bin.len().into(),
                name: None,
                uri: buffer_uri.map(str::to_string),
                extensions: None,
                extras: Default::default(),
            });
        }
        let lights = root
            .extensions
            .as_ref()
            .is_some_and(|e| e.khr_lights_punctual.is_some());
        if lights {
            root.extensions_used.push("KHR_lights_punctual".into());
        }
        root.extensions_used
            .extend(self.extensions_required.iter().cloned());
        root.extensions_required = self.extensions_required.clone();
        root.to_string()
            .expect("the writer builds only values glTF can name")
    }

    fn write_image_files(&self, dir: &Path) -> io::Result<()> {
        for (uri, bytes) in &self.image_files {
            std::fs::write(dir.join(uri), bytes)?;
        }
        Ok(())
    }

    /// Writes a .gltf (and its .bin and image files, beside it).
    pub fn write_gltf(&self, path: &Path, buffers: &BufferStorage) -> io::Result<()> {
        let dir = path.parent().unwrap_or(Path::new("."));
        self.write_image_files(dir)?;
        let json = match buffers {
            BufferStorage::External(uri) => {
                std::fs::write(dir.join(uri), &self.bin)?;
                self.to_json(Some(uri))
            }
            BufferStorage::Embedded => {
                let data = base64::encode(&self.bin);
                self.to_json(Some(&format!(
                    "data:application/octet-stream;base64,{data}"
                )))
            }
        };
        std::fs::write(path, json)
    }

    /// The GLB bytes (JSON chunk, then the binary chunk when there is data).
    pub fn to_glb(&self) -> Vec<u8> {
        let glb = gltf::binary::Glb {
            // to_vec writes the magic, version and length itself.
            header: gltf::binary::Header {
                magic: *b"glTF",
                version: 2,
                length: 0,
            },
            json: Cow::Owned(self.to_json(None).into_bytes()),
            bin: (!self.bin.is_empty()).then_some(Cow::Borrowed(&self.bin[..])),
        };
        glb.to_vec().expect("writing a GLB into memory cannot fail")
    }

    /// Writes a .glb (image files with [`ImageStorage::File`](super::ImageStorage::File)
    /// go beside it).
    pub fn write_glb(&self, path: &Path) -> io::Result<()> {
        let dir = path.parent().unwrap_or(Path::new("."));
        self.write_image_files(dir)?;
        std::fs::write(path, self.to_glb())
    }
}
