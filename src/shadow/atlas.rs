//! The shadow atlas's allocation, CPU side: which shadow-casting lights get a shadow
//! map this frame, how large, where in the atlas, and each view's projection.
//!
//! Policy (after Unity URP's, with the drops reported instead of silent):
//! - every shadow-casting light whose range sphere touches the camera's frustum asks for
//!   a square tile of its screen-space diameter × `importance`, rounded up to a power of
//!   two and clamped to `[min_tile, max_tile]`; a point light (or a spot wider than
//!   `CUBE_SPOT_ANGLE`) asks for six such faces;
//! - requests are ranked: larger first, then spot before point, then nearer the camera,
//!   then by light index (so the same view always allocates the same way);
//! - the pass's `policy` (`shadow::policy`) first leaves out the lights it gives to
//!   ray-cast shadows (listed, not dropped);
//! - past `max_lights`, the lowest ranked are dropped; then, while the tiles' total area
//!   exceeds the atlas, every tile above `min_tile` is halved; when all are at
//!   `min_tile`, the lowest ranked light is dropped instead (with `fit: DropLights`, the
//!   lowest ranked are dropped at once, tiles kept at their asked size);
//! - tiles are placed in Morton order in decreasing size, which packs power-of-two
//!   squares without gaps, so a set fits exactly when its area does.
//!
//! Cube faces are rendered with a field of view widened by [`GUARD_TEXELS`] on every
//! side, so a 5×5 filter around any point of a face's inner 90° stays on that face.

use super::policy::{self, AtlasFit, AtlasPolicy, Candidate};
use super::view_bounds::{frustum_planes, ray_pixels_bound, screen_size, sphere_in_frustum};
use crate::scene::{Camera, Light, LightShape};
use glam::{Mat4, Vec3};

/// Texels of each cube face (and spot tile) rendered beyond its inner field of view:
/// the 5×5 filter reaches 2 texels out, plus one for the bilinear comparison.
pub const GUARD_TEXELS: u32 = 3;
/// Spot lights whose outer cone half-angle exceeds this take six faces like a point
/// light: one perspective tile loses too much resolution towards the rim of a wide cone.
pub(crate) const CUBE_SPOT_ANGLE: f32 = std::f32::consts::FRAC_PI_3;
/// The light's near plane as a fraction of its range.
pub(crate) const NEAR_FRACTION: f32 = 0.002;

/// The allocator's knobs (the ShadowAtlas pass's parameters and its texture's size).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct AtlasConfig {
    /// The atlas's side in texels (a power of two).
    pub(crate) size: u32,
    pub(crate) min_tile: u32,
    pub(crate) max_tile: u32,
    pub(crate) importance: f32,
    pub(crate) max_lights: u32,
    /// Which lights in view ask for a tile.
    pub(crate) policy: AtlasPolicy,
    /// Shrink tiles or drop lights when they do not fit.
    pub(crate) fit: AtlasFit,
}

/// One rendered view: a square tile of the atlas and the projection that fills it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct AtlasView {
    pub light: u32,
    /// Cube face (0 +X, 1 −X, 2 +Y, 3 −Y, 4 +Z, 5 −Z), or 0 for a spot tile.
    pub(crate) face: u8,
    /// Top-left texel and side.
    pub(crate) x: u32,
    pub(crate) y: u32,
    pub(crate) tile: u32,
    pub(crate) view_proj: Mat4,
    /// World size of one texel at unit distance along the view axis.
    pub(crate) texel_scale: f32,
}

/// A shadowed light: its first view and whether it has six.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AtlasLight {
    /// The light's index in the scene.
    pub light: u32,
    pub(crate) first_view: u32,
    pub(crate) cube: bool,
    /// Side of each of its tiles, texels.
    pub tile: u32,
}

/// Why a shadow-casting light in view got no shadow this frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DropReason {
    /// Past the pass's `max_lights`.
    MaxLights,
    /// No room at the minimum tile size.
    NoRoom,
}

/// A shadow-casting light in view that got no tile this frame: it is lit unshadowed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DroppedLight {
    /// The light's index in the scene.
    pub light: u32,
    /// The tile side it asked for before any halving.
    pub wanted: u32,
    /// Why it was dropped.
    pub reason: DropReason,
}

/// One frame's allocation.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Allocation {
    pub(crate) views: Vec<AtlasView>,
    pub lights: Vec<AtlasLight>,
    pub(crate) dropped: Vec<DroppedLight>,
    /// Shadow-casting lights in view the policy left to ray-cast shadows (none with
    /// `policy: All`), by light index.
    pub(crate) left_by_policy: Vec<u32>,
    /// Shadow-casting lights whose range does not reach the camera's frustum.
    pub(crate) off_screen: u32,
    /// How many times the tiles were halved to fit.
    pub(crate) halvings: u32,
    /// Texels covered by tiles.
    pub(crate) used_texels: u64,
}

struct Request {
    light: u32,
    cube: bool,
    spot: bool,
    wanted: u32,
    tile: u32,
    screen_px: f32,
    distance: f32,
    ray_pixels: f64,
}

impl Request {
    fn area(&self) -> u64 {
        let faces = if self.cube { 6 } else { 1 };
        faces * self.tile as u64 * self.tile as u64
    }
}

fn is_cube(light: &Light) -> bool {
    match light.shape {
        LightShape::Point => true,
        LightShape::Spot { outer_angle, .. } => outer_angle > CUBE_SPOT_ANGLE,
    }
}

/// Allocates the atlas for every light with `CASTS_SHADOW` seen from `camera` rendering
/// `width`×`height`.
pub(crate) fn allocate(
    lights: &[Light],
    camera: &Camera,
    width: u32,
    height: u32,
    cfg: &AtlasConfig,
) -> Allocation {
    let aspect = width as f32 / height.max(1) as f32;
    let view_proj = camera.projection(aspect) * camera.view();
    let planes = frustum_planes(view_proj);
    let mut out = Allocation::default();
    let mut requests = Vec::new();
    for (i, l) in lights.iter().enumerate() {
        if l.flags & crate::scene::light_flags::CASTS_SHADOW == 0 {
            continue;
        }
        if !sphere_in_frustum(&planes, l.position, l.range) {
            out.off_screen += 1;
            continue;
        }
        let screen_px = screen_size(l, camera, height);
        let size = (screen_px * cfg.importance).ceil();
        let wanted = (size.max(1.0) as u32)
            .checked_next_power_of_two()
            .unwrap_or(cfg.max_tile)
            .clamp(cfg.min_tile, cfg.max_tile);
        requests.push(Request {
            light: i as u32,
            cube: is_cube(l),
            spot: matches!(l.shape, LightShape::Spot { .. }),
            wanted,
            tile: wanted,
            screen_px,
            distance: l.position.distance(camera.eye),
            ray_pixels: ray_pixels_bound(l, &view_proj, width, height),
        });
    }
    let candidates: Vec<Candidate> = requests
        .iter()
        .map(|r| Candidate {
            light: r.light,
            screen_px: r.screen_px,
            distance: r.distance,
            ray_pixels: r.ray_pixels,
        })
        .collect();
    let keep = policy::select(cfg.policy, &candidates);
    let mut kept = keep.iter();
    requests.retain(|r| {
        let keep = *kept.next().expect("a verdict per request");
        if !keep {
            out.left_by_policy.push(r.light);
        }
        keep
    });
    requests.sort_by(|a, b| {
        b.wanted
            .cmp(&a.wanted)
            .then(b.spot.cmp(&a.spot))
            .then(a.distance.total_cmp(&b.distance))
            .then(a.light.cmp(&b.light))
    });
    let drop = |r: Request, reason, out: &mut Allocation| {
        out.dropped.push(DroppedLight {
            light: r.light,
            wanted: r.wanted,
            reason,
        })
    };
    while requests.len() > cfg.max_lights as usize {
        let r = requests.pop().expect("longer than max_lights");
        drop(r, DropReason::MaxLights, &mut out);
    }
    let capacity = cfg.size as u64 * cfg.size as u64;
    while requests.iter().map(Request::area).sum::<u64>() > capacity {
        if cfg.fit == AtlasFit::ShrinkTiles && requests.iter().any(|r| r.tile > cfg.min_tile) {
            for r in requests.iter_mut().filter(|r| r.tile > cfg.min_tile) {
                r.tile /= 2;
            }
            out.halvings += 1;
        } else {
            let r = requests.pop().expect("over capacity with requests left");
            drop(r, DropReason::NoRoom, &mut out);
        }
    }
    // Halving keeps the ranking's order of sizes, and dropping from the end keeps the
    // rest in it, so tiles come in decreasing size.
    let mut cursor = 0u64; // in min_tile cells, Morton order
    for r in &requests {
        let l = &lights[r.light as usize];
        let cells = (r.tile / cfg.min_tile) as u64;
        let faces = if r.cube { 6 } else { 1 };
        out.lights.push(AtlasLight {
            light: r.light,
            first_view: out.views.len() as u32,
            cube: r.cube,
            tile: r.tile,
        });
        for face in 0..faces {
            let (cx, cy) = morton_decode(cursor);
            cursor += cells * cells;
            let (view_proj, texel_scale) = view_projection(l, r.cube, face, r.tile);
            out.views.push(AtlasView {
                light: r.light,
                face,
                x: cx * cfg.min_tile,
                y: cy * cfg.min_tile,
                tile: r.tile,
                view_proj,
                texel_scale,
            });
        }
        out.used_texels += r.area();
    }
    out
}

/// The (x, y) cell of Morton index `i` (x in the even bits).
pub(crate) fn morton_decode(i: u64) -> (u32, u32) {
    fn compact(mut v: u64) -> u32 {
        v &= 0x5555_5555_5555_5555;
        v = (v | (v >> 1)) & 0x3333_3333_3333_3333;
        v = (v | (v >> 2)) & 0x0f0f_0f0f_0f0f_0f0f;
        v = (v | (v >> 4)) & 0x00ff_00ff_00ff_00ff;
        v = (v | (v >> 8)) & 0x0000_ffff_0000_ffff;
        v = (v | (v >> 16)) & 0x0000_0000_ffff_ffff;
        v as u32
    }
    (compact(i), compact(i >> 1))
}

/// Cube face directions and ups, in face order.
const FACES: [(Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::NEG_Y),
    (Vec3::NEG_X, Vec3::NEG_Y),
    (Vec3::Y, Vec3::Z),
    (Vec3::NEG_Y, Vec3::NEG_Z),
    (Vec3::Z, Vec3::NEG_Y),
    (Vec3::NEG_Z, Vec3::NEG_Y),
];

/// The face a direction from the light falls on: its major axis (ties to the lower
/// face, as the shader picks).
pub fn cube_face(d: Vec3) -> u8 {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        if d.x >= 0.0 {
            0
        } else {
            1
        }
    } else if a.y >= a.z {
        if d.y >= 0.0 {
            2
        } else {
            3
        }
    } else if d.z >= 0.0 {
        4
    } else {
        5
    }
}

/// A view's projection and the world size of a texel at unit distance.
fn view_projection(light: &Light, cube: bool, face: u8, tile: u32) -> (Mat4, f32) {
    let (dir, up, half) = if cube {
        let (dir, up) = FACES[face as usize];
        (dir, up, std::f32::consts::FRAC_PI_4)
    } else {
        let LightShape::Spot {
            direction,
            outer_angle,
            ..
        } = light.shape
        else {
            unreachable!("a point light is always a cube")
        };
        let dir = direction.normalize_or(Vec3::NEG_Y);
        let up = if dir.y.abs() > 0.9 { Vec3::Z } else { Vec3::Y };
        (dir, up, outer_angle.max(1e-3))
    };
    // The inner field of view covers tile − 2·guard texels; the guard is extra.
    let inner = (tile.saturating_sub(2 * GUARD_TEXELS)).max(1) as f32;
    let tan_half = half.tan() * tile as f32 / inner;
    let near = light.range * NEAR_FRACTION;
    let proj = Mat4::perspective_rh(2.0 * tan_half.atan(), 1.0, near, light.range);
    let view = Mat4::look_to_rh(light.position, dir, up);
    (proj * view, 2.0 * tan_half / tile as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::light_flags::CASTS_SHADOW;

    fn caster(position: Vec3, range: f32) -> Light {
        Light {
            flags: CASTS_SHADOW,
            ..Light::point(position, range, Vec3::ONE, 1.0)
        }
    }

    fn spot(position: Vec3, range: f32) -> Light {
        Light {
            shape: LightShape::Spot {
                direction: Vec3::NEG_Y,
                inner_angle: 0.3,
                outer_angle: 0.5,
            },
            ..caster(position, range)
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
            policy: AtlasPolicy::All,
            fit: AtlasFit::ShrinkTiles,
        }
    }

    fn check_packing(a: &Allocation, size: u32) {
        for (i, v) in a.views.iter().enumerate() {
            assert!(v.x + v.tile <= size && v.y + v.tile <= size, "{v:?}");
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
    fn packs_without_overlap_and_ranks_spots_first() {
        let mut lights: Vec<Light> = (0..12)
            .map(|i| caster(Vec3::new(i as f32 - 6.0, 1.0, 0.0), 2.0))
            .collect();
        lights.extend((0..12).map(|i| spot(Vec3::new(i as f32 - 6.0, 3.0, -2.0), 2.0)));
        let a = allocate(&lights, &camera(), 1920, 1080, &cfg(4096));
        assert_eq!(a.lights.len(), 24);
        assert_eq!(a.views.len(), 12 * 6 + 12);
        assert!(a.dropped.is_empty());
        check_packing(&a, 4096);
        // Same size: spots rank first.
        let first = &lights[a.lights[0].light as usize];
        assert!(matches!(first.shape, LightShape::Spot { .. }));
        // Deterministic for the same view.
        assert_eq!(a, allocate(&lights, &camera(), 1920, 1080, &cfg(4096)));
    }

    #[test]
    fn halves_then_drops_and_reports() {
        let lights: Vec<Light> = (0..50)
            .map(|i| caster(Vec3::new(i as f32 * 0.5 - 12.5, 1.0, 5.0), 3.0))
            .collect();
        let big = allocate(&lights, &camera(), 1920, 1080, &cfg(16384));
        assert!(big.dropped.is_empty());
        let small = allocate(&lights, &camera(), 1920, 1080, &cfg(256));
        assert!(small.halvings > 0);
        // 256² holds 256 min tiles: 42 point lights of six faces at 16 texels.
        assert_eq!(small.lights.len(), 256 / 6);
        assert_eq!(small.dropped.len(), 50 - 256 / 6);
        assert!(small
            .dropped
            .iter()
            .all(|d| d.reason == DropReason::NoRoom && d.wanted >= 16));
        assert!(small.views.iter().all(|v| v.tile == 16));
        check_packing(&small, 256);
        // The kept ones are the highest ranked: the nearest to the camera.
        let far = |l: u32| lights[l as usize].position.distance(camera().eye);
        let kept_max = small
            .lights
            .iter()
            .map(|l| far(l.light))
            .fold(0.0, f32::max);
        let dropped_min = small
            .dropped
            .iter()
            .map(|d| far(d.light))
            .fold(f32::MAX, f32::min);
        assert!(kept_max <= dropped_min);
        let capped = allocate(
            &lights,
            &camera(),
            1920,
            1080,
            &AtlasConfig {
                max_lights: 5,
                ..cfg(16384)
            },
        );
        assert_eq!(capped.lights.len(), 5);
        assert_eq!(capped.dropped.len(), 45);
        assert!(capped
            .dropped
            .iter()
            .all(|d| d.reason == DropReason::MaxLights));
    }

    #[test]
    fn off_screen_and_unflagged_lights_ask_for_nothing() {
        let lights = vec![
            caster(Vec3::new(0.0, 0.0, 40.0), 1.0), // behind the camera
            Light::point(Vec3::ZERO, 3.0, Vec3::ONE, 1.0),
            caster(Vec3::ZERO, 3.0),
        ];
        let a = allocate(&lights, &camera(), 640, 360, &cfg(2048));
        assert_eq!(a.off_screen, 1);
        assert_eq!(a.lights.len(), 1);
        assert_eq!(a.lights[0].light, 2);
    }

    #[test]
    fn tiles_follow_screen_size_and_importance() {
        let near = caster(Vec3::new(0.0, 0.0, 15.0), 2.0);
        let far = caster(Vec3::new(0.0, 0.0, -40.0), 2.0);
        let a = allocate(&[near, far], &camera(), 1920, 1080, &cfg(16384));
        let tile = |l: u32| a.lights.iter().find(|x| x.light == l).unwrap().tile;
        assert!(tile(0) > tile(1), "{:?}", a.lights);
        let half = allocate(
            &[near, far],
            &camera(),
            1920,
            1080,
            &AtlasConfig {
                importance: 0.5,
                ..cfg(16384)
            },
        );
        assert_eq!(half.lights[0].tile * 2, a.lights[0].tile);
    }

    #[test]
    fn cube_faces_cover_their_axis_with_a_guard_band() {
        let l = caster(Vec3::new(1.0, 2.0, 3.0), 5.0);
        for face in 0..6u8 {
            let (m, _) = view_projection(&l, true, face, 64);
            let (dir, _) = FACES[face as usize];
            assert_eq!(cube_face(dir), face);
            // A point at the inner 45° edge lands GUARD_TEXELS inside the tile's edge.
            let side = if dir.x != 0.0 { Vec3::Y } else { Vec3::X };
            let p = l.position + dir + side;
            let ndc = m.project_point3(p);
            let edge_texels = (1.0 - ndc.x.abs().max(ndc.y.abs())) * 32.0;
            assert!(
                (edge_texels - GUARD_TEXELS as f32).abs() < 1e-3,
                "face {face}: {edge_texels}"
            );
            let center = m.project_point3(l.position + dir * 2.0);
            assert!(center.x.abs() < 1e-5 && center.y.abs() < 1e-5);
            assert!(center.z > 0.0 && center.z < 1.0);
        }
    }

    #[test]
    fn the_policy_leaves_lights_to_rays_before_the_budget() {
        let lights: Vec<Light> = (0..10)
            .map(|i| caster(Vec3::new(0.0, 1.0, 15.0 - 4.0 * i as f32), 2.0))
            .collect();
        let nearest = allocate(
            &lights,
            &camera(),
            1920,
            1080,
            &AtlasConfig {
                policy: AtlasPolicy::Nearest(3),
                ..cfg(16384)
            },
        );
        let mut kept: Vec<u32> = nearest.lights.iter().map(|l| l.light).collect();
        kept.sort();
        assert_eq!(kept, [0, 1, 2]);
        assert_eq!(nearest.left_by_policy.len(), 7);
        assert!(nearest.dropped.is_empty());
        // The kept lights get the tiles they get with every light in the atlas.
        let all = allocate(&lights, &camera(), 1920, 1080, &cfg(16384));
        assert!(all.left_by_policy.is_empty());
        for l in &nearest.lights {
            let same = all.lights.iter().find(|a| a.light == l.light).unwrap();
            assert_eq!(same.tile, l.tile);
        }
        check_packing(&nearest, 16384);
    }

    #[test]
    fn drop_lights_keeps_tile_sizes_and_drops_the_lowest_ranked() {
        let lights: Vec<Light> = (0..50)
            .map(|i| caster(Vec3::new(i as f32 * 0.5 - 12.5, 1.0, 5.0), 3.0))
            .collect();
        let wanted = allocate(&lights, &camera(), 1920, 1080, &cfg(16384));
        let fit = AtlasConfig {
            fit: AtlasFit::DropLights,
            ..cfg(2048)
        };
        let a = allocate(&lights, &camera(), 1920, 1080, &fit);
        assert_eq!(a.halvings, 0);
        assert!(!a.dropped.is_empty() && !a.lights.is_empty());
        assert_eq!(a.lights.len() + a.dropped.len(), 50);
        for l in &a.lights {
            let w = wanted.lights.iter().find(|w| w.light == l.light).unwrap();
            assert_eq!(w.tile, l.tile);
        }
        // The kept ones are the first of the ranking.
        let ranked: Vec<u32> = wanted.lights.iter().map(|l| l.light).collect();
        let kept: Vec<u32> = a.lights.iter().map(|l| l.light).collect();
        assert_eq!(kept, ranked[..kept.len()]);
        assert!(a.used_texels <= 2048 * 2048);
        check_packing(&a, 2048);
    }
}
