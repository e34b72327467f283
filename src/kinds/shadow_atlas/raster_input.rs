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
    /// (first pair of its run, first triangle, triangles, view) per run of one view's
    /// consecutive triangles, raster run after raster run.
    pub jobs: Vec<[u32; 4]>,
    /// Per raster run (the opaque casters, then each alpha-masked material's): its first
    /// job, its jobs and its pairs.
    pub runs: Vec<[u32; 3]>,
    /// Per view of the table: its tile (x, y, side, 0).
    pub rects: Vec<[u32; 4]>,
    /// Pieces (x, y, side, 0) of the drawn views' tiles, at most STORE_CELL a side.
    pub pieces: Vec<[u32; 4]>,
}

impl Work {
    /// Pairs of a view and a triangle, over every run.
    pub fn pairs(&self) -> u32 {
        self.runs.iter().map(|r| r[2]).sum()
    }
}

/// A frame's jobs as they are listed, each into its caster's raster run.
pub(super) struct JobLists<'a> {
    /// Per caster draw, its raster run.
    run_of_draw: &'a [usize],
    /// Per caster draw, its first index in the merged index buffer.
    index_base: &'a [u32],
    /// Per run, its jobs (first pairs counted within the run) and pairs.
    runs: Vec<(Vec<[u32; 4]>, u32)>,
}

impl<'a> JobLists<'a> {
    pub fn new(run_of_draw: &'a [usize], index_base: &'a [u32], runs: usize) -> Self {
        JobLists {
            run_of_draw,
            index_base,
            runs: vec![(Vec::new(), 0); runs],
        }
    }

    /// View `view` draws `count` indices of caster `draw` from its index `first`.
    pub fn push(&mut self, view: u32, draw: usize, first: u32, count: u32) {
        let (jobs, pairs) = &mut self.runs[self.run_of_draw[draw]];
        let (first, count) = ((self.index_base[draw] + first) / 3, count / 3);
        // Consecutive triangles of one view make one job.
        match jobs.last_mut() {
            Some(job) if job[3] == view && job[1] + job[2] == first => job[2] += count,
            _ => jobs.push([*pairs, first, count, view]),
        }
        *pairs += count;
    }

    /// The work: the runs' jobs one after another, with `rects` and `pieces`.
    pub fn finish(self, rects: Vec<[u32; 4]>, pieces: Vec<[u32; 4]>) -> Work {
        let mut work = Work {
            rects,
            pieces,
            ..Work::default()
        };
        for (jobs, pairs) in self.runs {
            work.runs
                .push([work.jobs.len() as u32, jobs.len() as u32, pairs]);
            work.jobs.extend(jobs);
        }
        work
    }
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
    /// Per merged triangle, its visibility id (the IDS pass keeps it, the alpha test
    /// rebuilds it), where either runs; else empty.
    pub tri_ids: Vec<u32>,
    /// Per caster, its raster run: 0 draws solid, k > 0 alpha-tests `masked[k - 1]`.
    pub run_of_draw: Vec<usize>,
    /// The alpha-masked materials among the casters, in the order they first appear.
    pub masked: Vec<usize>,
}

/// The meshes `casters` merged, each mesh's triangles as the hardware path draws them,
/// with visibility ids where `ids` asks for them or a caster is alpha-masked.
pub(super) fn merge_casters(cx: &PrepareCtx, casters: &[usize], ids: bool) -> MergedCasters {
    let gpu: &SceneGpu = cx.gpu;
    let mut merged = MergedCasters {
        positions: Vec::new(),
        indices: Vec::new(),
        index_base: Vec::new(),
        tri_ids: Vec::new(),
        run_of_draw: Vec::new(),
        masked: Vec::new(),
    };
    for &m in casters {
        let material = gpu.meshes[m].material;
        let run = match gpu.materials[material].alpha_mode {
            AlphaMode::Mask(_) => match merged.masked.iter().position(|&k| k == material) {
                Some(k) => k + 1,
                None => {
                    merged.masked.push(material);
                    merged.masked.len()
                }
            },
            _ => 0,
        };
        merged.run_of_draw.push(run);
    }
    let with_ids = ids || !merged.masked.is_empty();
    for &m in casters {
        let mesh = &cx.scene.meshes[gpu.meshes[m].scene_mesh];
        let base = merged.positions.len() as u32;
        merged.index_base.push(merged.indices.len() as u32);
        merged
            .positions
            .extend(mesh.positions.iter().map(|p| [p.x, p.y, p.z, 1.0]));
        // The triangles as the hardware path draws them (shadow chunk order), so a
        // view's culled ranges index both the same way.
        let (order, _, sources) =
            crate::shadow::chunks::chunk_triangles_with_sources(&mesh.positions, &mesh.indices);
        merged.indices.extend(order.iter().map(|i| i + base));
        if with_ids {
            let first = gpu.meshes[m].first_triangle;
            merged.tri_ids.extend(sources.iter().map(|t| first + t));
        }
    }
    merged
}
