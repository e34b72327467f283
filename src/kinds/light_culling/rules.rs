//! `LightCulling`: per-tile light lists from the prepass depth (Frustum, HalfZ,
//! DepthMask, Clustered), with an optional coarse stage. Runs `shaders/cull/light_culling.wgsl`.
//! A multisampled depth is read sample by sample. The depth may also be a single-sample
//! R32Float texture (ComputeRaster's compute resolve), read as `texture_2d<f32>`
//! (`FLOAT_DEPTH`). With a `transparent_depth` (a TransparentDepth pass's) the lists are
//! for transparent surfaces: a tile spans, over its pixels that hold one, from the
//! nearest transparent depth to the opaque depth behind it (AMD's TiledLighting11
//! sample); either depth may be a depth format or single-sample R32Float there
//! (`FLOAT_TRANSPARENT` for the transparent one).
//!
//! Two list layouts (`lists:`), read alike through `shaders/common/light_lists.wgsl`:
//! `Fixed` gives every list room for `capacity` lights (a longer list is cut, counted
//! and reported); `Compact(max_indices, scratch)` counts every list, writing its first
//! `scratch` lights to a slot of its own as it counts, prefix-sums the counts of the
//! lists longer than that and fills only those into a pool after the slots, so each
//! list holds exactly its lights, and only the total is bounded (past `max_indices` the
//! last long lists are cut, counted and reported).

use super::{slot, Access, BufferLayout, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::CullVariant;
use crate::graph::plan::FrameSize;
use crate::graph::roles::PassRoles;
use serde::{Deserialize, Serialize};

/// `LightCulling(tile: 16, variant: Frustum, capacity: 256, coarse: 4)` or
/// `LightCulling(tile: 16, variant: Frustum, lists: Compact(max_indices: 16777216))`
/// (`Compact(max_indices: N, scratch: S)`; `scratch` 256 unless given).
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(deny_unknown_fields)]
pub struct LightCulling {
    /// Pixels per tile side: 8, 16 or 32.
    pub tile: u32,
    /// How a tile is bounded in depth (`Frustum` by default).
    #[serde(default)]
    pub variant: CullVariant,
    /// How the lists are stored: `Fixed` (the default) or `Compact(max_indices: N)`
    /// (optionally `scratch: S`).
    #[serde(default)]
    pub lists: ListMode,
    /// `Fixed` lists: most lights a tile (or a half, or a cluster) can list (default
    /// 256). Written as a plain number; `None` where the graph gives none.
    #[serde(
        default,
        deserialize_with = "super::plain_some",
        serialize_with = "super::plain_u32",
        skip_serializing_if = "Option::is_none"
    )]
    pub capacity: Option<u32>,
    /// Tiles per side of a coarse tile culled first: fine tiles then test only
    /// their coarse tile's lights instead of every light. 0 or 1 turns it off.
    #[serde(default = "default_coarse")]
    pub coarse: u32,
    /// Coarse tiles per side of a wide tile culled before them against its side planes
    /// alone (no depth): coarse tiles then test only their wide tile's lights. 0 or 1
    /// turns it off (the default); it needs the coarse stage.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub wide: u32,
}

fn is_zero(v: &u32) -> bool {
    *v == 0
}

/// How a culling pass stores its lists.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(deny_unknown_fields)]
pub enum ListMode {
    /// Room for `capacity` lights in every list: one pass, lists cut at the capacity.
    #[default]
    Fixed,
    /// Count → prefix sum → fill: every list holds exactly its lights, in one flat array
    /// of at most `max_indices` light indices (4 bytes each) for all lists together.
    /// The count writes each list's first `scratch` lights to a slot of its own at the
    /// array's start; a list that fits stays there, and only longer lists are tested
    /// again to be filled into the pool after the slots. The slots take at most half the
    /// array (see `ListLayout::scratch_per_list`); `scratch: 0` fills every list.
    Compact {
        /// Light indices all lists may hold together (4 bytes each).
        max_indices: u32,
        #[serde(
            default = "default_scratch",
            skip_serializing_if = "is_default_scratch"
        )]
        /// Light indices each list's own slot holds before it spills into the pool (256 by
        /// default).
        scratch: u32,
    },
}

pub(crate) const DEFAULT_CAPACITY: u32 = 256;
/// Scratch slot of compact lists, in light indices: at 1920×1080 with 16-pixel tiles
/// fixed lists of 256 held every tile of harada's 3,072 lights, so none is filled twice
/// there; 8 MiB of the shipped 64 MiB bound.
pub(crate) const DEFAULT_SCRATCH: u32 = 256;
/// Largest scratch slot: as fixed lists' capacity.
pub(crate) const MAX_SCRATCH: u32 = 4096;
/// Largest `max_indices`: the index array's words stay addressable by u32 with room
/// for the header and entries.
pub(crate) const MAX_INDICES_LIMIT: u32 = 1 << 30;

fn default_coarse() -> u32 {
    4
}

fn default_scratch() -> u32 {
    DEFAULT_SCRATCH
}

fn is_default_scratch(s: &u32) -> bool {
    *s == DEFAULT_SCRATCH
}

impl LightCulling {
    /// Where the lists live: the graph's `lists` and `capacity` together.
    pub fn storage(&self) -> ListStorage {
        match self.lists {
            ListMode::Fixed => ListStorage::Fixed {
                capacity: self.capacity.unwrap_or(DEFAULT_CAPACITY),
            },
            ListMode::Compact {
                max_indices,
                scratch,
            } => ListStorage::Compact {
                max_indices,
                scratch,
            },
        }
    }
    pub(crate) fn list_layout(&self, width: u32, height: u32) -> ListLayout {
        ListLayout::new(self.tile, self.variant, self.storage(), width, height)
    }
}

/// Layout of a culling pass's light-list buffer, shared with `shaders/cull/*.wgsl` and
/// every reader through `shaders/common/light_lists.wgsl`: a header of 4 u32, then
/// (offset, count, z_min, z_max) per list, then the index pool. A list's lights are
/// `pool[offset .. offset + count]`, in ascending light order, in both storages.
/// `Compact` pools start with a scratch slot of [`Self::scratch_per_list`] indices per
/// list, in list order: a list of 1 to that many lights lies in its own slot, every other
/// list after all slots, back to back in list order.
///
/// Header, `Fixed`: pool cursor, lists cut at the capacity, longest list wanted, unused.
/// Header, `Compact`: indices the lists past their slot wanted (all lists without
/// scratch; saturating at u32::MAX), lists cut at the bound, longest list wanted, lists
/// whose fill found other lights than their count (0 unless the two dispatches disagree;
/// counted so it is never silent).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ListLayout {
    /// Pixels per tile side.
    pub tile: u32,
    /// How tiles were bounded in depth.
    pub variant: CullVariant,
    /// Tiles across the frame.
    pub tiles_x: u32,
    /// Tiles down the frame.
    pub tiles_y: u32,
    /// Lists per tile: 1, 2 for HalfZ, or the slice count for Clustered.
    pub lists_per_tile: u32,
    /// Fixed or compact storage, as the graph asks.
    pub storage: ListStorage,
}

/// How a culling pass stores its lists: room for `capacity` lights in every list, or
/// one flat array of at most `max_indices` for all lists together, filled by count →
/// prefix sum → fill, with slots of `scratch` indices per list (as the graph asks; see
/// [`ListLayout::scratch_per_list`]) for the lists that need no fill.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ListStorage {
    /// Room for `capacity` lights in every list.
    Fixed {
        /// Most lights a list holds.
        capacity: u32,
    },
    /// One flat array for all lists.
    Compact {
        /// Light indices all lists may hold together.
        max_indices: u32,
        /// Each list's own slot, in light indices, as the graph asks.
        scratch: u32,
    },
}

impl ListLayout {
    pub(crate) const HEADER_WORDS: u32 = 4;
    /// Words per list entry: offset, count, and the view-depth range it covers (f32 bits).
    pub(crate) const ENTRY_WORDS: u32 = 4;
    /// Lists per workgroup of the compact layout's scan (256 invocations × 4 lists).
    pub(crate) const SCAN_BLOCK: u32 = 1024;
    /// The layout of `tile`-pixel tiles over a `width`×`height` frame.
    pub fn new(
        tile: u32,
        variant: CullVariant,
        storage: ListStorage,
        width: u32,
        height: u32,
    ) -> Self {
        Self {
            tile,
            variant,
            tiles_x: width.div_ceil(tile),
            tiles_y: height.div_ceil(tile),
            lists_per_tile: match variant {
                CullVariant::HalfZ => 2,
                CullVariant::Clustered { slices } => slices,
                CullVariant::Frustum | CullVariant::DepthMask => 1,
            },
            storage,
        }
    }
    /// Lists over the whole frame: tiles times lists per tile.
    pub fn lists(&self) -> u32 {
        self.tiles_x * self.tiles_y * self.lists_per_tile
    }
    /// The word offset where the index pool starts (after the header and list entries).
    pub fn pool_offset_words(&self) -> u32 {
        Self::HEADER_WORDS + Self::ENTRY_WORDS * self.lists()
    }
    /// Light indices the pool holds: every list at full capacity (so only a list longer
    /// than the capacity can overflow), or the compact bound for all lists together.
    pub fn pool_indices(&self) -> u64 {
        match self.storage {
            ListStorage::Fixed { capacity } => self.lists() as u64 * capacity as u64,
            ListStorage::Compact { max_indices, .. } => max_indices as u64,
        }
    }
    /// Compact lists: each list's scratch slot, in light indices. The graph's `scratch`,
    /// lowered where the slots would take more than half of `max_indices` (to
    /// ⌊max_indices / 2L⌋ for L lists), so the pool keeps at least half; 0 for fixed lists.
    pub fn scratch_per_list(&self) -> u32 {
        match self.storage {
            ListStorage::Fixed { .. } => 0,
            ListStorage::Compact {
                max_indices,
                scratch,
            } => {
                let half_per_list = max_indices as u64 / (2 * self.lists().max(1) as u64);
                scratch.min(half_per_list as u32)
            }
        }
    }
    /// Compact lists: the indices all scratch slots take at the start of the pool.
    pub(crate) fn scratch_indices(&self) -> u64 {
        self.scratch_per_list() as u64 * self.lists() as u64
    }
    /// Scan blocks of the compact layout (0 for fixed lists).
    pub fn scan_blocks(&self) -> u32 {
        match self.storage {
            ListStorage::Fixed { .. } => 0,
            ListStorage::Compact { .. } => self.lists().div_ceil(Self::SCAN_BLOCK),
        }
    }
    /// The whole buffer: header, entries and pool. Overflow of any list is counted,
    /// never silent.
    pub fn bytes(&self) -> u64 {
        4 * (self.pool_offset_words() as u64 + self.pool_indices())
    }
}

pub(crate) const SLOTS: &[SlotSpec] = &[
    // A depth format, or R32Float depths (a compute-only frame's ComputeRaster).
    SlotSpec::new(
        slot::DEPTH,
        SlotType::DepthValues,
        Access::Read,
        Usage::Sampled,
    ),
    super::LIGHT_GEOMETRY_READ,
    SlotSpec::new(
        slot::LIGHT_LISTS,
        SlotType::Buffer,
        Access::Write,
        Usage::Bound,
    ),
    SlotSpec::new(
        slot::TRANSPARENT_DEPTH,
        SlotType::DepthValues,
        Access::Read,
        Usage::Sampled,
    )
    .optional(),
    // The farthest transparent depth: a transparent tile's range ends there where that
    // is nearer than the opaque surface (ComputeRaster writes it beside the nearest).
    SlotSpec::new(
        slot::TRANSPARENT_FAR,
        SlotType::DepthValues,
        Access::Read,
        Usage::Sampled,
    )
    .optional(),
];

pub(crate) fn check(p: &LightCulling, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    super::check_float_depth_samples(ctx, errors);
    if let Some(t) = ctx.slot(slot::TRANSPARENT_DEPTH) {
        if ctx.is_float_depth(t) && ctx.samples(t) > 1 {
            errors.push(ctx.mismatch(
                t,
                format!("an R32Float transparent depth is single-sample (compute stores one depth a pixel); it has {} samples: use a multisampled Depth32Float for MSAA", ctx.samples(t)),
            ));
        }
    }
    if let Some(far) = ctx.slot(slot::TRANSPARENT_FAR) {
        let single_float =
            |r: Option<&str>| r.is_some_and(|r| ctx.is_float_depth(r) && ctx.samples(r) == 1);
        if !single_float(Some(far)) || !single_float(ctx.slot(slot::TRANSPARENT_DEPTH)) {
            errors.push(ctx.mismatch(
                far,
                "the farthest transparent depth bounds the nearest one's range: a single-sample R32Float texture beside a single-sample R32Float transparent depth",
            ));
        }
    }
    if let (Some(depth), Some(t)) = (ctx.slot(slot::DEPTH), ctx.slot(slot::TRANSPARENT_DEPTH)) {
        let (ds, ts) = (ctx.samples(depth), ctx.samples(t));
        if ds != ts {
            errors.push(ctx.mismatch(
                t,
                format!("transparent depth has {ts} sample(s) but depth '{depth}' has {ds}: culling compares them sample by sample"),
            ));
        }
    }
    if !matches!(p.tile, 8 | 16 | 32) {
        errors.push(ctx.bad(format!(
            "tile size {} is not supported (8, 16 or 32 pixels a side)",
            p.tile
        )));
    }
    match (p.lists, p.capacity) {
        (ListMode::Fixed, Some(c)) if c == 0 || c > 4096 => {
            errors.push(ctx.bad(format!("capacity {c} must be in 1..=4096")));
        }
        (ListMode::Compact { .. }, Some(c)) => errors.push(ctx.bad(format!(
            "capacity {c} is for lists: Fixed; Compact lists have no per-list capacity (their total is max_indices)"
        ))),
        (ListMode::Compact { max_indices, .. }, None)
            if max_indices == 0 || max_indices > MAX_INDICES_LIMIT =>
        {
            errors.push(ctx.bad(format!(
                "max_indices {max_indices} must be in 1..={MAX_INDICES_LIMIT}"
            )));
        }
        _ => {}
    }
    if let ListMode::Compact { scratch, .. } = p.lists {
        if scratch > MAX_SCRATCH {
            errors.push(ctx.bad(format!(
                "scratch {scratch} must be in 0..={MAX_SCRATCH} light indices a list (0: no scratch slots)"
            )));
        }
    }
    if p.coarse > 16 {
        errors.push(ctx.bad(format!(
            "coarse {} must be in 0..=16 tiles per side (0 or 1: no coarse stage)",
            p.coarse
        )));
    }
    if p.wide > 16 {
        errors.push(ctx.bad(format!(
            "wide {} must be in 0..=16 coarse tiles per side (0 or 1: no wide stage)",
            p.wide
        )));
    } else if p.wide > 1 && p.coarse <= 1 {
        errors.push(ctx.bad(format!(
            "wide {} groups coarse tiles, and coarse {} turns the coarse stage off",
            p.wide, p.coarse
        )));
    }
    if let CullVariant::Clustered { slices } = p.variant {
        if slices == 0 || slices > 64 {
            errors.push(ctx.bad(format!("clustered slices {slices} must be in 1..=64")));
        }
    }
}

impl KindRules for LightCulling {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(self, ctx, errors)
    }
    fn buffer_layout(&self, slot: &str, frame: FrameSize) -> Option<BufferLayout> {
        (slot == slot::LIGHT_LISTS)
            .then(|| BufferLayout::LightLists(self.list_layout(frame.width, frame.height)))
    }
    fn writes_transparency(&self, roles: &PassRoles) -> bool {
        roles.slot(slot::TRANSPARENT_DEPTH).is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::{ListLayout, ListStorage};
    use crate::graph::kinds::test_support::{errors, PREPASS};
    use crate::graph::model::CullVariant;

    #[test]
    fn checks_parameters() {
        let e = errors(
            &format!(
                r#"{PREPASS} Pass(name: "c", kind: LightCulling(tile: 12, capacity: 0, coarse: 17, variant: Clustered(slices: 65)), reads: ["depth", "lg"], writes: ["lists"])"#
            ),
            "hdr",
        );
        for want in [
            "tile size 12",
            "capacity 0",
            "coarse 17",
            "clustered slices 65",
        ] {
            assert!(e.contains(want), "{want}: {e}");
        }
        let e = cull("LightCulling(tile: 16, wide: 17)");
        assert!(e.contains("wide 17 must be in 0..=16"), "{e}");
        let e = cull("LightCulling(tile: 16, wide: 4, coarse: 0)");
        assert!(
            e.contains("wide 4 groups coarse tiles, and coarse 0 turns the coarse stage off"),
            "{e}"
        );
    }

    /// The errors of a depth prepass and a culling pass of `kind`.
    fn cull(kind: &str) -> String {
        errors(
            &format!(
                r#"{PREPASS} Pass(name: "c", kind: {kind}, reads: ["depth", "lg"], writes: ["lists"])"#
            ),
            "hdr",
        )
    }

    #[test]
    fn compact_lists_take_a_bound_and_no_capacity() {
        let e = cull("LightCulling(tile: 16, lists: Compact(max_indices: 64), capacity: 256)");
        assert!(e.contains("capacity 256 is for lists: Fixed"), "{e}");
        let e = cull("LightCulling(tile: 16, lists: Compact(max_indices: 0))");
        assert!(e.contains("max_indices 0 must be in 1..=1073741824"), "{e}");
        let e = cull("LightCulling(tile: 16, lists: Compact(max_indices: 1073741825))");
        assert!(e.contains("max_indices 1073741825"), "{e}");
        let e = cull("LightCulling(tile: 16, lists: Compact(max_indices: 64, scratch: 4097))");
        assert!(e.contains("scratch 4097 must be in 0..=4096"), "{e}");
        crate::graph::kinds::test_support::validate(
            &format!(
                r#"{PREPASS} Pass(name: "c", kind: LightCulling(tile: 16, lists: Compact(max_indices: 1024)), reads: ["depth", "lg"], writes: ["lists"])"#
            ),
            "hdr",
        )
        .expect("compact lists with a bound and no capacity are valid");
    }

    #[test]
    fn storage_follows_lists_and_capacity() {
        use super::{LightCulling, ListMode};
        let text = |t: &str| ron::from_str::<LightCulling>(t).unwrap();
        let fixed = text("(tile: 16, capacity: 64)");
        assert_eq!(fixed.storage(), ListStorage::Fixed { capacity: 64 });
        let default = text("(tile: 16)");
        assert_eq!(default.storage(), ListStorage::Fixed { capacity: 256 });
        let compact = text("(tile: 8, lists: Compact(max_indices: 4096))");
        assert_eq!(
            compact.lists,
            ListMode::Compact {
                max_indices: 4096,
                scratch: 256
            }
        );
        assert_eq!(
            compact.storage(),
            ListStorage::Compact {
                max_indices: 4096,
                scratch: 256
            }
        );
        let no_scratch = text("(tile: 8, lists: Compact(max_indices: 4096, scratch: 0))");
        assert_eq!(
            no_scratch.storage(),
            ListStorage::Compact {
                max_indices: 4096,
                scratch: 0
            }
        );
        // The default is left out when written back, so shipped graphs read as before.
        let written = ron::to_string(&compact).unwrap();
        assert!(written.contains("Compact(max_indices:4096)"), "{written}");
        let written = ron::to_string(&no_scratch).unwrap();
        assert!(written.contains("scratch:0"), "{written}");
    }

    #[test]
    fn lists_must_be_written_and_depths_alike() {
        let e = errors(
            &format!(
                r#"{PREPASS} Pass(name: "c", kind: LightCulling(tile: 16), reads: ["depth", "lg", "lists"])"#
            ),
            "hdr",
        );
        assert!(
            e.contains("LightCulling needs a buffer in writes (slot 'light_lists')"),
            "{e}"
        );
        crate::graph::kinds::test_support::validate(
            r#"Pass(name: "pre", kind: DepthPrepass, writes: ["depth4"]), Pass(name: "c", kind: LightCulling(tile: 16), reads: ["depth4", "lg"], writes: ["lists"]), Pass(name: "s", kind: ForwardShading(lights: Culled), reads: ["depth4", "lg", "lp", "lists"], writes: ["hdr4"])"#,
            "hdr",
        )
        .map_err(|e| e.to_string())
        .or_else(|e| {
            // The graph's output is never written; the MSAA culling itself must pass.
            assert!(!e.contains("pass 'c'"), "{e}");
            Ok::<(), String>(())
        })
        .unwrap();
        let e = errors(
            r#"Pass(name: "pre", kind: DepthPrepass, writes: ["depth4"]), Pass(name: "tp", kind: TransparentDepth, writes: ["depth"]), Pass(name: "c", kind: LightCulling(tile: 16), reads: ["depth4", "transparent_depth=depth", "lg"], writes: ["lists"])"#,
            "hdr",
        );
        assert!(
            e.contains("transparent depth has 1 sample(s) but depth 'depth4' has 4"),
            "{e}"
        );
    }

    #[test]
    fn transparent_lists_read_an_r32float_opaque_depth() {
        // A compute resolve's R32Float depth beside a TransparentDepth pass's depth.
        const FLOAT_FRAME: &str = r#"Pass(name: "cr", kind: ComputeRaster, reads: ["vertices", "triangles", "material_triangles"], writes: ["fdepth", "visibility"]),
            Pass(name: "tp", kind: TransparentDepth, reads: ["geometry"], writes: ["depth"]),
            Pass(name: "c", kind: LightCulling(tile: 16), reads: ["fdepth", "transparent_depth=depth", "lg"], writes: ["lists"]),
            Pass(name: "s", kind: VisibilityShading(lights: Culled), reads: ["visibility", "vertices", "triangles", "material_triangles", "lg", "lp", "lists"], writes: ["hdr"])"#;
        crate::graph::kinds::test_support::validate(FLOAT_FRAME, "hdr")
            .expect("an R32Float opaque depth with a Depth32Float transparent depth is valid");
        // A compute-rasterized transparent depth: R32Float too.
        let float_transparent = FLOAT_FRAME
            .replace(r#"writes: ["depth"]"#, r#"writes: ["tdepth_f"]"#)
            .replace(
                r#""transparent_depth=depth""#,
                r#""transparent_depth=tdepth_f""#,
            );
        crate::graph::kinds::test_support::validate(&float_transparent, "hdr")
            .expect("R32Float opaque and transparent depths are valid");
        // But single-sample, as the opaque one.
        let e = errors(
            &FLOAT_FRAME.replace(
                r#""transparent_depth=depth""#,
                r#""transparent_depth=fdepth4""#,
            ),
            "hdr",
        );
        assert!(e.contains("pass 'c', resource 'fdepth4'"), "{e}");
    }

    #[test]
    fn list_layout_counts_partial_tiles() {
        let fixed = |capacity| ListStorage::Fixed { capacity };
        let l = ListLayout::new(16, CullVariant::Frustum, fixed(256), 333, 197);
        assert_eq!((l.tiles_x, l.tiles_y), (21, 13));
        assert_eq!(l.lists(), 273);
        let h = ListLayout::new(8, CullVariant::HalfZ, fixed(64), 16, 16);
        assert_eq!(h.lists(), 8);
        assert_eq!(h.bytes(), 4 * (4 + 32 + 8 * 64));
        assert_eq!(h.scan_blocks(), 0);
    }

    #[test]
    fn compact_lists_are_bounded_by_the_graph_alone() {
        let compact = ListStorage::Compact {
            max_indices: 5000,
            scratch: 256,
        };
        let c = ListLayout::new(8, CullVariant::Clustered { slices: 16 }, compact, 333, 197);
        assert_eq!(c.lists(), 42 * 25 * 16);
        // Header, one entry a list, then exactly the bound: scratch slots come out of it.
        assert_eq!(c.bytes(), 4 * (4 + 4 * 16_800 + 5000));
        assert_eq!(c.scan_blocks(), 17);
        // 16,800 slots of 256 would take 860 times the bound: none fit in half of it.
        assert_eq!(c.scratch_per_list(), 0);
    }

    #[test]
    fn scratch_slots_take_at_most_half_the_bound() {
        let compact = |max_indices, scratch| ListStorage::Compact {
            max_indices,
            scratch,
        };
        let frustum = |storage| ListLayout::new(16, CullVariant::Frustum, storage, 1920, 1080);
        // The shipped bound at 1920×1080: 8,160 slots of 256 (8 MiB of 64).
        let shipped = frustum(compact(16_777_216, 256));
        assert_eq!(shipped.scratch_per_list(), 256);
        assert_eq!(shipped.scratch_indices(), 8_160 * 256);
        assert_eq!(shipped.bytes(), 4 * (4 + 4 * 8_160 + 16_777_216));
        // 2 · 8,160 · 100 = 1,632,000 indices: 100 fits, 101 does not.
        assert_eq!(frustum(compact(1_632_000, 256)).scratch_per_list(), 100);
        assert_eq!(frustum(compact(1_631_999, 256)).scratch_per_list(), 99);
        assert_eq!(frustum(compact(16_777_216, 0)).scratch_per_list(), 0);
        let clustered = ListLayout::new(
            16,
            CullVariant::Clustered { slices: 16 },
            compact(16_777_216, 256),
            1920,
            1080,
        );
        assert_eq!(clustered.scratch_per_list(), 64);
        let fixed = frustum(ListStorage::Fixed { capacity: 256 });
        assert_eq!(fixed.scratch_per_list(), 0);
    }
}
