//! `ComputeRaster`: the merged opaque triangles rasterized in compute. One compute pass
//! clears a per-pixel `u64` buffer, rasterizes a triangle per thread with a 64-bit
//! atomic min of (depth bits, inverted id), and hands triangles with large bounding boxes
//! to an indirect dispatch of one workgroup per 4,096 pixels of their boxes; a resolve then
//! writes the buffer into the depth texture and the R32Uint visibility texture (a draw or a
//! dispatch, by the depth's format: `compute_raster_resolve.rs`).
//! See `shaders/visibility/compute_raster.wgsl`.

use super::compute_raster_resolve::Resolve;
use super::{defines, pass_error, PrepareCtx, PreparedPass, Timestamps};
use crate::graph::{Name, ScheduledPass};
use crate::render::pipelines::PipelineKey;
use crate::render::RenderError;
use crate::scene::AlphaMode;
use std::collections::BTreeMap;
use std::sync::Arc;
use wgpu::util::DeviceExt;

const SHADER: &str = "visibility/compute_raster.wgsl";
/// Threads per workgroup of the clear and per-triangle dispatches.
const GROUP: u32 = 64;
/// Threads sharing one large triangle.
const BIG_GROUP: u32 = 256;
/// A (clipped) triangle whose pixel bounding box holds more pixels than this goes to the
/// shared-workgroup dispatch: one thread would walk it alone while the others idle.
const BIG_PIXELS: u32 = 1024;
/// Pixels of a large triangle's box per workgroup (16 per thread): a screen-filling
/// floor becomes hundreds of workgroups across the GPU instead of one.
const BIG_CHUNK: u32 = 16 * BIG_GROUP;

/// What the rasterizer needs of the device: 64-bit integers and their atomic min on
/// storage buffers.
pub const FEATURES: wgpu::Features =
    wgpu::Features::SHADER_INT64.union(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX);

pub(super) struct ComputeRasterPass {
    name: Name,
    clear: (Arc<wgpu::ComputePipeline>, wgpu::BindGroup, [u32; 3]),
    raster: (Arc<wgpu::ComputePipeline>, wgpu::BindGroup, [u32; 3]),
    big: (Arc<wgpu::ComputePipeline>, wgpu::BindGroup),
    big_args: wgpu::Buffer,
    resolve: Resolve,
}

/// A 1D grid of `items` threads in groups of `per_group`, folded into y past the
/// device's per-dimension limit (the shaders flatten it back).
fn grid(items: u32, per_group: u32, max: u32) -> [u32; 3] {
    let groups = items.div_ceil(per_group).max(1);
    if groups <= max {
        [groups, 1, 1]
    } else {
        [max, groups.div_ceil(max), 1]
    }
}

/// Why this device cannot run the pass, if it cannot.
pub fn missing_features(have: wgpu::Features, adapter: &str) -> Option<String> {
    let missing = FEATURES - have;
    (!missing.is_empty()).then(|| {
        format!(
            "the compute rasterizer needs 64-bit atomic min on storage buffers; adapter {adapter} lacks {missing:?} (use DepthPrepass there)"
        )
    })
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
) -> Result<ComputeRasterPass, RenderError> {
    let device = cx.device();
    if let Some(m) = missing_features(device.features(), &cx.renderer.ctx.adapter_name()) {
        return Err(pass_error(&sp.name, m));
    }
    let geometry = cx
        .gpu
        .visibility_geometry(&device, cx.scene)
        .map_err(|m| pass_error(&sp.name, m))?;
    // Bit t set: triangle t is culled when it faces away (its material is single-sided).
    let mut single_sided = vec![0u32; (geometry.triangle_count.div_ceil(32)).max(1) as usize];
    for (m, &[first, end]) in geometry.material_ranges.iter().enumerate() {
        let material = &cx.gpu.materials[m];
        if first == end {
            continue;
        }
        if let AlphaMode::Mask(_) = material.alpha_mode {
            return Err(pass_error(
                &sp.name,
                format!(
                    "material '{}' is alpha-masked: ComputeRaster has no alpha test and would cover its cut-out pixels (use DepthPrepass for scenes with masked materials)",
                    material.name
                ),
            ));
        }
        if !material.double_sided {
            for t in first..end {
                single_sided[(t / 32) as usize] |= 1 << (t % 32);
            }
        }
    }
    let (width, height) = (cx.size.width, cx.size.height);
    let pixels = width as u64 * height as u64;
    let limits = device.limits();
    let bytes = 8 * pixels;
    if bytes
        > limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
    {
        return Err(pass_error(
            &sp.name,
            format!(
                "its per-pixel buffer of {bytes} bytes is over this device's storage buffer limit"
            ),
        ));
    }
    let max_groups = limits.max_compute_workgroups_per_dimension;
    // The large-triangle list (triangle, chunk) is dispatched one workgroup per entry, in
    // x only: as many entries as one dispatch holds (512 KiB at 65,535); a triangle that
    // finds it full is drawn by its own thread instead.
    let capacity = max_groups.max(1);
    let storage = |label: &str, size: u64, extra: wgpu::BufferUsages| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::STORAGE | extra,
            mapped_at_creation: false,
        })
    };
    let vis = storage(
        "compute raster depth and ids",
        bytes,
        wgpu::BufferUsages::empty(),
    );
    let big_list = storage(
        "large triangles",
        8 * capacity as u64,
        wgpu::BufferUsages::empty(),
    );
    let big_args = storage("large triangle dispatch", 16, wgpu::BufferUsages::INDIRECT);
    let init = |label: &str, contents: &[u8], usage| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage,
        })
    };
    let params = init(
        "compute raster params",
        bytemuck::cast_slice(&[geometry.triangle_count, capacity, width, height]),
        wgpu::BufferUsages::UNIFORM,
    );
    let sides = init(
        "single-sided triangles",
        bytemuck::cast_slice(&single_sided),
        wgpu::BufferUsages::STORAGE,
    );
    let mut offered = cx.declared(sp)?;
    offered.buffer("raster_params", &params);
    offered.buffer("single_sided", &sides);
    offered.buffer("vis", &vis);
    offered.buffer("big_list", &big_list);
    offered.buffer("big_args", &big_args);
    let key = |d: &[(&str, String)], state: &str| PipelineKey {
        shader: SHADER.into(),
        defines: defines(d),
        virtual_code: BTreeMap::new(),
        state: state.into(),
    };
    let consts = [
        ("GROUP", format!("{GROUP}u")),
        ("BIG_GROUP", format!("{BIG_GROUP}u")),
        ("BIG_PIXELS", format!("{BIG_PIXELS}u")),
        ("BIG_CHUNK", format!("{BIG_CHUNK}u")),
    ];
    let (clear, clear_bind) =
        cx.compute_pipeline(&sp.name, key(&consts, "clear"), "clear", &offered)?;
    let mut atomic = consts.to_vec();
    atomic.push(("ATOMIC", "1".into()));
    let (raster, raster_bind) =
        cx.compute_pipeline(&sp.name, key(&atomic, "raster"), "raster", &offered)?;
    atomic.push(("BIG", "1".into()));
    let big = cx.compute_pipeline(&sp.name, key(&atomic, "raster_big"), "raster_big", &offered)?;
    let resolve = Resolve::prepare(cx, sp, key(&[("RESOLVE", "1".into())], "resolve"), &offered)?;
    Ok(ComputeRasterPass {
        name: sp.name.clone(),
        clear: (
            clear,
            clear_bind,
            grid(pixels.min(u32::MAX as u64) as u32, GROUP, max_groups),
        ),
        raster: (
            raster,
            raster_bind,
            grid(geometry.triangle_count, GROUP, max_groups),
        ),
        big,
        big_args,
        resolve,
    })
}

impl PreparedPass for ComputeRasterPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        // One timestamp pair around all of it: the compute pass opens it, the resolve
        // (a dispatch in it, or a draw after it) closes it.
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&self.name),
            timestamp_writes: self.resolve.compute_timestamps(ts),
        });
        // wgpu orders dispatches that use a buffer read-write with a barrier between them.
        for (pipeline, bind, [x, y, z]) in [&self.clear, &self.raster] {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, bind, &[]);
            pass.dispatch_workgroups(*x, *y, *z);
        }
        pass.set_pipeline(&self.big.0);
        pass.set_bind_group(0, &self.big.1, &[]);
        pass.dispatch_workgroups_indirect(&self.big_args, 0);
        self.resolve.dispatch(&mut pass);
        drop(pass);
        self.resolve.draw(encoder, &self.name, ts);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_the_adapter_and_the_missing_feature() {
        let m = missing_features(wgpu::Features::SHADER_INT64, "Example GPU (Vulkan)").unwrap();
        assert!(m.contains("Example GPU (Vulkan)"), "{m}");
        assert!(m.contains("SHADER_INT64_ATOMIC_MIN_MAX"), "{m}");
        assert!(missing_features(FEATURES, "x").is_none());
    }

    #[test]
    fn large_grids_fold_into_y() {
        assert_eq!(grid(0, 64, 65535), [1, 1, 1]);
        assert_eq!(grid(64 * 65535, 64, 65535), [65535, 1, 1]);
        assert_eq!(grid(64 * 65535 + 1, 64, 65535), [65535, 2, 1]);
    }
}
