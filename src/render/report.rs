//! What a frame returns: the image, per-pass GPU times, culling reports, statistics.

use crate::graph::{ListLayout, ListStorage};

/// Per culling pass: what its lists held this frame.
#[derive(Clone, Debug)]
pub struct CullingReport {
    /// The culling pass's name in the graph.
    pub pass: String,
    /// The list buffer's layout (tiles, lists per tile, storage) this frame.
    pub layout: ListLayout,
    /// Lists (tiles, halves or clusters) that lost lights: past the capacity (fixed
    /// lists), or past the end of the index array (compact lists).
    pub overflowed_lists: u32,
    /// The longest list wanted (before any cut).
    pub longest_list: u32,
    /// Compact lists: the indices all lists wanted together (those past their scratch
    /// slots saturate at u32::MAX). `None` for fixed lists.
    pub wanted: Option<u64>,
    /// Compact lists: the indices held by lists that lie whole in their scratch slot
    /// (0 without scratch slots); the rest of `wanted` is what the pool had to hold.
    pub scratch_held: u64,
    /// Compact lists whose fill found other lights than their count: 0 unless the two
    /// runs of the culling shader disagree (a driver or shader bug; never silent).
    pub mismatched_lists: u32,
    /// Compact lists whose offset is not the sum of the kept counts before them (the
    /// prefix sum checked on the CPU from the entries read back): 0 unless the scan is
    /// wrong.
    pub misplaced_lists: u32,
    /// Kept count of every list, `lists_per_tile` consecutive entries per tile.
    pub counts: Vec<u32>,
}

impl CullingReport {
    /// Lights listed per tile (all its lists together), row-major.
    pub fn per_tile(&self) -> Vec<u32> {
        self.counts
            .chunks(self.layout.lists_per_tile as usize)
            .map(|c| c.iter().sum())
            .collect()
    }
    /// Light indices the lists hold.
    pub fn listed(&self) -> u64 {
        self.counts.iter().map(|&c| c as u64).sum()
    }
    /// The bytes of the list buffer: header, entries, index pool.
    pub fn bytes(&self) -> u64 {
        self.layout.bytes()
    }
    /// One line on the lists' size and memory, e.g. for `render` and the viewer.
    pub fn summary(&self) -> String {
        let per_tile = self.per_tile();
        let avg = per_tile.iter().map(|&x| x as f64).sum::<f64>() / per_tile.len().max(1) as f64;
        let storage = match self.layout.storage {
            ListStorage::Fixed { capacity } => format!("fixed, capacity {capacity}"),
            ListStorage::Compact { max_indices, .. } => {
                format!("compact, {} of max_indices {max_indices}", self.listed())
            }
        };
        let slots = match self.layout.scratch_per_list() {
            0 => String::new(),
            s => format!("; {} in scratch slots of {s}", self.scratch_held),
        };
        format!(
            "{}: {} tiles x {} lists, lights per tile avg {avg:.1} max {}, longest list wanted {} ({storage}; {:.2} MiB{slots})",
            self.pass,
            self.layout.tiles_x * self.layout.tiles_y,
            self.layout.lists_per_tile,
            per_tile.iter().max().unwrap_or(&0),
            self.longest_list,
            self.bytes() as f64 / (1u64 << 20) as f64,
        )
    }
    /// What went wrong this frame, one line each: lights dropped from lists, or a fill
    /// that disagreed with its count. Empty when every list holds exactly its lights.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if self.overflowed_lists > 0 {
            w.push(match self.layout.storage {
                ListStorage::Compact {
                    max_indices,
                    scratch,
                } => {
                    let wanted = self.wanted.unwrap_or_default();
                    let slots = self.layout.scratch_indices();
                    if slots == 0 {
                        format!(
                            "{}: the lists wanted {wanted} light indices, over max_indices {max_indices}: {} lists lost lights (max_indices: {wanted} fits this frame)",
                            self.pass, self.overflowed_lists
                        )
                    } else {
                        // At 2·L·scratch the slots are the graph's whole `scratch` (not
                        // lowered), and no more lists spill into the pool than now.
                        let pooled = wanted - self.scratch_held;
                        let full_slots = self.layout.lists() as u64 * scratch as u64;
                        let fits = (2 * full_slots).max(full_slots + pooled);
                        format!(
                            "{}: the lists wanted {wanted} light indices, {pooled} of them in lists longer than their scratch slot of {}, over the {} the pool holds (max_indices {max_indices} less {slots} in scratch slots): {} lists lost lights (max_indices: {fits} fits this frame)",
                            self.pass,
                            self.layout.scratch_per_list(),
                            max_indices as u64 - slots,
                            self.overflowed_lists
                        )
                    }
                }
                ListStorage::Fixed { capacity } => format!(
                    "{} lists overflowed their capacity of {capacity} (worst wanted {}): lights were dropped there",
                    self.overflowed_lists, self.longest_list
                ),
            });
        }
        if self.mismatched_lists > 0 {
            w.push(format!(
                "{}: {} compact lists found other lights when filled than when counted: those lists are wrong",
                self.pass, self.mismatched_lists
            ));
        }
        if self.misplaced_lists > 0 {
            w.push(format!(
                "{}: {} compact lists start elsewhere than after the lists before them: the prefix sum is wrong",
                self.pass, self.misplaced_lists
            ));
        }
        w
    }
}

/// Per light linked list pass: what its pool held this frame.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LinkReport {
    /// The light linked list pass's name in the graph.
    pub pass: String,
    /// The buffer's layout (head resolution, pool size) this frame.
    pub layout: crate::graph::kinds::light_linked_list::LinkLayout,
    /// Links the list pixels wanted (kept plus dropped).
    pub links_wanted: u64,
    /// Links past the pool: those lights are missing from their pixels.
    pub links_dropped: u64,
    /// List pixels that lost at least one link.
    pub overflow_pixels: u64,
    /// The longest list a pixel wanted.
    pub longest_list: u32,
}

impl LinkReport {
    /// Links kept in the pool.
    pub fn links(&self) -> u64 {
        self.links_wanted - self.links_dropped
    }
    /// Bytes of the heads and of the whole buffer (header, heads, pool).
    pub fn head_bytes(&self) -> u64 {
        self.layout.head_bytes()
    }
    /// Bytes of the whole buffer: header, heads and pool.
    pub fn bytes(&self) -> u64 {
        self.layout.bytes()
    }
}

/// Per-pixel light statistics over pixels that hold geometry.
#[derive(Clone, Debug, Default)]
pub struct LightStats {
    /// Pixels with geometry that were counted.
    pub pixels: u64,
    /// Lights listed for those pixels (what the shading loop visits), summed.
    pub listed_total: u64,
    /// Lights that actually reach those pixels (range test per pixel), summed.
    pub exact_total: u64,
    /// The most lights listed for one pixel.
    pub max_listed: u32,
    /// The most lights actually reaching one pixel.
    pub max_exact: u32,
}

impl LightStats {
    /// Lights listed per counted pixel, on average.
    pub fn avg_listed(&self) -> f64 {
        self.listed_total as f64 / self.pixels.max(1) as f64
    }
    /// Lights actually reaching a counted pixel, on average.
    pub fn avg_exact(&self) -> f64 {
        self.exact_total as f64 / self.pixels.max(1) as f64
    }
    /// Listed over exact: 1 means no false positives.
    pub fn false_positive_ratio(&self) -> f64 {
        self.listed_total as f64 / self.exact_total.max(1) as f64
    }
    /// Sums the (listed, exact) counts of every pixel that holds either.
    pub(crate) fn from_counts(counts: &[[u32; 2]]) -> Self {
        let mut s = LightStats::default();
        for &[listed, exact] in counts {
            if listed == 0 && exact == 0 {
                continue;
            }
            s.pixels += 1;
            s.listed_total += listed as u64;
            s.exact_total += exact as u64;
            s.max_listed = s.max_listed.max(listed);
            s.max_exact = s.max_exact.max(exact);
        }
        s
    }
}

/// Per ray-cast shadow job pass: what this frame asked of it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShadowReport {
    /// The ShadowRayJobs pass's name in the graph.
    pub pass: String,
    /// Jobs the pixels asked for: one ray each, unless dropped.
    pub jobs_wanted: u64,
    /// Jobs past the buffer's capacity: those lights are lit unshadowed.
    pub jobs_dropped: u64,
    /// Pixels with more than 128 shadow-casting lights (the rest lit unshadowed).
    pub overflow_pixels: u64,
    /// Jobs the job buffer holds (`jobs_per_pixel` times the frame's pixels).
    pub capacity: u64,
    /// Bytes of the job buffer.
    pub job_bytes: u64,
    /// Bytes of the per-pixel hit mask.
    pub mask_bytes: u64,
    /// Pixels of the frame the mask covers.
    pub pixels: u64,
}

impl ShadowReport {
    /// Rays traced this frame.
    pub fn rays(&self) -> u64 {
        self.jobs_wanted.min(self.capacity)
    }
}

/// Per shadow atlas pass: what this frame's allocation gave and refused.
#[derive(Clone, Debug, PartialEq)]
pub struct AtlasReport {
    /// The ShadowAtlas pass's name in the graph.
    pub pass: String,
    /// The atlas's side in texels.
    pub side: u32,
    /// Bytes of the atlas texture and of its view table.
    pub atlas_bytes: u64,
    /// Bytes of the per-view table (matrices and tile rectangles) the shading reads.
    pub table_bytes: u64,
    /// Shadow-casting lights in view, with a tile each, and without room.
    pub shadowed: Vec<crate::shadow::atlas::AtlasLight>,
    /// Shadow-casting lights that found no tile, and why.
    pub dropped: Vec<crate::shadow::atlas::DroppedLight>,
    /// Shadow-casting lights in view the pass's policy gave no tile (left to rays).
    pub left_by_policy: Vec<u32>,
    /// Whether a ShadowRayJobs pass reads the view table: the dropped lights and those
    /// left by the policy are ray-cast; without one, dropped lights are lit unshadowed.
    pub rays_for_the_rest: bool,
    /// Shadow-casting lights whose range misses the camera's frustum.
    pub off_screen: u32,
    /// Depth views rendered into the atlas (six per point light or wide spot light, else one).
    pub views: u32,
    /// How many times every tile was halved so that all requests fit the atlas.
    pub halvings: u32,
    /// Atlas texels covered by tiles.
    pub used_texels: u64,
    /// Draw calls and triangles over all views after culling chunks per view.
    pub draws: u64,
    /// Triangles drawn over all views after culling chunks per view.
    pub triangles: u64,
    /// Allocations made since prepare: one at prepare, then at most one a frame, before
    /// a frame whose camera or lights changed.
    pub allocations: u64,
    /// Views the last recorded frame drew: all of them, or with `cache: true` those
    /// whose tile did not hold them yet (the rest of `views` were kept).
    pub views_rendered: u32,
    /// The compute raster's lists and serial fallbacks (`raster: Compute`).
    pub raster: Option<crate::render::AtlasRasterReport>,
}

impl AtlasReport {
    /// Tile sides and how many lights got each, largest first.
    pub fn tiers(&self) -> Vec<(u32, usize)> {
        let mut tiers: Vec<(u32, usize)> = Vec::new();
        for l in &self.shadowed {
            match tiers.iter_mut().find(|(t, _)| *t == l.tile) {
                Some((_, n)) => *n += 1,
                None => tiers.push((l.tile, 1)),
            }
        }
        tiers.sort_by_key(|t| std::cmp::Reverse(t.0));
        tiers
    }
}

/// Per ShadowCompare pass: the atlas against ray-cast shadows, per (pixel, light) pair.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShadowCompareReport {
    /// The ShadowCompare pass's name in the graph.
    pub pass: String,
    /// Pairs of a pixel and a shadow-casting light that reaches it.
    pub pairs: u64,
    /// Pairs whose filtered visibility is on the other side of one half from the ray's.
    pub disagree_pcf5: u64,
    pub(crate) disagree_2x2: u64,
    /// Pairs partly lit by the 5×5 filter.
    pub penumbra_pcf5: u64,
}

impl ShadowCompareReport {
    /// The fraction of pairs where the 5×5 PCF visibility disagrees with the ray, in 0..=1.
    pub fn error_pcf5(&self) -> f64 {
        self.disagree_pcf5 as f64 / self.pairs.max(1) as f64
    }
    /// The fraction of pairs where the hardware 2×2 comparison filter disagrees with the
    /// ray, in 0..=1.
    pub fn error_2x2(&self) -> f64 {
        self.disagree_2x2 as f64 / self.pairs.max(1) as f64
    }
}

/// Per VplSpawn pass: the virtual lights this frame made, kept and dropped.
#[derive(Clone, Debug, PartialEq)]
pub struct VplReport {
    /// The VplSpawn pass's name in the graph.
    pub pass: String,
    /// Indirect lights with map views, and their views.
    pub lights: u32,
    /// Reflective shadow map views those lights rendered.
    pub views: u32,
    /// Indirect lights that got no views (atlas full, n not dividing the tile...).
    pub dropped_lights: Vec<crate::indirect::rsm_views::DroppedRsmLight>,
    /// n² over every view, and those whose block captured any flux.
    pub candidates: u32,
    pub(crate) with_flux: u32,
    /// Appended after the scene's lights, and dropped (lowest flux first) for want of room.
    pub spawned: u32,
    /// VPLs dropped for want of room (lowest flux first).
    pub dropped: u32,
    /// Candidates merged into a neighbour (`merge`): the merged VPL carries their flux.
    pub merged: u32,
    /// Candidates dropped as negligible: flux (luminance) at most `min_flux` of the total.
    pub negligible: u32,
    /// Their summed luminance, in the maps' flux units (before the lights' VPL
    /// `intensity`).
    pub negligible_flux: f32,
    /// Every candidate's summed luminance (after merging), in the same units.
    pub total_flux: f32,
    /// The pass's `min_flux`.
    pub min_flux: f32,
    /// Whether the kept VPLs were scaled to carry the negligible ones' flux
    /// (`redistribute`).
    pub redistributed: bool,
    /// Room for VPLs (the graph's max_vpls).
    pub room: u32,
    /// The scene's lights, before the VPLs.
    pub scene_lights: u32,
}

/// The report's lines for `render` (a full room or a dropped light is a warning).
impl VplReport {
    /// The share of the flux the negligible VPLs carried (0 when there was none).
    pub fn negligible_fraction(&self) -> f32 {
        if self.total_flux > 0.0 {
            self.negligible_flux / self.total_flux
        } else {
            0.0
        }
    }

    /// One summary line, then a warning line for a full room and for each light that
    /// spawned nothing.
    pub fn lines(&self) -> Vec<String> {
        let v = self;
        let mut lines = vec![format!(
        "{}: {} indirect lights, {} map views, {} VPLs spawned of {} candidates with flux ({} blocks); room {}",
        v.pass, v.lights, v.views, v.spawned, v.with_flux, v.candidates, v.room
    )];
        if v.merged > 0 {
            lines.push(format!(
                "{}: {} VPLs merged into their neighbours (flux kept)",
                v.pass, v.merged
            ));
        }
        if v.min_flux > 0.0 {
            lines.push(format!(
                "{}: {} VPLs under min_flux {} dropped: {:.3}% of the flux{}",
                v.pass,
                v.negligible,
                v.min_flux,
                100.0 * v.negligible_fraction(),
                if v.redistributed {
                    ", redistributed over the rest"
                } else {
                    ", lost"
                }
            ));
        }
        if v.dropped > 0 {
            lines.push(format!(
                "warning: {}: {} VPLs dropped (lowest flux first): max_vpls {} is full",
                v.pass, v.dropped, v.room
            ));
        }
        for crate::indirect::rsm_views::DroppedRsmLight { light, reason } in &v.dropped_lights {
            lines.push(format!(
                "warning: {}: indirect light {light} spawns no VPLs: {reason}",
                v.pass
            ));
        }
        lines
    }
}

/// Per ComputeRaster pass: how its work lists filled this frame. A full list loses
/// nothing (what finds no room is rasterized serially, exactly, by the thread that
/// found it full), but serial work is slow: a non-zero count is a warning.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RasterReport {
    /// The ComputeRaster pass's name in the graph.
    pub pass: String,
    /// Entries used and capacity: fan-triangle records, tiles and blocks.
    pub records: u32,
    pub(crate) records_capacity: u32,
    /// Tile entries used.
    pub tiles: u32,
    pub(crate) tiles_capacity: u32,
    /// Block entries used.
    pub blocks: u32,
    pub(crate) blocks_capacity: u32,
    /// Rasterized serially for want of room: fan triangles without a record, tiles
    /// without a tile entry, blocks without a block entry.
    pub serial_triangles: u32,
    /// Tiles rasterized serially because the tile list was full.
    pub serial_tiles: u32,
    /// Blocks rasterized serially because the block list was full.
    pub serial_blocks: u32,
    /// Fan triangles of at most 16 pixels (their box) covered by their setup thread
    /// itself, without a record or a list entry (all runs').
    pub small_triangles: u32,
    /// Fan triangles within 2×2 blocks whose blocks setup listed itself, without a tile
    /// entry or bin (all runs').
    pub block_triangles: u32,
}

impl RasterReport {
    /// Fan triangles, tiles and blocks rasterized serially together.
    pub fn serial(&self) -> u64 {
        self.serial_triangles as u64 + self.serial_tiles as u64 + self.serial_blocks as u64
    }
    /// The report's lines for `render` (serial work is a warning).
    pub fn lines(&self) -> Vec<String> {
        let r = self;
        let mut lines = vec![format!(
            "{}: {} of {} triangle records, {} of {} tiles, {} of {} blocks; {} small fan triangles drawn in setup, {} listed by block",
            r.pass,
            r.records,
            r.records_capacity,
            r.tiles,
            r.tiles_capacity,
            r.blocks,
            r.blocks_capacity,
            r.small_triangles,
            r.block_triangles
        )];
        if r.serial() > 0 {
            lines.push(format!(
                "warning: {}: lists full: {} fan triangles, {} tiles and {} blocks rasterized serially (exact, slow)",
                r.pass, r.serial_triangles, r.serial_tiles, r.serial_blocks
            ));
        }
        lines
    }
}

/// What a pass counted on the GPU (or decided on the CPU for this frame).
#[derive(Clone, Debug)]
pub enum PassReport {
    /// A pass that ran another way on this device.
    Fallback(FallbackReport),
    /// Light lists of a LightCulling pass.
    Culling(CullingReport),
    /// Jobs of a ShadowRayJobs pass.
    Shadow(ShadowReport),
    /// The allocation of a ShadowAtlas pass.
    Atlas(AtlasReport),
    /// The disagreement counted by a ShadowCompare pass.
    ShadowCompare(ShadowCompareReport),
    /// The pool of a LightLinkedList pass.
    Links(LinkReport),
    /// The virtual lights of a VplSpawn pass.
    Vpl(VplReport),
    /// The work lists of a ComputeRaster pass.
    Raster(RasterReport),
}

/// What rendering one frame returns: the read-back image and what its passes counted on the
/// GPU.
pub struct FrameResult {
    /// The image's width in pixels.
    pub width: u32,
    /// The image's height in pixels.
    pub height: u32,
    /// Linear HDR RGBA, row-major.
    pub image: Vec<[f32; 4]>,
    /// GPU milliseconds per pass, when the adapter has timestamp queries.
    pub pass_ms: Option<Vec<(String, f64)>>,
    /// Passes that ran another way on this device (see [`FallbackReport`]).
    pub fallbacks: Vec<FallbackReport>,
    /// One report per LightCulling pass, in graph order.
    pub culling: Vec<CullingReport>,
    /// One report per LightLinkedList pass.
    pub links: Vec<LinkReport>,
    /// One report per ShadowRayJobs pass.
    pub shadows: Vec<ShadowReport>,
    /// One report per ShadowAtlas pass.
    pub atlases: Vec<AtlasReport>,
    /// One report per ShadowCompare pass.
    pub shadow_compare: Vec<ShadowCompareReport>,
    /// One report per VplSpawn pass.
    pub vpls: Vec<VplReport>,
    /// One report per ComputeRaster pass.
    pub rasters: Vec<RasterReport>,
    /// Listed against exact lights per pixel, when the frame was rendered with light
    /// statistics.
    pub light_stats: Option<LightStats>,
}

/// A pass that runs another way than its kind's own on this device: the compute
/// rasterizer drawn with the hardware rasterizer where the adapter lacks its 64-bit
/// atomics. Reported with every frame, so a run on such a device never passes silently
/// for the compute path (timings included).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FallbackReport {
    /// The pass's name in the graph.
    pub pass: String,
    /// The adapter, as `GpuContext::adapter_name` gives it.
    pub adapter: String,
    /// What the pass needs that the device lacks.
    pub missing: wgpu::Features,
    /// Of `missing`, what the adapter offers but the context was asked to leave off
    /// (`ContextOptions::disabled_features`).
    pub disabled: wgpu::Features,
    /// How the pass ran instead.
    pub instead: &'static str,
}

impl FallbackReport {
    /// Pass `pass` ran `instead` on the device of `ctx`, which lacks `missing`.
    pub(crate) fn new(
        pass: &str,
        ctx: &crate::gpu::GpuContext,
        missing: wgpu::Features,
        instead: &'static str,
    ) -> Self {
        FallbackReport {
            pass: pass.to_string(),
            adapter: ctx.adapter_name(),
            missing,
            disabled: missing & ctx.disabled_features,
            instead,
        }
    }

    /// One line for `render` and the viewer, e.g. `compute_raster: adapter X lacks
    /// SHADER_INT64_ATOMIC_MIN_MAX; drawn with the hardware rasterizer`.
    pub fn line(&self) -> String {
        let disabled = if self.disabled.is_empty() {
            String::new()
        } else if self.disabled == self.missing {
            " (offered by the adapter, disabled on request)".to_string()
        } else {
            format!(" ({} disabled on request)", self.disabled)
        };
        format!(
            "{}: adapter {} lacks {}{disabled}; {}",
            self.pass, self.adapter, self.missing, self.instead
        )
    }
}

#[cfg(test)]
mod tests {
    use super::FallbackReport;
    use wgpu::Features as F;

    #[test]
    fn a_fallback_line_names_the_pass_adapter_and_missing_features() {
        let mut f = FallbackReport {
            pass: "cr".into(),
            adapter: "Some GPU (Vulkan)".into(),
            missing: F::SHADER_INT64 | F::SHADER_INT64_ATOMIC_MIN_MAX,
            disabled: F::empty(),
            instead: "drawn with the hardware rasterizer",
        };
        assert_eq!(
            f.line(),
            "cr: adapter Some GPU (Vulkan) lacks SHADER_INT64 | SHADER_INT64_ATOMIC_MIN_MAX; drawn with the hardware rasterizer"
        );
        f.disabled = F::SHADER_INT64_ATOMIC_MIN_MAX;
        assert!(
            f.line()
                .contains("MIN_MAX (SHADER_INT64_ATOMIC_MIN_MAX disabled on request);"),
            "{}",
            f.line()
        );
        f.disabled = f.missing;
        assert!(
            f.line()
                .contains("MIN_MAX (offered by the adapter, disabled on request);"),
            "{}",
            f.line()
        );
    }
}
