//! `LightLinkedList`: per-pixel linked lists of the lights whose volume a pixel's view
//! ray crosses in front of the scene (Bezrati, "Real-Time Lighting via Light Linked List"), at 1/1, 1/2, 1/4 or 1/8 of the output
//! per side. Built in compute from a LightCulling pass's tile lists (or from every
//! light); runs `shaders/cull/light_linked_list.wgsl`. The depth is a depth texture or
//! R32Float depths (ComputeRaster's compute resolve; `FLOAT_DEPTH`), single-sample.

use super::contracts::InputsCtx;
use super::{slot, Access, BufferLayout, Contents, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::plan::FrameSize;
use serde::{Deserialize, Serialize};

/// `LightLinkedList(scale: 8, links_per_pixel: 32)`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(deny_unknown_fields)]
pub struct LightLinkedList {
    /// Output pixels per list-pixel side: 1 (full resolution), 2, 4 or 8.
    pub scale: u32,
    /// The link pool, as links per list pixel on average (the seed's table assumes 32);
    /// links past it are dropped, counted and reported.
    #[serde(default = "default_links_per_pixel")]
    pub links_per_pixel: u32,
}

fn default_links_per_pixel() -> u32 {
    32
}

/// The slot it writes (the WGSL binding name).
pub(crate) const LIGHT_LINKS: &str = "light_links";

impl LightLinkedList {
    pub(crate) fn link_layout(&self, width: u32, height: u32) -> LinkLayout {
        let scale = self.scale.max(1);
        let (w, h) = (width.div_ceil(scale), height.div_ceil(scale));
        LinkLayout {
            scale,
            width: w,
            height: h,
            pool: w as u64 * h as u64 * self.links_per_pixel as u64,
        }
    }
}

/// Layout of a light linked list buffer, shared with `shaders/common/light_lists.wgsl`:
/// a header of 4 u32 (links wanted, links dropped, pixels that lost a link, longest
/// list wanted), a head link per list pixel, then the pool of 12-byte links: the near
/// and far view depth as two f16 (rounded outwards), the light index, the next link.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LinkLayout {
    /// Output pixels per list-pixel side (the pass's `scale`).
    pub scale: u32,
    /// List pixels across.
    pub width: u32,
    /// List pixels down.
    pub height: u32,
    /// Links the pool holds.
    pub pool: u64,
}

impl LinkLayout {
    pub(crate) const HEADER_WORDS: u64 = 4;
    pub(crate) const LINK_WORDS: u64 = 3;
    /// List pixels (one head link each).
    pub fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }
    /// The word offset where the link pool starts (after the header and heads).
    pub fn pool_offset_words(&self) -> u64 {
        Self::HEADER_WORDS + self.pixels()
    }
    /// Bytes of the head links.
    pub fn head_bytes(&self) -> u64 {
        4 * self.pixels()
    }
    /// Bytes of the link pool (12 bytes a link).
    pub fn pool_bytes(&self) -> u64 {
        4 * Self::LINK_WORDS * self.pool
    }
    /// Bytes of the whole buffer: header, heads and pool.
    pub fn bytes(&self) -> u64 {
        4 * Self::HEADER_WORDS + self.head_bytes() + self.pool_bytes()
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
    // A LightCulling pass's tile lists: only their lights are tested (else every light).
    super::LIGHT_LISTS_READ.needs(&[Contents::LightLists]),
    SlotSpec::new(LIGHT_LINKS, SlotType::Buffer, Access::Write, Usage::Bound),
];

/// Scales whose list pixels tile a 8- or 16-pixel culling tile exactly, so each list
/// pixel reads one tile's list.
pub(crate) const SCALES: [u32; 4] = [1, 2, 4, 8];
/// Most links a list pixel may reserve on average (the pool must stay addressable by
/// a u32 word index at 8192² / 64).
pub(crate) const MAX_LINKS_PER_PIXEL: u32 = 1024;

pub(crate) fn check(p: &LightLinkedList, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    if let Some(depth) = ctx.slot(slot::DEPTH) {
        if ctx.samples(depth) > 1 {
            errors.push(ctx.mismatch(
                depth,
                "the light linked list reads a single-sample depth texture; this one is multisampled",
            ));
        }
    }
    if !SCALES.contains(&p.scale) {
        errors.push(ctx.bad(format!(
            "scale {} is not supported (1, 2, 4 or 8 output pixels per list pixel side)",
            p.scale
        )));
    }
    if p.links_per_pixel == 0 || p.links_per_pixel > MAX_LINKS_PER_PIXEL {
        errors.push(ctx.bad(format!(
            "links_per_pixel {} must be in 1..={MAX_LINKS_PER_PIXEL}",
            p.links_per_pixel
        )));
    }
}

impl KindRules for LightLinkedList {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(self, ctx, errors)
    }
    fn buffer_layout(&self, slot: &str, frame: FrameSize) -> Option<BufferLayout> {
        (slot == LIGHT_LINKS)
            .then(|| BufferLayout::LightLinks(self.link_layout(frame.width, frame.height)))
    }
    /// The candidates come from one list a tile, whose tiles a list pixel does not straddle.
    fn check_inputs(&self, ctx: &InputsCtx, errors: &mut Vec<GraphError>) {
        let (Some(lists), Some(BufferLayout::LightLists(tiles))) = (
            ctx.slot(slot::LIGHT_LISTS),
            ctx.published(slot::LIGHT_LISTS),
        ) else {
            return;
        };
        if tiles.lists_per_tile != 1 {
            errors.push(ctx.mismatch(
                lists,
                format!(
                    "'{lists}' has {} lists a tile ({:?}); the linked list reads one list a tile (Frustum or DepthMask)",
                    tiles.lists_per_tile, tiles.variant
                ),
            ));
        } else if SCALES.contains(&self.scale) && tiles.tile % self.scale != 0 {
            errors.push(ctx.mismatch(
                lists,
                format!(
                    "scale {} does not divide the culling tile of {} pixels of '{lists}'",
                    self.scale, tiles.tile
                ),
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::{errors, validate, CULL, PREPASS};

    #[test]
    fn checks_parameters() {
        let e = errors(
            &format!(
                r#"{PREPASS} Pass(name: "l", kind: LightLinkedList(scale: 3, links_per_pixel: 0), reads: ["depth", "lg"], writes: ["links"])"#
            ),
            "hdr",
        );
        for want in ["scale 3", "links_per_pixel 0"] {
            assert!(e.contains(want), "{want}: {e}");
        }
    }

    #[test]
    fn links_written_from_depth_with_or_without_tile_lists() {
        validate(
            &format!(
                r#"{PREPASS} {CULL} Pass(name: "l", kind: LightLinkedList(scale: 4), reads: ["depth", "lg", "lists"], writes: ["links"]), Pass(name: "s", kind: ForwardShading(lights: Culled), reads: ["depth", "lg", "lp", "links"], writes: ["hdr"])"#
            ),
            "hdr",
        )
        .unwrap();
        validate(
            &format!(
                r#"{PREPASS} Pass(name: "l", kind: LightLinkedList(scale: 1), reads: ["depth", "lg"], writes: ["links"]), Pass(name: "s", kind: ForwardShading(lights: Culled), reads: ["depth", "lg", "lp", "links"], writes: ["hdr"])"#
            ),
            "hdr",
        )
        .unwrap();
        let e = errors(
            &format!(
                r#"{PREPASS} Pass(name: "l", kind: LightLinkedList(scale: 8), reads: ["depth", "lg"])"#
            ),
            "hdr",
        );
        assert!(
            e.contains("LightLinkedList needs a buffer in writes (slot 'light_links')"),
            "{e}"
        );
        let e = errors(
            r#"Pass(name: "pre", kind: DepthPrepass, writes: ["depth4"]), Pass(name: "l", kind: LightLinkedList(scale: 8), reads: ["depth4", "lg"], writes: ["links"])"#,
            "hdr",
        );
        assert!(e.contains("single-sample depth"), "{e}");
    }

    #[test]
    fn memory_matches_the_seed_table_at_8_bytes_and_costs_half_again_at_12() {
        use super::{LightLinkedList, LinkLayout};
        let l = LightLinkedList {
            scale: 8,
            links_per_pixel: 32,
        }
        .link_layout(1920, 1080);
        // 240 × 135 list pixels, 32 links each.
        assert_eq!((l.width, l.height, l.pool), (240, 135, 240 * 135 * 32));
        let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
        // The seed's 8-byte links: 7.91 MiB; ours are 12 bytes.
        assert!((mib(l.pool * 8) - 7.91).abs() < 0.005);
        assert!((mib(l.pool_bytes()) - 11.87).abs() < 0.005);
        assert_eq!(
            l.bytes(),
            4 * LinkLayout::HEADER_WORDS + 4 * 240 * 135 + l.pool_bytes()
        );
    }
}
