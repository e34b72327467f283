//! What the CPU hands the shadow atlas's compute rasterizer (raster.rs): the casters
//! merged into one geometry, each frame's list of views to draw (jobs, tiles and the
//! pieces `store` copies), and the test hook that caps the lists.

use super::PrepareCtx;
use crate::render::scene_gpu::SceneGpu;
use crate::scene::AlphaMode;

/// Texels per side of a store workgroup's piece.
pub(super) const STORE_CELL: u32 = 16;
/// Texels per side of a cell entry (the shader's CELL).
const CELL: u32 = 32;
/// Bytes of a record and of a cell entry (as the shader's).
pub(super) const RECORD_BYTES: u64 = 64;
pub(super) const ENTRY_BYTES: u64 = 8;
/// Most records (the record counter grows by one a fan triangle past it, at most six a
/// pair).
const MAX_RECORDS: u64 = 1 << 24;

/// Test hook: `records=N,cells=N` (either) caps the lists' capacities below what
/// prepare sizes, so tests can fill them and watch the serial fallback. Read when the
/// pass is prepared; a malformed value is an error naming it.
pub const TEST_LIMITS_VAR: &str = "LIGHTGRAPH_ATLAS_RASTER_TEST_LIMITS";

/// The test hook's caps on (records, cells).
fn test_limits() -> Result<[Option<u32>; 2], String> {
    let mut caps = [None, None];
    let Ok(text) = std::env::var(TEST_LIMITS_VAR) else {
        return Ok(caps);
    };
    for item in text.split(',').map(str::trim).filter(|i| !i.is_empty()) {
        let bad = || {
            format!("{TEST_LIMITS_VAR}: '{item}' is not records=COUNT or cells=COUNT (COUNT >= 1)")
        };
        let (name, value) = item.split_once('=').ok_or_else(bad)?;
        let value: u32 = value.trim().parse().map_err(|_| bad())?;
        let slot = match name.trim() {
            "records" if value >= 1 => &mut caps[0],
            "cells" if value >= 1 => &mut caps[1],
            _ => return Err(bad()),
        };
        *slot = Some(value);
    }
    Ok(caps)
}

/// The lists' capacities (records, cells) for `texels` texels, each list in one binding
/// of at most `limit` bytes. Large triangles: room for a record per 64 texels and
/// sixteen cells per 32² of them (depth complexity 16 of large triangles); past that the
/// setup thread draws them itself (counted). The test hook lowers them.
pub(super) fn list_capacity(texels: u64, limit: u64) -> Result<[u32; 2], String> {
    let records = (texels / 64).min(limit / RECORD_BYTES).min(MAX_RECORDS) as u32;
    let cells = (16 * texels / (CELL as u64 * CELL as u64))
        .min(limit / ENTRY_BYTES)
        .max(1) as u32;
    let caps = test_limits()?;
    Ok([
        caps[0].map_or(records, |n| n.min(records)).max(1),
        caps[1].map_or(cells, |n| n.min(cells)).max(1),
    ])
}

/// One frame's work, as the CPU listed it for the views to draw.
#[derive(Default)]
pub(super) struct Work {
    /// (first pair, first triangle, triangles, view) per run of one view's triangles.
    pub jobs: Vec<[u32; 4]>,
    /// Per view of the table: its tile (x, y, side, 0).
    pub rects: Vec<[u32; 4]>,
    /// Pieces (x, y, side, 0) of the drawn views' tiles, at most STORE_CELL a side.
    pub pieces: Vec<[u32; 4]>,
    /// Pairs of a view and a triangle.
    pub pairs: u32,
}

/// Pieces of at most STORE_CELL² texels covering the tile at (x, y) of side `tile`.
pub(super) fn pieces(x: u32, y: u32, tile: u32, out: &mut Vec<[u32; 4]>) {
    let step = tile.min(STORE_CELL);
    for py in (0..tile).step_by(step as usize) {
        for px in (0..tile).step_by(step as usize) {
            out.push([x + px, y + py, step, 0]);
        }
    }
}

/// The casters merged into one geometry.
pub(super) struct MergedCasters {
    /// Every caster's vertices (w = 1), mesh after mesh.
    pub positions: Vec<[f32; 4]>,
    /// Their triangles, each mesh's in its shadow chunk order, indexing `positions`.
    pub indices: Vec<u32>,
    /// Where each caster's indices start.
    pub index_base: Vec<u32>,
    /// Per merged triangle, its visibility id (with `ids`; the IDS pass's), else empty.
    pub tri_ids: Vec<u32>,
}

/// The meshes `casters` merged, each mesh's triangles as the hardware path draws them.
/// None is alpha-masked: the compute raster draws no masks, and its callers fall back to
/// the raster units for such scenes.
pub(super) fn merge_casters(
    cx: &PrepareCtx,
    pass: &str,
    casters: &[usize],
    ids: bool,
) -> MergedCasters {
    let gpu: &SceneGpu = cx.gpu;
    let mut positions: Vec<[f32; 4]> = Vec::new();
    let mut indices: Vec<u32> = Vec::new();
    let mut index_base = Vec::new();
    // Per merged triangle, its visibility id (the IDS pass's).
    let mut tri_ids: Vec<u32> = Vec::new();
    for &m in casters {
        // The atlas and the reflective shadow maps send scenes with masked casters to the
        // raster units (SceneGpu::masked_material) before they get here.
        debug_assert!(
            !matches!(
                gpu.materials[gpu.meshes[m].material].alpha_mode,
                AlphaMode::Mask(_)
            ),
            "pass '{pass}': an alpha-masked caster reached the compute raster"
        );
        let mesh = &cx.scene.meshes[gpu.meshes[m].scene_mesh];
        let base = positions.len() as u32;
        index_base.push(indices.len() as u32);
        positions.extend(mesh.positions.iter().map(|p| [p.x, p.y, p.z, 1.0]));
        // The triangles as the hardware path draws them (shadow chunk order), so a
        // view's culled ranges index both the same way.
        let (order, _, sources) =
            crate::shadow::chunks::chunk_triangles_with_sources(&mesh.positions, &mesh.indices);
        indices.extend(order.iter().map(|i| i + base));
        if ids {
            let first = gpu.meshes[m].first_triangle;
            tri_ids.extend(sources.iter().map(|t| first + t));
        }
    }
    MergedCasters {
        positions,
        indices,
        index_base,
        tri_ids,
    }
}
