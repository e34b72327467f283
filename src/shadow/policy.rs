//! Which shadow-casting lights ask the shadow atlas for a map and which are left to
//! ray-cast shadows: the `policy` and `fit` of a `ShadowAtlas` pass, decided on the CPU
//! with the atlas's allocation (`shadow::atlas::allocate`) every time the camera or the
//! lights move.
//!
//! A graph whose `ShadowRayJobs` pass reads the atlas's view table casts rays only for
//! lights without a map (the table's entry 0), and its shading samples the atlas for
//! lights with one and reads the ray-cast mask for the rest. So every light the policy
//! leaves out, and every light the allocation drops, is shadowed by rays.

use serde::{Deserialize, Serialize};

/// Which shadow-casting lights in view ask for an atlas tile; the others get ray-cast
/// shadows.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq)]
pub enum AtlasPolicy {
    /// Every shadow-casting light in view (without a ray pass reading the view table,
    /// the only policy allowed: nothing else would shadow the rest).
    #[default]
    All,
    /// The `count` lights nearest the camera (distance from the eye to the light's
    /// position; ties to the lower light index).
    Nearest(u32),
    /// Lights whose range sphere is at least `min_pixels` across on screen (its diameter
    /// in pixels of the frame's height, the size tiles are asked by before `importance`;
    /// the frame's height when the camera is inside the range).
    ProjectedSize(f32),
    /// Lights whose position lies within `distance` world units of the eye.
    Within(f32),
    /// At most `rays` shadow rays for the lights left to rays: the lights that could
    /// cast the most take maps first, until the rest could cast no more than `rays`. A
    /// light's rays are bounded on the CPU by the pixels of its range's screen box (a
    /// pixel casts at most one ray a light, and only where its surface lies in range),
    /// so the rays of the lights this leaves out never exceed the budget. Lights the
    /// allocation then drops for room are ray-cast too, past it (reported).
    RayBudget(f64),
}

/// What the allocation does when the requested tiles exceed the atlas.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
pub enum AtlasFit {
    /// Halve every tile above `min_tile` until they fit; drop the lowest-ranked light
    /// only when all are at `min_tile` (soft shadows for as many lights as possible).
    #[default]
    ShrinkTiles,
    /// Keep each tile at the size it asked for and drop the lowest-ranked lights
    /// until the rest fit (with a ray pass: resolution kept, the crowd to rays).
    DropLights,
}

impl AtlasPolicy {
    /// Why the parameter is out of range, if it is.
    pub fn problem(&self) -> Option<String> {
        match *self {
            AtlasPolicy::All => None,
            AtlasPolicy::Nearest(n) if !(1..=65536).contains(&n) => Some(format!(
                "policy Nearest({n}): the count must be in 1..=65536"
            )),
            AtlasPolicy::ProjectedSize(px) if !(px.is_finite() && px > 0.0 && px <= 65536.0) => {
                Some(format!(
                    "policy ProjectedSize({px}): min_pixels must be in (0, 65536]"
                ))
            }
            AtlasPolicy::Within(d) if !(d.is_finite() && d > 0.0) => Some(format!(
                "policy Within({d}): the distance must be positive and finite"
            )),
            AtlasPolicy::RayBudget(rays) if !(rays.is_finite() && rays > 0.0) => Some(format!(
                "policy RayBudget({rays}): the budget must be a positive, finite number of rays"
            )),
            _ => None,
        }
    }

    /// Whether the policy may leave a light in view without a tile.
    pub fn leaves_lights_to_rays(&self) -> bool {
        *self != AtlasPolicy::All
    }
}

/// A shadow-casting light in view, as the policy sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Candidate {
    pub(crate) light: u32,
    /// Diameter of its range on screen, pixels.
    pub(crate) screen_px: f32,
    /// Distance from the eye to its position.
    pub(crate) distance: f32,
    /// The most rays it can ask for: the pixels of its range's screen box.
    pub(crate) ray_pixels: f64,
}

/// Which candidates ask for a tile: `keep[i]` for `candidates[i]`.
pub(crate) fn select(policy: AtlasPolicy, candidates: &[Candidate]) -> Vec<bool> {
    match policy {
        AtlasPolicy::All => vec![true; candidates.len()],
        AtlasPolicy::Nearest(count) => {
            let mut order: Vec<usize> = (0..candidates.len()).collect();
            order.sort_by(|&a, &b| {
                let (a, b) = (&candidates[a], &candidates[b]);
                a.distance
                    .total_cmp(&b.distance)
                    .then(a.light.cmp(&b.light))
            });
            let mut keep = vec![false; candidates.len()];
            for &i in order.iter().take(count as usize) {
                keep[i] = true;
            }
            keep
        }
        AtlasPolicy::ProjectedSize(min_pixels) => candidates
            .iter()
            .map(|c| c.screen_px >= min_pixels)
            .collect(),
        AtlasPolicy::Within(distance) => {
            candidates.iter().map(|c| c.distance <= distance).collect()
        }
        AtlasPolicy::RayBudget(budget) => {
            let mut order: Vec<usize> = (0..candidates.len()).collect();
            order.sort_by(|&a, &b| {
                let (a, b) = (&candidates[a], &candidates[b]);
                b.ray_pixels
                    .total_cmp(&a.ray_pixels)
                    .then(a.light.cmp(&b.light))
            });
            let mut left: f64 = candidates.iter().map(|c| c.ray_pixels).sum();
            let mut keep = vec![false; candidates.len()];
            for i in order {
                if left <= budget {
                    break;
                }
                keep[i] = true;
                left -= candidates[i].ray_pixels;
            }
            keep
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn candidates() -> Vec<Candidate> {
        [
            (0, 40.0, 9.0),
            (1, 300.0, 2.0),
            (2, 120.0, 4.0),
            (3, 120.0, 4.0),
        ]
        .map(|(light, screen_px, distance)| Candidate {
            light,
            screen_px,
            distance,
            ray_pixels: f64::from(screen_px * screen_px),
        })
        .to_vec()
    }

    #[test]
    fn each_policy_keeps_what_it_names() {
        let c = candidates();
        assert_eq!(select(AtlasPolicy::All, &c), [true; 4]);
        // Nearest: light 1, then the tie of 2 and 3 broken by index.
        assert_eq!(
            select(AtlasPolicy::Nearest(2), &c),
            [false, true, true, false]
        );
        assert_eq!(select(AtlasPolicy::Nearest(9), &c), [true; 4]);
        assert_eq!(
            select(AtlasPolicy::ProjectedSize(120.0), &c),
            [false, true, true, true]
        );
        assert_eq!(
            select(AtlasPolicy::Within(3.0), &c),
            [false, true, false, false]
        );
        // RayBudget: rays 1,600, 90,000, 14,400, 14,400 (30,400 without light 1); the
        // largest first, ties to the lower index.
        assert_eq!(
            select(AtlasPolicy::RayBudget(30_400.0), &c),
            [false, true, false, false]
        );
        assert_eq!(
            select(AtlasPolicy::RayBudget(30_399.0), &c),
            [false, true, true, false]
        );
        assert_eq!(select(AtlasPolicy::RayBudget(1e9), &c), [false; 4]);
        assert_eq!(
            select(AtlasPolicy::RayBudget(1.0), &c),
            [true, true, true, true]
        );
    }

    #[test]
    fn bad_parameters_are_named() {
        assert!(AtlasPolicy::Nearest(0)
            .problem()
            .unwrap()
            .contains("Nearest(0)"));
        assert!(AtlasPolicy::ProjectedSize(f32::NAN)
            .problem()
            .unwrap()
            .contains("min_pixels"));
        assert!(AtlasPolicy::Within(-1.0).problem().is_some());
        assert!(AtlasPolicy::Within(0.5).problem().is_none());
        assert!(AtlasPolicy::RayBudget(0.0)
            .problem()
            .unwrap()
            .contains("RayBudget(0)"));
        assert!(AtlasPolicy::RayBudget(f64::INFINITY).problem().is_some());
        assert!(AtlasPolicy::RayBudget(1e6).problem().is_none());
        assert!(!AtlasPolicy::All.leaves_lights_to_rays());
    }
}
