//! glTF's alignment rules for accessors: an accessor's `byteOffset`, its offset within
//! the buffer and its view's `byteStride` are multiples of its component size (2.0 spec,
//! §3.6.2.4). Readers that map buffers as typed arrays rely on it.

/// Why `acc` read through `view` breaks the rules, if it does.
pub(super) fn misalignment(acc: &gltf::Accessor, view: &gltf::buffer::View) -> Option<String> {
    let size = acc.data_type().size();
    let (acc_off, view_off) = (acc.offset(), view.offset());
    if acc_off % size != 0 {
        return Some(format!(
            "byteOffset {acc_off} is not a multiple of its component size {size}"
        ));
    }
    if (view_off + acc_off) % size != 0 {
        return Some(format!(
            "starts at buffer offset {} (bufferView {} at {view_off} + {acc_off}), not a multiple of its component size {size}",
            view_off + acc_off,
            view.index()
        ));
    }
    match view.stride() {
        Some(stride) if stride % size != 0 => Some(format!(
            "bufferView {} byteStride {stride} is not a multiple of the component size {size}",
            view.index()
        )),
        _ => None,
    }
}
