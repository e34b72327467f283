//! Property tests on the CPU twin of the culling shader: a light that reaches any point
//! of a tile between the tile's depth bounds is never culled, for the frustum test, the
//! spot-cone test and the 2.5D depth mask.

use glam::{Mat4, Vec2, Vec3};
use lightgraph::cull::*;
use proptest::prelude::*;

const W: f32 = 333.0;
const H: f32 = 197.0;
const TILE: f32 = 16.0;

fn setup() -> Mat4 {
    Mat4::perspective_rh(60f32.to_radians(), W / H, 0.1, 100.0).inverse()
}

/// A view-space point inside pixel rectangle of tile (tx, ty) at view depth z.
fn point_in_tile(inv: Mat4, tx: u32, ty: u32, u: f32, v: f32, z: f32) -> Vec3 {
    let x = (tx as f32 * TILE + u * TILE).min(W - 1e-3);
    let y = (ty as f32 * TILE + v * TILE).min(H - 1e-3);
    let ray = view_ray(inv, Vec2::new(W, H), Vec2::new(x, y));
    ray * (z / -ray.z)
}

fn tile(inv: Mat4, tx: u32, ty: u32) -> TileFrustum {
    let x0 = tx as f32 * TILE;
    let y0 = ty as f32 * TILE;
    tile_frustum(
        inv,
        Vec2::new(W, H),
        x0,
        y0,
        (x0 + TILE).min(W),
        (y0 + TILE).min(H),
    )
}

prop_compose! {
    fn light()(
        near in prop::bool::ANY,
        pos in (-1.0f32..1.0, -1.0f32..1.0, 0.05f32..1.0),
        range in prop_oneof![0.001f32..0.1, 0.1f32..5.0, 5.0f32..500.0],
        spot in prop::bool::ANY,
        dir in (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
        outer in 0.01f32..std::f32::consts::FRAC_PI_2,
    ) -> ViewLight {
        // Positions around the frustum, some near or behind the camera.
        let depth = if near { pos.2 * 2.0 - 1.0 } else { pos.2 * 60.0 };
        let position = Vec3::new(pos.0 * depth.abs().max(1.0), pos.1 * depth.abs().max(1.0), -depth);
        let direction = Vec3::new(dir.0, dir.1, dir.2).try_normalize().unwrap_or(Vec3::NEG_Z);
        ViewLight { position, range, direction, cos_outer: if spot { outer.cos() } else { -1.0 } }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4000))]

    #[test]
    fn a_reaching_light_is_never_culled(
        l in light(),
        tx in 0u32..21, ty in 0u32..13,
        lo in 0.1f32..50.0, span in 0.0f32..50.0,
        samples in prop::collection::vec((0.0f32..1.0, 0.0f32..1.0, 0.0f32..1.0), 64),
    ) {
        let inv = setup();
        let hi = lo + span;
        let t = tile(inv, tx, ty);
        for (u, v, s) in samples {
            let z = lo + (hi - lo) * s;
            let p = point_in_tile(inv, tx, ty, u, v, z);
            if reaches(&l, p) {
                prop_assert!(light_touches_tile(&l, &t, lo, hi, None),
                    "culled a light reaching {p:?} (tile {tx},{ty}, depth {lo}..{hi}): {l:?}");
                // With a 2.5D mask holding the cell of this very point.
                let mask = 1u32 << cell_of(z, lo, hi);
                prop_assert!(light_touches_tile(&l, &t, lo, hi, Some((mask, lo, hi))),
                    "depth mask culled a light reaching {p:?}: {l:?}");
            }
        }
    }

    #[test]
    fn spot_bounding_sphere_contains_the_cone(
        l in light(),
        dirs in prop::collection::vec((-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0, 0.0f32..1.0), 64),
    ) {
        let (c, r) = light_sphere(&l);
        for (x, y, z, t) in dirs {
            let d = Vec3::new(x, y, z).try_normalize().unwrap_or(l.direction);
            let p = l.position + d * (l.range * t);
            if reaches(&l, p) {
                prop_assert!(p.distance(c) <= r * 1.0001 + 1e-5, "{p:?} outside sphere ({c:?}, {r})");
            }
        }
    }
}

#[test]
fn cells_between_covers_exactly_the_range() {
    assert_eq!(cells_between(0, 31), u32::MAX);
    assert_eq!(cells_between(3, 3), 1 << 3);
    assert_eq!(cells_between(30, 31), 0xC000_0000);
}

#[test]
fn far_lights_and_lights_behind_are_culled() {
    // The property tests only check one direction; culling must also cull.
    let inv = setup();
    let t = tile(inv, 10, 6);
    let behind = ViewLight {
        position: Vec3::new(0.0, 0.0, 5.0),
        range: 1.0,
        direction: Vec3::Z,
        cos_outer: -1.0,
    };
    assert!(!light_touches_tile(&behind, &t, 1.0, 10.0, None));
    let beyond = ViewLight {
        position: Vec3::new(0.0, 0.0, -30.0),
        range: 1.0,
        direction: Vec3::Z,
        cos_outer: -1.0,
    };
    assert!(!light_touches_tile(&beyond, &t, 1.0, 10.0, None));
    // A spot in the tile's depth range pointing away from it.
    let away = ViewLight {
        position: Vec3::new(0.0, 0.0, -5.0),
        range: 3.0,
        direction: Vec3::Z,
        cos_outer: 0.95,
    };
    assert!(!light_touches_tile(&away, &t, 5.5, 10.0, None));
}
