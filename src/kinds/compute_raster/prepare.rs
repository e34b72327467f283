//! `ComputeRaster`: the merged opaque triangles rasterized in compute into a per-pixel
//! `u64` buffer with a 64-bit atomic min of (depth bits, inverted id). One compute pass of
//! four dispatches: `clear`; `setup`, a thread per triangle, covers a (clipped) fan
//! triangle of at most 16 pixels itself, else appends a record and either the 8×8-pixel
//! blocks it may cover (a box within 2×2 blocks) or its 64×64-pixel tiles to lists;
//! `bin` (indirect), a thread per block of a tile, appends the tile's blocks the triangle
//! may cover; `raster` (indirect), a thread per pixel of a block. A resolve then writes the buffer into the
//! depth texture and the R32Uint visibility texture (a draw or a dispatch, by the depth's
//! format: `resolve.rs`). Alpha-masked materials: setup, bin and raster
//! run again per group of masked materials that share their code (as visibility
//! shading groups them), with that code testing alpha per pixel; the first run draws the
//! opaque triangles, and the only group's too where there is one (flagged for the test).
//! With a transparent depth in its writes the first run also draws the blended triangles
//! (flagged: their nearest depth alone, and their farthest where it writes that too).
//! See `shaders/visibility/compute_raster.wgsl`.

use super::compute_raster_lists::{
    list_capacity, ListCapacity, TestLimits, ENTRY_BYTES, RECORD_BYTES,
};
use super::compute_raster_resolve::{Glass, Resolve};
use super::{defines, grid, pass_error, PrepareCtx, PreparedPass, Timestamps};
use crate::gpu::readback::read_buffer;
use crate::graph::{slot, Name, ScheduledPass};
use crate::render::materials::{group_label, shared_code_groups, GroupConstants, MaterialProgram};
use crate::render::pipelines::PipelineKey;
use crate::render::report::{PassReport, RasterReport};
use crate::render::{RenderError, Renderer};
use std::collections::BTreeMap;
use std::sync::Arc;
use wgpu::util::DeviceExt;

const SHADER: &str = "visibility/compute_raster.wgsl";
/// Threads per workgroup of the setup dispatch (a thread per triangle).
const GROUP: u32 = 64;
/// Threads per workgroup of the clear (a thread per pixel): a quarter as many workgroups
/// to launch as 64 (32,400 at 1080p).
const CLEAR_GROUP: u32 = 256;
/// Pixels per side of a block, a thread per pixel in `raster`: small enough to fit the
/// many small triangles tightly (a box of a few pixels touches one to four blocks).
pub(super) const BLOCK: u32 = 8;
/// Blocks per `raster` workgroup (256 threads): tiny workgroups are bound by how fast
/// the GPU launches them (harada lists ~57,500 blocks at 1080p); four blocks a workgroup
/// launch a quarter as many, with the same occupancy and still a thread per pixel.
const BLOCKS_PER_GROUP: u32 = 4;
/// Blocks per side of a tile, a thread per block in `bin`. Setup lists a triangle's
/// tiles serially, so a screen-filling triangle costs its thread 510 stores at 1080p
/// (not 32,400 blocks).
const TILE_BLOCKS: u32 = 8;
/// Tiles per `bin` workgroup (256 threads), as for blocks.
const TILES_PER_GROUP: u32 = 4;
pub(super) const TILE_PIXELS: u32 = BLOCK * TILE_BLOCKS;
/// Most triangles: the record counter grows by up to 6 per triangle (a triangle clipped
/// by five planes is a fan of six) without checking, so this keeps it from wrapping.
const MAX_TRIANGLES: u32 = u32::MAX / 8;
/// Words of the counter buffer (see the shader's `RECORDS`..`BLOCK_TRIANGLES`).
const COUNTERS: usize = 8;
/// What the rasterizer needs of the device: 64-bit integers and their atomic min on
/// storage buffers.
pub const FEATURES: wgpu::Features =
    wgpu::Features::SHADER_INT64.union(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX);

pub(super) struct ComputeRasterPass {
    name: Name,
    /// The opaque triangles' run (its clear also clears the per-pixel buffer), then one
    /// per group of alpha-masked materials sharing their code.
    runs: Vec<RasterRun>,
    /// Indirect arguments of `bin` and `raster`, written by the dispatch before each.
    tile_args: wgpu::Buffer,
    block_args: wgpu::Buffer,
    capacity: ListCapacity,
    resolve: Resolve,
}

/// One pass of the rasterizer over some triangles: its dispatches and its own counters.
struct RasterRun {
    clear: Dispatch,
    setup: Dispatch,
    bin: Dispatch,
    raster: Dispatch,
    /// Workgroups of `clear` and `setup` (`bin` and `raster` are indirect).
    grids: [[u32; 3]; 2],
    counters: wgpu::Buffer,
}

/// A pipeline with its bind groups: group 0, and the material's textures (group 2) in an
/// alpha-tested run.
struct Dispatch {
    pipeline: Arc<wgpu::ComputePipeline>,
    bind: wgpu::BindGroup,
    textures: Option<wgpu::BindGroup>,
}

impl Dispatch {
    fn bind(&self, pass: &mut wgpu::ComputePass<'_>) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind, &[]);
        if let Some(t) = &self.textures {
            pass.set_bind_group(2, t, &[]);
        }
    }
}

/// The registry's entry point: the compute rasterizer, or its hardware fallback on an
/// adapter without [`FEATURES`].
pub(super) use super::compute_raster_fallback::prepare;

/// The compute path, for a device with [`FEATURES`]: `compute_raster_fallback::prepare`
/// picks the hardware path on any other.
pub(super) fn prepare_compute(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
) -> Result<ComputeRasterPass, RenderError> {
    prepare_source(cx, sp, RasterSource::Opaque)
}

/// The triangles a compute raster pass draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum RasterSource {
    /// The opaque and alpha-masked meshes (`ComputeRaster`): the visibility ids, back
    /// faces of single-sided materials culled, masked materials alpha-tested, resolved
    /// into the depth and the visibility texture.
    Opaque,
    /// The blended meshes (`TransparentDepth` into an R32Float depth): both faces, as
    /// the transparent depth prepass draws them, resolved into the depth alone.
    Blended,
}

/// The compute rasterizer over `source`'s triangles, into the pass's `depth` (and, for
/// the opaque triangles, `visibility`).
pub(super) fn prepare_source(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    source: RasterSource,
) -> Result<ComputeRasterPass, RenderError> {
    let device = cx.device();
    let opaque = source == RasterSource::Opaque;
    let geometry = match source {
        RasterSource::Opaque => cx.gpu.visibility_geometry(&device, cx.scene),
        RasterSource::Blended => cx.gpu.transparent_geometry(&device, cx.scene),
    }
    .map_err(|m| pass_error(&sp.name, m))?;
    // The blended triangles, drawn in the opaque run where the pass writes their depth
    // too (none where the scene has none: the transparent depth is then left unwritten,
    // as a TransparentDepth pass under `when: Some(Transparent)` would be skipped).
    let glass = match sp.roles.slot(slot::TRANSPARENT_DEPTH) {
        Some(_) if opaque => Some(
            cx.gpu
                .transparent_geometry(&device, cx.scene)
                .map_err(|m| pass_error(&sp.name, m))?,
        )
        .filter(|g| g.triangle_count > 0),
        _ => None,
    };
    let glass_triangles = glass.map_or(0, |g| g.triangle_count);
    // Their farthest depth too, where the pass writes it.
    let far = glass.is_some() && sp.roles.slot(slot::TRANSPARENT_FAR).is_some();
    // Bit t set: triangle t is culled when it faces away (its material is single-sided);
    // in `alpha_tested`, its masked material's run draws it. Blended triangles: neither.
    let words = (geometry.triangle_count.div_ceil(32)).max(1) as usize;
    let mut single_sided = vec![0u32; words];
    let mut alpha_tested = vec![0u32; words];
    // The masked materials that have triangles, ascending.
    let mut masked = Vec::new();
    let ranges = if opaque {
        &geometry.material_ranges[..]
    } else {
        &[]
    };
    for (m, &[first, end]) in ranges.iter().enumerate() {
        let material = &cx.gpu.materials[m];
        if first == end {
            continue;
        }
        let mark = |bits: &mut [u32]| {
            for t in first..end {
                bits[(t / 32) as usize] |= 1 << (t % 32);
            }
        };
        if material.alpha_mode.is_masked() {
            mark(&mut alpha_tested);
            masked.push(m);
        }
        if !material.double_sided {
            mark(&mut single_sided);
        }
    }
    let (width, height) = (cx.size.width, cx.size.height);
    let pixels = width as u64 * height as u64;
    let limits = device.limits();
    let bytes = 8 * pixels;
    let max_binding = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    if bytes > max_binding {
        return Err(pass_error(
            &sp.name,
            format!(
                "its per-pixel buffer of {bytes} bytes is over this device's storage buffer limit"
            ),
        ));
    }
    let all_triangles = geometry.triangle_count as u64 + glass_triangles as u64;
    if all_triangles > MAX_TRIANGLES as u64 {
        return Err(pass_error(
            &sp.name,
            format!("{all_triangles} triangles are over the {MAX_TRIANGLES} it counts"),
        ));
    }
    // Pixel coordinates are packed in 16 bits in the lists' entries.
    if width > 1 << 16 || height > 1 << 16 {
        return Err(pass_error(
            &sp.name,
            format!("{width}×{height} is over the 65,536 pixels a side it addresses"),
        ));
    }
    let test_limits = TestLimits::from_env().map_err(|m| pass_error(&sp.name, m))?;
    let (capacity, max_groups) = test_limits.apply(
        list_capacity(all_triangles as u32, width, height, max_binding),
        limits.max_compute_workgroups_per_dimension.max(1),
    );
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
    let none = wgpu::BufferUsages::empty();
    // At least one entry each: a buffer of capacity 0 (the test hook) still binds.
    let records = storage(
        "compute raster triangle records",
        RECORD_BYTES * capacity.records.max(1) as u64,
        none,
    );
    let tiles = storage(
        "compute raster tiles",
        ENTRY_BYTES * capacity.tiles.max(1) as u64,
        none,
    );
    let blocks = storage(
        "compute raster blocks",
        ENTRY_BYTES * capacity.blocks.max(1) as u64,
        none,
    );
    let tile_args = storage(
        "compute raster bin dispatch",
        16,
        wgpu::BufferUsages::INDIRECT,
    );
    let block_args = storage(
        "compute raster block dispatch",
        16,
        wgpu::BufferUsages::INDIRECT,
    );
    let init = |label: &str, contents: &[u8], usage| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage,
        })
    };
    let params = init(
        "compute raster params",
        bytemuck::cast_slice(&[geometry.triangle_count, max_groups, width, height]),
        wgpu::BufferUsages::UNIFORM,
    );
    let list_capacity = init(
        "compute raster list capacity",
        bytemuck::cast_slice(&[
            capacity.records,
            capacity.tiles,
            capacity.blocks,
            test_limits.direct_paths(),
        ]),
        wgpu::BufferUsages::UNIFORM,
    );
    let sides = init(
        "single-sided triangles",
        bytemuck::cast_slice(&single_sided),
        wgpu::BufferUsages::STORAGE,
    );
    let alpha_tested = init(
        "alpha-tested triangles",
        bytemuck::cast_slice(&alpha_tested),
        wgpu::BufferUsages::STORAGE,
    );
    let mut offered = cx.declared(sp)?;
    if !opaque {
        // The graph imports the opaque merge under these names; the blended pass reads
        // its own.
        offered.buffer("vertices", &geometry.vertices);
        offered.buffer("triangles", &geometry.triangles);
    }
    offered.buffer("raster_params", &params);
    offered.buffer("list_capacity", &list_capacity);
    offered.buffer("single_sided", &sides);
    offered.buffer("vis", &vis);
    offered.buffer("records", &records);
    offered.buffer("tiles", &tiles);
    offered.buffer("blocks", &blocks);
    offered.buffer("alpha_tested", &alpha_tested);
    if let Some(g) = glass {
        offered.buffer("glass_vertices", &g.vertices);
        offered.buffer("glass_triangles", &g.triangles);
        offered.buffer(
            "glass_params",
            &init(
                "compute raster glass params",
                bytemuck::cast_slice(&[g.triangle_count, 0, 0, 0]),
                wgpu::BufferUsages::UNIFORM,
            ),
        );
        // Per pixel the nearest depth's bits, and the farthest's after it where kept.
        let words = 1 + far as u64;
        offered.buffer(
            "glass_depth",
            &storage("compute raster glass depths", 4 * words * pixels, none),
        );
    }
    offered.buffer("tile_args", &tile_args);
    offered.buffer("block_args", &block_args);
    let key = |d: &[(&str, String)], state: &str, material: Option<&str>| PipelineKey {
        shader: SHADER.into(),
        defines: defines(d),
        virtual_code: material
            .map(|code| BTreeMap::from([("material".to_string(), code.to_string())]))
            .unwrap_or_default(),
        state: state.into(),
    };
    let sizes = [
        ("GROUP", format!("{GROUP}u")),
        ("CLEAR_GROUP", format!("{CLEAR_GROUP}u")),
        ("BLOCK", format!("{BLOCK}u")),
        ("BLOCKS_PER_GROUP", format!("{BLOCKS_PER_GROUP}u")),
        ("TILE_BLOCKS", format!("{TILE_BLOCKS}u")),
        ("TILES_PER_GROUP", format!("{TILES_PER_GROUP}u")),
    ];
    // Masked materials that differ only in constants (and read the same images) share one
    // run, their constants read from `material_constants` (as visibility shading groups).
    let materials = &cx.gpu.materials;
    let groups = shared_code_groups(materials, &masked);
    let constants = GroupConstants::new(materials, &groups);
    constants.offer(&device, &mut offered);
    // (opaque, masked group) per run: the opaque run over every triangle, then a run per
    // group; one group alone is folded into the opaque run (its triangles flagged for
    // the alpha test there), which saves its four dispatches.
    let plan: Vec<(bool, Option<&Vec<usize>>)> = match &groups[..] {
        [group] => vec![(true, Some(group))],
        _ => std::iter::once((true, None))
            .chain(groups.iter().map(|g| (false, Some(g))))
            .collect(),
    };
    let mut runs = Vec::new();
    for (opaque_run, run) in plan {
        let counters = storage(
            "compute raster counters",
            4 * COUNTERS as u64,
            wgpu::BufferUsages::COPY_SRC,
        );
        let mut offered = offered.clone();
        offered.buffer("counters", &counters);
        let mut material_defines = Vec::new();
        let mut material = None;
        let mut setup_triangles = geometry.triangle_count;
        // The glass rides in the opaque run (the first).
        let mut glass_defines = Vec::new();
        if opaque_run && glass.is_some() {
            setup_triangles += glass_triangles;
            glass_defines.push(("GLASS", "1".to_string()));
            if far {
                glass_defines.push(("GLASS_FAR", "1".to_string()));
            }
        }
        if let Some(group) = run {
            let members = MaskedMembers::new(materials, group, ranges, &constants);
            if opaque_run {
                material_defines.push(("FOLDED", "1".to_string()));
            } else {
                setup_triangles = members.triangles;
            }
            offered.buffer(
                "masked_members",
                &init(
                    "masked materials' triangles",
                    bytemuck::cast_slice(&members.table),
                    wgpu::BufferUsages::STORAGE,
                ),
            );
            let m = &materials[group[0]];
            let shared = group.len() > 1;
            material_defines.push(("ALPHA_TEST", "1".to_string()));
            material_defines.push(("MEMBERS_COUNT", format!("{}u", group.len())));
            material_defines.push(("MEMBERS_THREADS", format!("{}u", members.triangles)));
            if shared {
                material_defines.push(("SHARED_CODE", "1".to_string()));
            }
            if m.textures.is_some() {
                material_defines.push(("MATERIAL_TEXTURED", "1".to_string()));
            }
            material = Some((
                m.group_code(shared).to_string(),
                m.textures.clone(),
                group_label(&sp.name, materials, group),
            ));
        }
        let label = match &material {
            Some((_, _, group)) if opaque_run => format!("{group}, alpha-tested"),
            Some((_, _, group)) => format!("{group}'s alpha test"),
            None => sp.name.to_string(),
        };
        let mut pipeline = |stage: &str, entry: &str, extra: &[(&str, String)]| {
            let mut d = sizes.to_vec();
            d.push((stage, "1".into()));
            d.extend_from_slice(extra);
            let (code, set) = match &material {
                Some((code, set, _)) if stage != "CLEAR" => (Some(code.as_str()), set.as_ref()),
                _ => (None, None),
            };
            let (pipeline, bind, textures) = cx.compute_pipeline_with_material(
                &label,
                key(&d, entry, code),
                entry,
                &offered,
                set,
            )?;
            Ok::<_, RenderError>(Dispatch {
                pipeline,
                bind,
                textures,
            })
        };
        material_defines.extend(glass_defines.iter().cloned());
        let (clear, clear_items) = if opaque_run {
            (
                pipeline("CLEAR", "clear", &glass_defines)?,
                pixels.min(u32::MAX as u64) as u32,
            )
        } else {
            // The counters and arguments only, keeping the buffer.
            (
                pipeline("CLEAR", "clear", &[("LISTS_ONLY", "1".into())])?,
                COUNTERS as u32,
            )
        };
        let setup = pipeline("SETUP", "setup", &material_defines)?;
        let bin = pipeline("BIN", "bin", &material_defines)?;
        let raster = pipeline("RASTER", "raster", &material_defines)?;
        runs.push(RasterRun {
            clear,
            setup,
            bin,
            raster,
            grids: [
                grid(clear_items, CLEAR_GROUP, max_groups),
                grid(setup_triangles, GROUP, max_groups),
            ],
            counters,
        });
    }
    let resolve = Resolve::prepare(
        cx,
        sp,
        key(&[("RESOLVE", "1".into())], "resolve", None),
        &offered,
        opaque,
        match (glass.is_some(), far) {
            (false, _) => Glass::None,
            (true, false) => Glass::Nearest,
            (true, true) => Glass::NearestAndFarthest,
        },
    )?;
    Ok(ComputeRasterPass {
        name: sp.name.clone(),
        runs,
        tile_args,
        block_args,
        capacity,
        resolve,
    })
}

/// A masked run's materials as its shader finds them (`masked_members`): per material, its
/// first triangle, the first setup thread that draws it (its triangles follow the earlier
/// members'), its first constant in `material_constants` and its alpha cutoff's bits.
struct MaskedMembers {
    table: Vec<[u32; 4]>,
    /// The members' triangles together: the setup dispatch's threads.
    triangles: u32,
}

impl MaskedMembers {
    fn new(
        materials: &[MaterialProgram],
        group: &[usize],
        ranges: &[[u32; 2]],
        constants: &GroupConstants,
    ) -> Self {
        let mut table = Vec::with_capacity(group.len());
        let mut triangles = 0;
        for &m in group {
            let [first, end] = ranges[m];
            let cutoff = materials[m].alpha_mode.cutoff();
            table.push([first, triangles, constants.first[m], cutoff.to_bits()]);
            triangles += end - first;
        }
        Self { table, triangles }
    }
}

impl ComputeRasterPass {
    /// The rasterizing dispatches, in one compute pass (wgpu orders dispatches that use a
    /// buffer read-write, or as indirect arguments after writing it, with barriers).
    fn record_raster(&self, pass: &mut wgpu::ComputePass<'_>) {
        for run in &self.runs {
            for (dispatch, [x, y, z]) in [(&run.clear, run.grids[0]), (&run.setup, run.grids[1])] {
                dispatch.bind(pass);
                pass.dispatch_workgroups(x, y, z);
            }
            for (dispatch, args) in [(&run.bin, &self.tile_args), (&run.raster, &self.block_args)] {
                dispatch.bind(pass);
                pass.dispatch_workgroups_indirect(args, 0);
            }
        }
    }

    /// The lists' fill (the fullest run's) and the serial fallbacks (all runs') of the
    /// last frame.
    fn raster_report(&self, r: &Renderer) -> Result<RasterReport, RenderError> {
        let cap = self.capacity;
        let mut report = RasterReport {
            pass: self.name.to_string(),
            records: 0,
            records_capacity: cap.records,
            tiles: 0,
            tiles_capacity: cap.tiles,
            blocks: 0,
            blocks_capacity: cap.blocks,
            serial_triangles: 0,
            serial_tiles: 0,
            serial_blocks: 0,
            small_triangles: 0,
            block_triangles: 0,
        };
        for run in &self.runs {
            let bytes = read_buffer(&r.ctx.device, &r.ctx.queue, &run.counters)?;
            let c: &[u32] = bytemuck::cast_slice(&bytes);
            report.records = report.records.max(c[0].min(cap.records));
            report.tiles = report.tiles.max(c[1].min(cap.tiles));
            report.blocks = report.blocks.max(c[2].min(cap.blocks));
            report.serial_triangles += c[3];
            report.serial_tiles += c[4];
            report.serial_blocks += c[5];
            report.small_triangles += c[6];
            report.block_triangles += c[7];
        }
        Ok(report)
    }
}

impl PreparedPass for ComputeRasterPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        // One timestamp pair around all of it: the compute pass opens it, the resolve
        // (a dispatch in it, or a draw after it) closes it.
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&self.name),
            timestamp_writes: self.resolve.compute_timestamps(ts),
        });
        self.record_raster(&mut pass);
        self.resolve.dispatch(&mut pass);
        drop(pass);
        self.resolve.draw(encoder, &self.name, ts);
    }

    fn report(&self, r: &Renderer) -> Result<Option<PassReport>, RenderError> {
        Ok(Some(PassReport::Raster(self.raster_report(r)?)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn large_grids_fold_into_y() {
        assert_eq!(grid(0, 64, 65535), [1, 1, 1]);
        assert_eq!(grid(64 * 65535, 64, 65535), [65535, 1, 1]);
        assert_eq!(grid(64 * 65535 + 1, 64, 65535), [65535, 2, 1]);
    }
}
