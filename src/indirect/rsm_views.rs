//! Where each indirect light's reflective-shadow-map views go: one tile for a spot light
//! of at most 60° half-angle, six cube faces otherwise, in scene order on a grid of
//! tiles over the atlas. The views do not depend on the camera, so both the map pass
//! and the spawn pass compute the same layout from the scene, and again from the lights
//! of every light update (`PreparedFrame::update_lights`).

use crate::scene::{Light, LightShape, Scene, VplControls};
use glam::{Mat4, Vec3};
use std::collections::BTreeMap;

/// One view of one light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RsmView {
    pub light: u32,
    pub(crate) view_proj: Mat4,
    /// Texel origin of its tile in the atlas.
    pub(crate) x: u32,
    pub(crate) y: u32,
    /// Solid angle of a texel on the view's axis (steradians).
    pub(crate) texel_solid_angle: f32,
    pub axis: Vec3,
    pub(crate) controls: VplControls,
    /// Index of its first VPL candidate (n² candidates a view).
    pub(crate) first_candidate: u32,
}

/// An indirect light that got no views, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct DroppedRsmLight {
    /// The light's index in the scene.
    pub light: u32,
    /// Why it got none (past `max_lights`, no room left, or its VPL `n` does not divide
    /// the tile).
    pub(crate) reason: String,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct RsmLayout {
    pub(crate) views: Vec<RsmView>,
    pub(crate) dropped: Vec<DroppedRsmLight>,
    /// n² summed over the views: VPL candidates a frame.
    pub(crate) candidates: u32,
    /// Indirect lights with views.
    pub lights: u32,
}

/// Cube faces: (forward, up) of each.
const FACES: [(Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::NEG_Y),
    (Vec3::NEG_X, Vec3::NEG_Y),
    (Vec3::Y, Vec3::Z),
    (Vec3::NEG_Y, Vec3::NEG_Z),
    (Vec3::Z, Vec3::NEG_Y),
    (Vec3::NEG_Z, Vec3::NEG_Y),
];

/// Views of one light: (view-projection, axis, tan of the half field of view).
pub(crate) fn light_views(l: &Light) -> Vec<(Mat4, Vec3, f32)> {
    let near = (l.range * 1e-3).max(1e-4);
    let view = |dir: Vec3, up: Vec3, half: f32| {
        let up = if dir.cross(up).length_squared() < 1e-6 {
            dir.any_orthonormal_vector()
        } else {
            up
        };
        let v = Mat4::look_at_rh(l.position, l.position + dir, up);
        let p = Mat4::perspective_rh(2.0 * half, 1.0, near, l.range);
        (p * v, dir, half.tan())
    };
    match l.shape {
        LightShape::Spot {
            direction,
            outer_angle,
            ..
        } if outer_angle <= 60f32.to_radians() => {
            vec![view(
                direction.normalize_or_zero(),
                Vec3::Y,
                outer_angle.max(1e-3),
            )]
        }
        _ => FACES
            .iter()
            .map(|&(d, up)| view(d, up, std::f32::consts::FRAC_PI_4))
            .collect(),
    }
}

/// Lays out the views of every indirect light of `scene` on `tile`-texel tiles of a
/// `width`×`height` atlas, at most `max_lights` lights; a light whose views do not fit,
/// or whose n does not divide the tile, is dropped with its reason.
pub(crate) fn layout(
    scene: &Scene,
    tile: u32,
    width: u32,
    height: u32,
    max_lights: u32,
) -> RsmLayout {
    layout_lights(
        &scene.lights,
        &scene.vpl_controls,
        tile,
        width,
        height,
        max_lights,
    )
}

/// [`layout`] for `lights` with the VPL controls of each light index (`Scene::vpl_controls`;
/// a light not in it gets the defaults, as in [`Scene::vpl`]).
pub(crate) fn layout_lights(
    lights: &[Light],
    controls_of: &BTreeMap<u32, VplControls>,
    tile: u32,
    width: u32,
    height: u32,
    max_lights: u32,
) -> RsmLayout {
    let cols = width / tile.max(1);
    let cells = cols * (height / tile.max(1));
    let mut out = RsmLayout::default();
    for (i, l) in lights.iter().enumerate() {
        if l.flags & crate::scene::light_flags::INDIRECT == 0 {
            continue;
        }
        let controls = controls_of.get(&(i as u32)).copied().unwrap_or_default();
        let views = light_views(l);
        let drop = |reason: String| DroppedRsmLight {
            light: i as u32,
            reason,
        };
        if controls.n == 0 || controls.n > tile || !tile.is_multiple_of(controls.n) {
            out.dropped.push(drop(format!(
                "vpl n {} does not divide the {tile}-texel RSM tile",
                controls.n
            )));
            continue;
        }
        if out.lights >= max_lights {
            out.dropped.push(drop(format!(
                "over max_lights {max_lights} indirect lights"
            )));
            continue;
        }
        if out.views.len() + views.len() > cells as usize {
            out.dropped.push(drop(format!(
                "the atlas's {cells} tiles are full ({} views wanted)",
                views.len()
            )));
            continue;
        }
        out.lights += 1;
        for (view_proj, axis, tan_half) in views {
            let cell = out.views.len() as u32;
            let side = 2.0 * tan_half / tile as f32;
            out.views.push(RsmView {
                light: i as u32,
                view_proj,
                x: (cell % cols) * tile,
                y: (cell / cols) * tile,
                texel_solid_angle: side * side,
                axis,
                controls,
                first_candidate: out.candidates,
            });
            out.candidates += controls.n * controls.n;
        }
    }
    out
}

/// The view table the map and spawn shaders read (`VIEW_VEC4S` vec4 a view after a
/// header of (views, tile, width, height)), as u32 words.
pub(crate) fn view_table(
    layout: &RsmLayout,
    tile: u32,
    width: u32,
    height: u32,
    max_views: u64,
) -> Vec<[u32; 4]> {
    use crate::graph::kinds::reflective_shadow_maps::VIEW_VEC4S;
    let mut t = vec![[0u32; 4]; 1 + (VIEW_VEC4S * max_views) as usize];
    t[0] = [layout.views.len() as u32, tile, width, height];
    for (v, view) in layout.views.iter().take(max_views as usize).enumerate() {
        let b = 1 + VIEW_VEC4S as usize * v;
        for (c, col) in view.view_proj.to_cols_array_2d().iter().enumerate() {
            t[b + c] = col.map(f32::to_bits);
        }
        t[b + 4] = [view.x, view.y, view.light, view.controls.n];
        let c = &view.controls;
        t[b + 5] = [view.texel_solid_angle, c.intensity, c.range, c.clamp].map(f32::to_bits);
        t[b + 6] = [0.0f32; 4].map(f32::to_bits);
        t[b + 7] = [view.axis.x, view.axis.y, view.axis.z, 0.0].map(f32::to_bits);
        t[b + 7][3] = view.first_candidate;
        t[b + 6][3] = c.material_mask;
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::light_flags::INDIRECT;

    fn scene(lights: &[(LightShape, u32)]) -> Scene {
        let mut s = Scene::default();
        for (i, (shape, n)) in lights.iter().enumerate() {
            let mut l = Light::point(Vec3::ZERO, 5.0, Vec3::ONE, 1.0);
            l.shape = *shape;
            l.flags = INDIRECT;
            s.lights.push(l);
            s.vpl_controls.insert(
                i as u32,
                VplControls {
                    n: *n,
                    ..Default::default()
                },
            );
        }
        // A light that is not indirect gets no views.
        s.lights.push(Light::point(Vec3::ONE, 5.0, Vec3::ONE, 1.0));
        s
    }

    const SPOT: LightShape = LightShape::Spot {
        direction: Vec3::NEG_Y,
        inner_angle: 0.3,
        outer_angle: 0.6,
    };

    #[test]
    fn spots_take_one_tile_points_six_and_a_full_atlas_drops_with_its_reason() {
        // 64×64 of 32-texel tiles: four tiles.
        let s = scene(&[(SPOT, 8), (LightShape::Point, 4), (SPOT, 2), (SPOT, 32)]);
        let l = layout(&s, 32, 64, 64, 64);
        // The spot fits, the point light's six views do not, the next spots fill the rest.
        assert_eq!(
            l.views.iter().map(|v| v.light).collect::<Vec<_>>(),
            [0, 2, 3]
        );
        assert_eq!(l.dropped.len(), 1);
        assert_eq!(l.dropped[0].light, 1);
        assert!(
            l.dropped[0]
                .reason
                .contains("tiles are full (6 views wanted)"),
            "{:?}",
            l.dropped
        );
        assert_eq!(l.candidates, 64 + 4 + 1024);
        assert_eq!(l.views[1].first_candidate, 64);
        assert_eq!(
            (l.views[1].x, l.views[1].y, l.views[2].x, l.views[2].y),
            (32, 0, 0, 32)
        );
        let l = layout(&s, 32, 512, 512, 1);
        assert_eq!(l.lights, 1);
        assert!(l.dropped.iter().all(|d| d.reason.contains("max_lights 1")));
        let l = layout(&s, 16, 512, 512, 64);
        assert!(l
            .dropped
            .iter()
            .any(|d| d.light == 3 && d.reason.contains("does not divide")));
    }

    #[test]
    fn a_point_lights_six_faces_cover_every_direction_once() {
        let l = Light::point(Vec3::new(1.0, 2.0, 3.0), 10.0, Vec3::ONE, 1.0);
        let views = light_views(&l);
        assert_eq!(views.len(), 6);
        for d in [
            Vec3::X,
            Vec3::new(0.3, -0.9, 0.2).normalize(),
            Vec3::new(-0.5, 0.5, 0.7).normalize(),
        ] {
            let inside = views
                .iter()
                .filter(|(vp, _, _)| {
                    let c = *vp * (l.position + d * 2.0).extend(1.0);
                    let n = c.truncate() / c.w;
                    c.w > 0.0 && n.x.abs() <= 1.0 && n.y.abs() <= 1.0 && (0.0..=1.0).contains(&n.z)
                })
                .count();
            assert!(inside >= 1, "{d} seen by {inside} faces");
        }
    }
}
