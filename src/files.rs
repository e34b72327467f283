//! Reading input files: only regular files (a device or FIFO never ends, or never
//! starts), never more than a stated cap, and text without its UTF-8 byte-order mark.
//! Every front end (graphs, scenes, models, glTF buffers and images, materials, shaders)
//! reads through here.

use std::io::{self, Read};
use std::path::Path;

/// The most bytes read from one file of each kind. Past them the read is refused before
/// anything is allocated.
pub mod caps {
    /// A graph, scene or material RON file.
    pub const RON: u64 = 64 << 20;
    /// A WGSL file (one file; includes are capped each).
    pub const SHADER: u64 = 16 << 20;
    /// A .gltf or .glb file, or one external glTF buffer.
    pub const GLTF: u64 = 1 << 30;
    /// An encoded image (a glTF image or a material texture).
    pub const IMAGE: u64 = 256 << 20;
}

/// The file's bytes, if it is a regular file of at most `cap` bytes.
pub fn read_bytes(path: &Path, cap: u64) -> io::Result<Vec<u8>> {
    // Checked before opening: opening a FIFO blocks until a writer comes.
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("not a regular file ({})", kind_of(&meta.file_type())),
        ));
    }
    if meta.len() > cap {
        return Err(too_big(meta.len(), cap));
    }
    // The file may grow between the check and the read: read at most one byte past the cap.
    let file = std::fs::File::open(path)?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(cap + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > cap {
        return Err(too_big(bytes.len() as u64, cap));
    }
    Ok(bytes)
}

/// The file's text (UTF-8, a leading byte-order mark dropped), as [`read_bytes`] reads it.
pub fn read_text(path: &Path, cap: u64) -> io::Result<String> {
    let bytes = read_bytes(path, cap)?;
    let text = String::from_utf8(bytes)
        .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, format!("not UTF-8: {e}")))?;
    Ok(strip_bom(&text).to_string())
}

/// `text` without a leading UTF-8 byte-order mark (editors on Windows write one).
pub(crate) fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

fn too_big(len: u64, cap: u64) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidInput,
        format!("{len} bytes is over the limit of {cap} bytes for this kind of file"),
    )
}

fn kind_of(t: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() {
        "a directory"
    } else {
        "not a plain file"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_devices_and_oversized_files_and_drops_a_bom() {
        let e = read_bytes(Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert_eq!(e.to_string(), "not a regular file (a device)");
        let e = read_bytes(Path::new("/tmp"), 1 << 20).unwrap_err();
        assert_eq!(e.to_string(), "not a regular file (a directory)");
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("a.txt");
        std::fs::write(&f, "\u{feff}hello").unwrap();
        assert_eq!(read_text(&f, 100).unwrap(), "hello");
        let e = read_text(&f, 4).unwrap_err();
        assert_eq!(
            e.to_string(),
            "8 bytes is over the limit of 4 bytes for this kind of file"
        );
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_is_refused_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("fifo");
        let status = std::process::Command::new("mkfifo")
            .arg(&f)
            .status()
            .unwrap();
        assert!(status.success());
        let e = read_bytes(&f, 100).unwrap_err();
        assert_eq!(e.to_string(), "not a regular file (a FIFO)");
    }
}
