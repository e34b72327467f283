//! Keeping shadow maps across frames (`ShadowAtlas(cache: true)`): which of an
//! allocation's views the atlas already holds, and a placement that keeps a light's
//! tiles where they were while their size stays.
//!
//! A view is kept when the texels of its tile were last drawn with the same view: the
//! same light and face, the same tile (position and side) and bit-for-bit the same
//! view-projection (which carries the light's position, range, direction and cone).
//! Anything else about a light (colour, intensity) does not change its depths. The
//! casters are fixed for a prepared pass: a scene whose meshes change is prepared again,
//! which starts with nothing held.

use super::atlas::{morton_decode, Allocation, AtlasConfig};
use std::collections::HashMap;

/// What one tile of the atlas holds: the view last drawn into it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Held {
    light: u32,
    face: u8,
    view_proj: [u32; 16],
}

/// The views the atlas holds, by tile (x, y, side).
#[derive(Clone, Debug, Default)]
pub(crate) struct AtlasCache {
    held: HashMap<(u32, u32, u32), Held>,
}

impl AtlasCache {
    /// Indices of the views of `a` whose tile does not hold them: those to draw.
    pub(crate) fn stale_views(&self, a: &Allocation) -> Vec<u32> {
        (0..a.views.len() as u32)
            .filter(|&v| {
                let view = &a.views[v as usize];
                self.held.get(&(view.x, view.y, view.tile)) != Some(&held(view))
            })
            .collect()
    }

    /// The atlas now holds every view of `a` (all drawn or kept); texels outside its
    /// tiles hold nothing anyone will look up.
    pub(crate) fn hold(&mut self, a: &Allocation) {
        self.held = a
            .views
            .iter()
            .map(|v| ((v.x, v.y, v.tile), held(v)))
            .collect();
    }
}

fn held(v: &super::atlas::AtlasView) -> Held {
    Held {
        light: v.light,
        face: v.face,
        view_proj: v.view_proj.to_cols_array().map(f32::to_bits),
    }
}

/// `next` with each light that kept its shape and tile side since `prev` placed where it
/// was, and the others packed into the free space (largest first, in Morton order).
/// When fragmentation leaves no room for one, `next`'s own packing (everything moves).
pub(crate) fn keep_places(
    prev: &Allocation,
    mut next: Allocation,
    cfg: &AtlasConfig,
) -> Allocation {
    let cells = cfg.size / cfg.min_tile;
    let mut tree = Occupancy::new(cells);
    let before: HashMap<u32, &super::atlas::AtlasLight> =
        prev.lights.iter().map(|l| (l.light, l)).collect();
    let mut kept = vec![false; next.lights.len()];
    for (i, l) in next.lights.iter().enumerate() {
        let Some(old) = before.get(&l.light) else {
            continue;
        };
        if old.cube != l.cube || old.tile != l.tile {
            continue;
        }
        let faces = if l.cube { 6 } else { 1 };
        for f in 0..faces {
            let from = &prev.views[(old.first_view + f) as usize];
            let to = &mut next.views[(l.first_view + f) as usize];
            to.x = from.x;
            to.y = from.y;
            tree.fill(
                from.x / cfg.min_tile,
                from.y / cfg.min_tile,
                l.tile / cfg.min_tile,
            );
        }
        kept[i] = true;
    }
    // `next.lights` come in decreasing tile size: packing largest first fragments least.
    for (i, l) in next.lights.iter().enumerate() {
        if kept[i] {
            continue;
        }
        let faces = if l.cube { 6 } else { 1 };
        for f in 0..faces {
            match tree.take(l.tile / cfg.min_tile) {
                Some((x, y)) => {
                    let view = &mut next.views[(l.first_view + f) as usize];
                    view.x = x * cfg.min_tile;
                    view.y = y * cfg.min_tile;
                }
                None => return fresh(next, cfg),
            }
        }
    }
    next
}

/// `next` as `allocate` packed it (its views' places are recomputed: `keep_places` may
/// have moved some before giving up).
fn fresh(mut next: Allocation, cfg: &AtlasConfig) -> Allocation {
    let mut cursor = 0u64;
    for l in &next.lights {
        let cells = (l.tile / cfg.min_tile) as u64;
        let faces = if l.cube { 6 } else { 1 };
        for f in 0..faces {
            let (cx, cy) = morton_decode(cursor);
            cursor += cells * cells;
            let view = &mut next.views[(l.first_view + f) as usize];
            view.x = cx * cfg.min_tile;
            view.y = cy * cfg.min_tile;
        }
    }
    next
}

/// Which cells of the atlas are taken, as a quadtree of used-cell counts: level `l`
/// counts the cells of each aligned 2^l × 2^l block (blocks in Morton order). A block
/// taken whole counts full at its level and above, nothing below: a search never
/// descends into a full block.
struct Occupancy {
    levels: Vec<Vec<u32>>,
}

impl Occupancy {
    fn new(cells: u32) -> Self {
        let top = cells.max(1).trailing_zeros() as usize;
        let levels = (0..=top)
            .map(|l| vec![0u32; 1usize << (2 * (top - l))])
            .collect();
        Occupancy { levels }
    }

    fn full(level: usize) -> u32 {
        1 << (2 * level)
    }

    /// Marks the aligned `side`-cell square at cell (x, y) taken.
    fn fill(&mut self, x: u32, y: u32, side: u32) {
        let level = side.trailing_zeros() as usize;
        let mut k = (morton_encode(x, y) >> (2 * level)) as usize;
        self.levels[level][k] = Self::full(level);
        for l in level + 1..self.levels.len() {
            k >>= 2;
            self.levels[l][k] += Self::full(level);
        }
    }

    /// Takes the first free aligned `side`-cell square in Morton order: its cell.
    fn take(&mut self, side: u32) -> Option<(u32, u32)> {
        let level = side.trailing_zeros() as usize;
        let top = self.levels.len() - 1;
        if level > top {
            return None;
        }
        let k = self.find(top, 0, level)?;
        let (x, y) = morton_decode((k as u64) << (2 * level));
        self.fill(x, y, side);
        Some((x, y))
    }

    /// The first empty block of `level` under block `k` of level `at`.
    fn find(&self, at: usize, k: usize, level: usize) -> Option<usize> {
        let used = self.levels[at][k];
        if at == level {
            return (used == 0).then_some(k);
        }
        if used == Self::full(at) {
            return None;
        }
        (0..4).find_map(|c| self.find(at - 1, 4 * k + c, level))
    }
}

/// The Morton index of cell (x, y) (x in the even bits).
fn morton_encode(x: u32, y: u32) -> u64 {
    fn spread(v: u32) -> u64 {
        let mut v = v as u64;
        v = (v | (v << 16)) & 0x0000_ffff_0000_ffff;
        v = (v | (v << 8)) & 0x00ff_00ff_00ff_00ff;
        v = (v | (v << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
        v = (v | (v << 2)) & 0x3333_3333_3333_3333;
        v = (v | (v << 1)) & 0x5555_5555_5555_5555;
        v
    }
    spread(x) | (spread(y) << 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::light_flags::CASTS_SHADOW;
    use crate::scene::{Camera, Light};
    use crate::shadow::atlas::allocate;
    use glam::Vec3;

    fn caster(position: Vec3, range: f32) -> Light {
        Light {
            flags: CASTS_SHADOW,
            ..Light::point(position, range, Vec3::ONE, 1.0)
        }
    }

    fn camera() -> Camera {
        Camera {
            eye: Vec3::new(0.0, 2.0, 20.0),
            target: Vec3::ZERO,
            ..Default::default()
        }
    }

    fn cfg(size: u32) -> AtlasConfig {
        AtlasConfig {
            size,
            min_tile: 16,
            max_tile: 1024,
            importance: 1.0,
            max_lights: 512,
            policy: Default::default(),
            fit: Default::default(),
        }
    }

    fn no_overlap(a: &Allocation, size: u32) {
        for (i, v) in a.views.iter().enumerate() {
            assert!(v.x + v.tile <= size && v.y + v.tile <= size, "{v:?}");
            assert!(v.x % v.tile == 0 && v.y % v.tile == 0, "unaligned {v:?}");
            for w in &a.views[..i] {
                let apart = v.x + v.tile <= w.x
                    || w.x + w.tile <= v.x
                    || v.y + v.tile <= w.y
                    || w.y + w.tile <= v.y;
                assert!(apart, "{v:?} overlaps {w:?}");
            }
        }
    }

    #[test]
    fn morton_round_trips() {
        for (x, y) in [(0, 0), (1, 0), (0, 1), (5, 9), (1023, 77)] {
            assert_eq!(morton_decode(morton_encode(x, y)), (x, y));
        }
    }

    #[test]
    fn a_light_that_moves_keeps_the_others_in_place_and_drawn() {
        let mut lights: Vec<Light> = (0..20)
            .map(|i| caster(Vec3::new(i as f32 - 10.0, 1.0, (i % 3) as f32), 2.0))
            .collect();
        let c = cfg(4096);
        let first = allocate(&lights, &camera(), 1920, 1080, &c);
        let mut cache = AtlasCache::default();
        assert_eq!(cache.stale_views(&first).len(), first.views.len());
        cache.hold(&first);
        assert!(cache.stale_views(&first).is_empty(), "nothing moved");
        // Light 7 moves towards the camera: its tile grows and the ranking changes.
        lights[7].position += Vec3::new(0.0, 0.0, 8.0);
        let next = keep_places(&first, allocate(&lights, &camera(), 1920, 1080, &c), &c);
        no_overlap(&next, 4096);
        let stale = cache.stale_views(&next);
        assert_eq!(stale.len(), 6, "only the moved light's faces: {stale:?}");
        assert!(stale.iter().all(|&v| next.views[v as usize].light == 7));
        // Without keeping places, the new ranking moves many lights' tiles.
        let moved = allocate(&lights, &camera(), 1920, 1080, &c);
        assert!(cache.stale_views(&moved).len() > 6);
        cache.hold(&next);
        assert!(cache.stale_views(&next).is_empty());
    }

    #[test]
    fn no_room_after_fragmenting_falls_back_to_packing_everything() {
        // 256² holds 256 tiles of 16: forty lights, then all but one grow or shrink.
        let lights: Vec<Light> = (0..40)
            .map(|i| caster(Vec3::new(i as f32 * 0.5 - 10.0, 1.0, 5.0), 3.0))
            .collect();
        let c = cfg(256);
        let a = allocate(&lights, &camera(), 1920, 1080, &c);
        let b = keep_places(&a, a.clone(), &c);
        assert_eq!(a, b, "same lights, same places");
        // Give every second light another tile side by asking for less everywhere.
        let mut prev = a.clone();
        for l in prev.lights.iter_mut().step_by(2) {
            l.tile *= 2;
        }
        let kept = keep_places(&prev, a.clone(), &c);
        no_overlap(&kept, 256);
        assert_eq!(kept.lights, a.lights);
    }
}
