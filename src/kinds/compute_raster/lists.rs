//! `ComputeRaster`'s work lists: how many records, tile and block entries each run has
//! room for (past that, setup and bin rasterize serially and count it), and the test
//! hook that lowers those capacities or turns setup's direct paths off.

use super::compute_raster::{BLOCK, TILE_PIXELS};

/// Bytes of a fan-triangle record and of a tile or block entry (as the shader's).
pub(super) const RECORD_BYTES: u64 = 64;
pub(super) const ENTRY_BYTES: u64 = 8;
/// Most entries a list holds: the block counter, which grows by at most TILE_BLOCKS² per
/// tile entry and 4 per record without checking, then stays under 2^31 (no wrap).
const MAX_ENTRIES: u64 = 1 << 24;
/// Most records: the tile counter, which grows by up to 16 tiles per record without
/// checking, then stays under 2^27 (see the setup shader's `reserve_entries`).
const MAX_RECORDS: u64 = 1 << 22;
/// Most pixels in the box of a fan triangle that its setup thread covers itself (why 16:
/// the setup shader's `small_pixels`).
const SMALL_PIXELS: u32 = 16;
/// The most the test hook's `small=N` may ask (a 16×16 box, 16 rows a thread).
const MAX_SMALL_PIXELS: u32 = 256;
/// Test hook: `records=N,tiles=N,blocks=N,groups=N,small=N,direct=0` (any of them)
/// overrides the lists' capacities and the workgroups per dispatch dimension, so tests
/// can fill the lists and fold small dispatches into y; `small=N` sets the most pixels of
/// a box setup covers itself (0: none; to measure the threshold on a GPU); `direct=0`
/// turns setup's direct paths off (every fan triangle through tiles and bin), the
/// reference they are tested against. Read when the pass is prepared.
pub const TEST_LIMITS_VAR: &str = "LIGHTGRAPH_COMPUTE_RASTER_TEST_LIMITS";

/// Entries of the three work lists.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct ListCapacity {
    pub(super) records: u32,
    pub(super) tiles: u32,
    pub(super) blocks: u32,
}

/// Room for 1.5 fan triangles per triangle (back faces and triangles off screen give
/// none, most others one; near-plane and side clipping give more), two tiles per record plus 16 screens of tiles, four blocks per record
/// plus 8 screens of blocks (depth complexity 8 of large triangles), each within the
/// device's binding size. Past that, work is rasterized serially and counted.
pub(super) fn list_capacity(
    triangles: u32,
    width: u32,
    height: u32,
    max_binding: u64,
) -> ListCapacity {
    let screen_tiles = width.div_ceil(TILE_PIXELS) as u64 * height.div_ceil(TILE_PIXELS) as u64;
    let screen_blocks = width.div_ceil(BLOCK) as u64 * height.div_ceil(BLOCK) as u64;
    let records = triangles as u64 * 3 / 2 + 4096;
    let fit = |n: u64, bytes: u64| n.min(max_binding / bytes).min(MAX_ENTRIES) as u32;
    ListCapacity {
        records: fit(records, RECORD_BYTES).min(MAX_RECORDS as u32),
        tiles: fit(2 * records + 16 * screen_tiles, ENTRY_BYTES),
        blocks: fit(4 * records + 8 * screen_blocks, ENTRY_BYTES),
    }
}

/// The test hook's overrides (`TEST_LIMITS_VAR`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct TestLimits {
    records: Option<u32>,
    tiles: Option<u32>,
    blocks: Option<u32>,
    groups: Option<u32>,
    /// `small=N`: the small path's threshold instead of SMALL_PIXELS.
    small: Option<u32>,
    /// `direct=0`: setup neither covers small fan triangles nor lists blocks itself.
    no_direct: bool,
}

fn parse_test_limits(text: &str) -> Result<TestLimits, String> {
    let mut limits = TestLimits::default();
    for item in text.split(',').map(str::trim).filter(|i| !i.is_empty()) {
        let bad = || {
            format!(
                "{TEST_LIMITS_VAR}: '{item}' is not NAME=COUNT (records, tiles, blocks, groups, small up to {MAX_SMALL_PIXELS}) or direct=0"
            )
        };
        let (name, value) = item.split_once('=').ok_or_else(bad)?;
        let value: u32 = value.trim().parse().map_err(|_| bad())?;
        if name.trim() == "direct" {
            if value != 0 {
                return Err(bad());
            }
            limits.no_direct = true;
            continue;
        }
        let field = match name.trim() {
            "records" => &mut limits.records,
            "tiles" => &mut limits.tiles,
            "blocks" => &mut limits.blocks,
            "groups" if value >= 1 => &mut limits.groups,
            "small" if value <= MAX_SMALL_PIXELS => &mut limits.small,
            _ => return Err(bad()),
        };
        *field = Some(value);
    }
    Ok(limits)
}

impl TestLimits {
    pub(super) fn from_env() -> Result<Self, String> {
        match std::env::var(TEST_LIMITS_VAR) {
            Ok(text) => parse_test_limits(&text),
            Err(_) => Ok(Self::default()),
        }
    }
    pub(super) fn apply(self, c: ListCapacity, max_groups: u32) -> (ListCapacity, u32) {
        let capacity = ListCapacity {
            records: self.records.map_or(c.records, |n| n.min(c.records)),
            tiles: self.tiles.map_or(c.tiles, |n| n.min(c.tiles)),
            blocks: self.blocks.map_or(c.blocks, |n| n.min(c.blocks)),
        };
        (
            capacity,
            self.groups.map_or(max_groups, |g| g.min(max_groups)),
        )
    }
    /// The setup shader's `list_capacity.w`: bit 0, setup lists the blocks of fan
    /// triangles within 2×2 blocks; above it, the most pixels of a box it covers itself.
    pub(super) fn direct_paths(self) -> u32 {
        if self.no_direct {
            0
        } else {
            (self.small.unwrap_or(SMALL_PIXELS) << 1) | 1
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_hold_the_scene_and_fit_the_binding() {
        // harada at 1080p: 2,240 triangles, 30×17 tiles, 240×135 blocks.
        let c = list_capacity(2240, 1920, 1080, 1 << 30);
        assert_eq!(c.records, 3 * 2240 / 2 + 4096);
        assert_eq!(c.tiles, 2 * c.records + 16 * 30 * 17);
        assert_eq!(c.blocks, 4 * c.records + 8 * 240 * 135);
        // A small binding limit caps each list by its entry size.
        let c = list_capacity(1 << 20, 1920, 1080, 1 << 20);
        assert_eq!((c.records, c.tiles, c.blocks), (1 << 14, 1 << 17, 1 << 17));
        // And no list passes its maximum (the counters never wrap).
        let c = list_capacity(u32::MAX, 16384, 16384, u64::MAX);
        assert_eq!((c.records, c.tiles, c.blocks), (1 << 22, 1 << 24, 1 << 24));
    }

    #[test]
    fn test_limits_parse_and_only_lower() {
        assert_eq!(parse_test_limits(""), Ok(TestLimits::default()));
        let t = parse_test_limits("records=0, blocks=7,groups=3").unwrap();
        assert_eq!(
            t,
            TestLimits {
                records: Some(0),
                tiles: None,
                blocks: Some(7),
                groups: Some(3),
                small: None,
                no_direct: false,
            }
        );
        assert_eq!(t.direct_paths(), (SMALL_PIXELS << 1) | 1);
        let small = parse_test_limits("small=0").unwrap();
        assert_eq!((small.small, small.direct_paths()), (Some(0), 1));
        let off = parse_test_limits("direct=0,small=64").unwrap();
        assert_eq!((off.no_direct, off.direct_paths()), (true, 0));
        let full = ListCapacity {
            records: 10,
            tiles: 20,
            blocks: 5,
        };
        let (c, groups) = t.apply(full, 65535);
        assert_eq!(
            (c, groups),
            (
                ListCapacity {
                    records: 0,
                    tiles: 20,
                    blocks: 5
                },
                3
            )
        );
        for bad in [
            "records",
            "tiles=x",
            "groups=0",
            "pixels=3",
            "direct=1",
            "small=257",
        ] {
            let e = parse_test_limits(bad).unwrap_err();
            assert!(e.contains(TEST_LIMITS_VAR) && e.contains(bad), "{e}");
        }
    }
}
