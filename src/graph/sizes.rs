//! Part of step 2: sizes a graph declares, checked before any frame is planned. Texture
//! and buffer sizes must stay inside what any frame can allocate, a buffer a built-in pass
//! lays out must be sized by that pass, and a compute dispatch must cover the frame with
//! the shader's own workgroup size. What depends on the device or the frame (the device's
//! texture and buffer limits, per-light dispatch counts) is checked again at prepare.

use super::error::GraphError;
use super::kinds;
use super::location::SourceText;
use super::model::{BufferSize, Dispatch, GraphDesc, PassDesc, ResourceDesc, TextureSize};
use super::roles::PassRoles;
use rustc_hash::FxHashMap;
use std::sync::Arc;

/// Largest output side the CLI and scene files accept.
pub const MAX_FRAME_SIDE: u32 = 16384;
/// Largest side of a `Fixed` texture.
pub const MAX_TEXTURE_SIDE: u32 = 16384;
/// Largest `Scaled` factor (a texture up to 4× the output per side).
pub const MAX_SCALE: f32 = 4.0;
/// Largest `Bytes` buffer, and largest per-pixel, per-tile or per-light unit.
pub const MAX_BUFFER_BYTES: u64 = 1 << 40;
pub(crate) const MAX_BUFFER_UNIT: u64 = 1 << 32;
/// WebGPU's default limits, which every wgpu device offers.
pub const MAX_WORKGROUPS_PER_DIMENSION: u32 = 65535;
pub(crate) const MAX_INVOCATIONS_PER_WORKGROUP: u32 = 256;
pub(crate) const MAX_WORKGROUP_SIZE: [u32; 3] = [256, 256, 64];
/// Sample counts wgpu knows; which of them a format has on the adapter is checked at
/// prepare (`render/device_limits.rs`).
pub const SAMPLE_COUNTS: [u32; 5] = [1, 2, 4, 8, 16];

pub(crate) fn check_resources(desc: &GraphDesc, source: &SourceText, errors: &mut Vec<GraphError>) {
    for r in &desc.resources {
        let problem = match r {
            ResourceDesc::Texture { size, samples, .. } => texture_problem(*size).or_else(|| {
                (!SAMPLE_COUNTS.contains(samples))
                    .then(|| format!("samples: {samples} is not supported (1, 2, 4, 8 or 16)"))
            }),
            ResourceDesc::Buffer { size, .. } => buffer_problem(*size),
            ResourceDesc::Import { .. } => None,
        };
        let Some(problem) = problem else { continue };
        // Named with the pass that writes it, where it is too small or too big.
        let writer = desc
            .passes
            .iter()
            .find(|p| p.writes.iter().any(|w| w == r.name()));
        errors.push(match writer {
            Some(pass) => GraphError::Mismatch {
                at: source.in_pass(&pass.name, r.name()),
                pass: pass.name.to_string(),
                resource: r.name().to_string(),
                problem,
            },
            None => GraphError::BadResource {
                at: source.of_declaration(r.name()),
                resource: r.name().to_string(),
                problem,
            },
        });
    }
}

fn texture_problem(size: TextureSize) -> Option<String> {
    match size {
        TextureSize::Output => None,
        TextureSize::Scaled(s) if !(s > 0.0 && s <= MAX_SCALE) => Some(format!(
            "size Scaled({s}) must be a factor in (0, {MAX_SCALE}] of the output"
        )),
        TextureSize::Fixed(w, h)
            if !(1..=MAX_TEXTURE_SIDE).contains(&w) || !(1..=MAX_TEXTURE_SIDE).contains(&h) =>
        {
            Some(format!(
                "size Fixed({w}, {h}) must lie in 1..={MAX_TEXTURE_SIDE} per side"
            ))
        }
        _ => None,
    }
}

fn buffer_problem(size: BufferSize) -> Option<String> {
    let unit = |what: &str, b: u64| {
        (b == 0 || b > MAX_BUFFER_UNIT)
            .then(|| format!("size {what}({b}) must be 1..={MAX_BUFFER_UNIT} bytes a unit"))
    };
    match size {
        BufferSize::Auto => None,
        BufferSize::Bytes(b) if b > MAX_BUFFER_BYTES => Some(format!(
            "size Bytes({b}) is over the limit of {MAX_BUFFER_BYTES} bytes"
        )),
        BufferSize::Bytes(_) => None,
        BufferSize::PerTile { tile, .. } if !(1..=MAX_FRAME_SIDE).contains(&tile) => Some(format!(
            "size PerTile(tile: {tile}) must be 1..={MAX_FRAME_SIDE} pixels"
        )),
        BufferSize::PerTile { bytes, .. } => unit("PerTile", bytes),
        BufferSize::PerPixel(b) => unit("PerPixel", b),
        BufferSize::PerLight(b) => unit("PerLight", b),
    }
}

/// A buffer a built-in pass lays out (light lists, shadow jobs, the shadow mask) follows
/// the frame and the pass's parameters: only `size: Auto` is always big enough.
pub(crate) fn check_laid_out_buffers(
    desc: &GraphDesc,
    resources: &FxHashMap<&str, &ResourceDesc>,
    roles: &[Arc<PassRoles>],
    source: &SourceText,
    errors: &mut Vec<GraphError>,
) {
    let frame = super::plan::FrameSize {
        width: 1280,
        height: 720,
        lights: 1,
    };
    for (pass, r) in desc.passes.iter().zip(roles) {
        for (slot, name) in &r.slots {
            if !pass.writes.contains(name) {
                continue;
            }
            let Some(layout) = kinds::buffer_layout(&pass.kind, slot, frame) else {
                continue;
            };
            let declared = match resources.get(name.as_str()) {
                Some(ResourceDesc::Buffer { size, .. }) => Some(*size),
                _ => None,
            };
            if let Some(size) = declared.filter(|s| *s != BufferSize::Auto) {
                errors.push(GraphError::Mismatch {
                    at: source.in_pass(&pass.name, name),
                    pass: pass.name.to_string(),
                    resource: name.to_string(),
                    problem: format!(
                        "{} lays out slot '{slot}' from the frame and its parameters ({} bytes at 1280×720): declare the buffer `size: Auto`, not {size:?}",
                        pass.kind.label(),
                        layout.bytes()
                    ),
                });
            }
        }
    }
}

/// A generic compute pass's dispatch against its shader's `@workgroup_size`.
pub fn check_dispatch(
    pass: &PassDesc,
    dispatch: Dispatch,
    workgroup: [u32; 3],
    source: &SourceText,
    file: &str,
) -> Option<GraphError> {
    let bad = |problem: String| GraphError::BadPass {
        at: source.in_pass(&pass.name, "dispatch"),
        pass: pass.name.to_string(),
        problem,
    };
    let [x, y, z] = workgroup;
    let invocations = x as u64 * y as u64 * z as u64;
    if invocations > MAX_INVOCATIONS_PER_WORKGROUP as u64
        || workgroup
            .iter()
            .zip(MAX_WORKGROUP_SIZE)
            .any(|(a, m)| *a > m)
    {
        return Some(bad(format!(
            "{file}: @workgroup_size({x}, {y}, {z}) is over the device limits ({MAX_INVOCATIONS_PER_WORKGROUP} invocations, {MAX_WORKGROUP_SIZE:?} per side)"
        )));
    }
    let max = MAX_WORKGROUPS_PER_DIMENSION;
    match dispatch {
        Dispatch::Fixed(a, b, c) => {
            if [a, b, c].iter().any(|&n| n == 0 || n > max) {
                return Some(bad(format!(
                    "dispatch Fixed({a}, {b}, {c}) must have 1..={max} workgroups per dimension"
                )));
            }
        }
        Dispatch::PerPixel { workgroup: (a, b) } => {
            if (a, b, 1) != (x, y, z) {
                return Some(bad(format!(
                    "dispatch PerPixel(workgroup: ({a}, {b})) does not match {file}'s @workgroup_size({x}, {y}, {z}): pixels would be missed or run twice"
                )));
            }
        }
        Dispatch::PerLight { workgroup: w } => {
            if (w, 1, 1) != (x, y, z) {
                return Some(bad(format!(
                    "dispatch PerLight(workgroup: {w}) does not match {file}'s @workgroup_size({x}, {y}, {z}): lights would be missed or run twice"
                )));
            }
        }
        Dispatch::PerTile { tile } => {
            if !(1..=MAX_FRAME_SIDE).contains(&tile) {
                return Some(bad(format!(
                    "dispatch PerTile(tile: {tile}) must be 1..={MAX_FRAME_SIDE} pixels"
                )));
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_outside_any_frame_are_refused() {
        assert!(texture_problem(TextureSize::Scaled(f32::NAN)).is_some());
        assert!(texture_problem(TextureSize::Scaled(0.5)).is_none());
        assert!(texture_problem(TextureSize::Fixed(100000, 4)).is_some());
        assert!(texture_problem(TextureSize::Fixed(0, 4)).is_some());
        assert!(texture_problem(TextureSize::Fixed(16384, 1)).is_none());
        assert!(buffer_problem(BufferSize::PerPixel(1 << 62)).is_some());
        assert!(buffer_problem(BufferSize::PerLight(0)).is_some());
        assert!(buffer_problem(BufferSize::PerLight(16)).is_none());
        assert!(buffer_problem(BufferSize::Bytes(16)).is_none());
    }
}
