//! Cheaper VPLs (VplSpawn's `merge`, `min_flux`, `redistribute`) and the disc falloff
//! (`falloff: Disc`): what each keeps and what it may change. On lavapipe, at small sizes.

mod common;

use common::{prepare_text, renderer};
use glam::Vec3;
use lightgraph::render::{FrameResult, PreparedFrame, Renderer, VplReport};
use lightgraph::scene::{self, Scene};
use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// graphs/indirect_vpl.ron with `params` added to its VplSpawn.
fn graph(params: &str) -> String {
    let text = std::fs::read_to_string(root().join("graphs/indirect_vpl.ron")).unwrap();
    let shipped = "VplSpawn(max_vpls: 16384)";
    assert!(text.contains(shipped));
    text.replace(shipped, &format!("VplSpawn(max_vpls: 16384, {params})"))
}

fn cornell(n: u32) -> Scene {
    let mut s = scene::load(&root().join("scenes/cornell_indirect.ron"))
        .expect("cornell_indirect loads")
        .scene;
    for c in s.vpl_controls.values_mut() {
        c.n = n;
    }
    s
}

fn render(r: &mut Renderer, text: &str, s: &Scene, w: u32, h: u32) -> (PreparedFrame, FrameResult) {
    let prepared = prepare_text(r, text, s, w, h, false).expect("prepare");
    let result = prepared.render(r).expect("render");
    (prepared, result)
}

/// The VPLs a frame spawned, as (flux, disc_sq): colour × π (VplSpawn writes Φ/π ×
/// the light's VPL intensity, 1 here) and the disc's squared radius.
fn vpls(r: &Renderer, f: &PreparedFrame, s: &Scene, v: &VplReport) -> Vec<(Vec3, f32)> {
    let props = f.read_buffer(r, "light_properties").unwrap();
    let words: &[f32] = bytemuck::cast_slice(&props);
    let base = s.lights.len();
    (base..base + v.spawned as usize)
        .map(|i| {
            let c = &words[8 * i..8 * i + 8];
            (Vec3::new(c[0], c[1], c[2]) * std::f32::consts::PI, c[7])
        })
        .collect()
}

fn luma(c: Vec3) -> f64 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722)) as f64
}

#[test]
fn merged_vpls_carry_the_same_total_flux_in_fewer_lights() {
    let (w, h) = (48, 36);
    let s = cornell(8);
    let mut r = renderer();
    let (fa, a) = render(&mut r, &graph("merge: 1"), &s, w, h);
    let (fm, m) = render(&mut r, &graph("merge: 2, merge_cos: 0.9"), &s, w, h);
    let (va, vm) = (&a.vpls[0], &m.vpls[0]);
    assert_eq!(va.merged, 0);
    assert!(vm.merged > 0, "{vm:?}");
    // Every merged candidate is one VPL fewer; merging drops none.
    assert_eq!(vm.spawned + vm.merged, va.spawned, "{vm:?} against {va:?}");
    // The Cornell box's walls are flat: most 2×2 groups face alike and merge.
    assert!(vm.spawned < va.spawned * 2 / 3, "{vm:?}");
    let total = |v: &[(Vec3, f32)]| v.iter().fold(Vec3::ZERO, |t, x| t + x.0);
    let (ta, tm) = (total(&vpls(&r, &fa, &s, va)), total(&vpls(&r, &fm, &s, vm)));
    // f32 sums of a few hundred terms in another order: 1e-5 relative.
    for c in 0..3 {
        let rel = ((tm[c] - ta[c]) / ta[c]).abs();
        assert!(
            rel < 1e-5,
            "channel {c}: merged {tm} against {ta} (rel {rel})"
        );
    }
    // With merge_cos 1, only groups whose normals are exactly alike merge: fewer merge.
    let (_, strict) = render(&mut r, &graph("merge: 2, merge_cos: 1.0"), &s, w, h);
    assert!(strict.vpls[0].merged < vm.merged, "{:?}", strict.vpls[0]);
}

#[test]
fn negligible_vpls_are_dropped_counted_and_change_the_image_within_their_flux_bound() {
    let (w, h) = (48, 36);
    let s = cornell(8);
    let min_flux = 2e-3;
    let mut r = renderer();
    let (fa, a) = render(&mut r, &graph("min_flux: 0.0"), &s, w, h);
    let (fd, d) = render(&mut r, &graph(&format!("min_flux: {min_flux}")), &s, w, h);
    let (va, vd) = (&a.vpls[0], &d.vpls[0]);
    // The CPU's count from the full frame's VPLs: under min_flux of their total.
    let every = vpls(&r, &fa, &s, va);
    let total: f64 = every.iter().map(|v| luma(v.0)).sum();
    let floor = min_flux * total;
    let small: Vec<f64> = every
        .iter()
        .map(|v| luma(v.0))
        .filter(|&l| l <= floor)
        .collect();
    assert!(
        !small.is_empty() && small.len() < every.len() / 2,
        "{}",
        small.len()
    );
    assert_eq!(vd.negligible as usize, small.len(), "{vd:?}");
    assert_eq!(vd.spawned as usize, every.len() - small.len());
    // The survivors are exactly the VPLs over the floor.
    let sorted = |mut l: Vec<f64>| {
        l.sort_by(f64::total_cmp);
        l
    };
    let over = sorted(
        every
            .iter()
            .map(|v| luma(v.0))
            .filter(|&l| l > floor)
            .collect(),
    );
    let kept = sorted(vpls(&r, &fd, &s, vd).iter().map(|v| luma(v.0)).collect());
    assert_eq!(kept, over);
    // With a full room as well, the room's selection runs over the rest: the brightest
    // `room` of those over the floor stay, the others count as dropped for room.
    let room = 40;
    let text = graph(&format!("min_flux: {min_flux}"))
        .replace("max_vpls: 16384", &format!("max_vpls: {room}"));
    let (ff, full) = render(&mut r, &text, &s, w, h);
    let vf = &full.vpls[0];
    assert!(over.len() > room, "{}", over.len());
    assert_eq!(vf.negligible as usize, small.len());
    assert_eq!(vf.dropped as usize, over.len() - room, "{vf:?}");
    let brightest = sorted(vpls(&r, &ff, &s, vf).iter().map(|v| luma(v.0)).collect());
    assert_eq!(brightest, over[over.len() - room..].to_vec());
    let lost: f64 = small.iter().sum();
    assert!(
        ((vd.negligible_flux as f64 - lost) / lost).abs() < 1e-4,
        "reported {} against {lost}",
        vd.negligible_flux
    );
    assert!(((vd.total_flux as f64 - total) / total).abs() < 1e-5);
    // Each dropped VPL adds at most Φ/π · 1/clamp² of radiance to a point, and a
    // Lambertian receiver (every material here) returns at most 1/π of it: a pixel's
    // luminance changes by at most the dropped luminance / (π² clamp²).
    let clamp = s.vpl(0).clamp as f64;
    let bound = lost / (std::f64::consts::PI.powi(2) * clamp * clamp);
    let worst = a
        .image
        .iter()
        .zip(&d.image)
        .map(|(x, y)| luma(Vec3::new(x[0] - y[0], x[1] - y[1], x[2] - y[2])).abs())
        .fold(0.0, f64::max);
    assert!(worst > 0.0, "dropping VPLs changed nothing");
    assert!(
        worst <= bound,
        "a pixel changed by {worst}; the bound is {bound}"
    );
    // Redistributed: the kept VPLs carry the whole flux again.
    let (fr, rd) = render(
        &mut r,
        &graph(&format!("min_flux: {min_flux}, redistribute: true")),
        &s,
        w,
        h,
    );
    let kept: f64 = vpls(&r, &fr, &s, &rd.vpls[0])
        .iter()
        .map(|v| luma(v.0))
        .sum();
    assert!(
        ((kept - total) / total).abs() < 1e-5,
        "{kept} against {total}"
    );
    assert!(rd.vpls[0]
        .lines()
        .iter()
        .any(|l| l.contains("redistributed")));
}

/// A floor and one indirect spot light straight above it whose whole map lands on it.
fn spot_over_floor(height: f32, outer: f32) -> Scene {
    spot_over_step(height, outer, 0.0)
}

/// `spot_over_floor` with the floor's x > 0 half `step` lower: the step runs under the
/// light, along the map's middle column.
fn spot_over_step(height: f32, outer: f32, step: f32) -> Scene {
    use lightgraph::scene::{light_flags, Camera, Light, LightShape, VplControls};
    let upper = common::cuboid(
        "upper",
        Vec3::new(-20.0, -1.0, -20.0),
        Vec3::new(0.0, 0.0, 20.0),
        0,
        false,
    );
    let lower = common::cuboid(
        "lower",
        Vec3::new(0.0, -1.0 - step, -20.0),
        Vec3::new(20.0, -step, 20.0),
        0,
        false,
    );
    let mut spot = Light::point(Vec3::new(0.0, height, 0.0), 30.0, Vec3::ONE, 4.0);
    spot.shape = LightShape::Spot {
        direction: -Vec3::Y,
        inner_angle: outer * 0.5,
        outer_angle: outer,
    };
    spot.flags = light_flags::INDIRECT;
    let mut s = Scene {
        name: "spot_over_step".into(),
        meshes: vec![upper, lower],
        materials: vec![common::lambert("white", Vec3::splat(0.8))],
        lights: vec![spot],
        camera: Camera {
            eye: Vec3::new(0.0, 3.0, 6.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y: 60f32.to_radians(),
            near: 0.05,
            far: 50.0,
        },
        ..Default::default()
    };
    s.vpl_controls.insert(
        0,
        VplControls {
            range: 30.0,
            n: 8,
            ..Default::default()
        },
    );
    s
}

#[test]
fn a_disc_vpl_covers_the_floor_area_its_map_texels_see() {
    let (height, outer) = (2.5f32, 40f32.to_radians());
    let s = spot_over_floor(height, outer);
    let mut r = renderer();
    let (f, res) = render(&mut r, &graph("falloff: Disc"), &s, 32, 24);
    let v = &res.vpls[0];
    // The corner blocks of the square map lie outside the round cone and spawn nothing.
    assert!(v.spawned > 40 && v.spawned <= 64, "{v:?}");
    // On a floor facing the light's axis, every map texel covers the same square:
    // (height × 2 tan(half angle) / tile)², whatever the texel's angle. The map's tile is
    // the graph's 32.
    let texel = height * 2.0 * outer.tan() / 32.0;
    let lit = f
        .read_texture(&r, "rsm_flux")
        .unwrap()
        .iter()
        .filter(|t| luma(Vec3::new(t[0], t[1], t[2])) > 0.0)
        .count();
    let expected = lit as f64 * (texel * texel) as f64;
    let discs: f64 = vpls(&r, &f, &s, v)
        .iter()
        .map(|x| std::f64::consts::PI * x.1 as f64)
        .sum();
    // f32 positions from the rasterizer and sums of 16 texels a VPL: 1e-4 relative.
    assert!(
        ((discs - expected) / expected).abs() < 1e-4,
        "the discs cover {discs} m², the {lit} lit texels {expected} m²"
    );
    // AreaClamp: the clamp (in cos_inner) grows to the disc's radius; no disc is added.
    let (fc, resc) = render(&mut r, &graph("falloff: AreaClamp"), &s, 32, 24);
    let props = fc.read_buffer(&r, "light_properties").unwrap();
    let words: &[f32] = bytemuck::cast_slice(&props);
    let base = s.lights.len();
    let clamp = s.vpl(0).clamp;
    let discs = vpls(&r, &f, &s, v);
    assert_eq!(resc.vpls[0].spawned, v.spawned);
    for (k, i) in (base..base + v.spawned as usize).enumerate() {
        assert_eq!(words[8 * i + 7], 0.0);
        let want = clamp.max(discs[k].1.sqrt());
        assert!(
            (words[8 * i + 3] - want).abs() <= 1e-6 * want,
            "VPL {k}: clamp {} against {want}",
            words[8 * i + 3]
        );
    }
    // Clamp (the default) leaves every VPL a point.
    let (f, res) = render(&mut r, &graph("falloff: Clamp"), &s, 32, 24);
    assert!(vpls(&r, &f, &s, &res.vpls[0]).iter().all(|x| x.1 == 0.0));
}

#[test]
fn parallel_surfaces_at_different_depths_do_not_merge() {
    let (height, outer) = (2.5f32, 40f32.to_radians());
    let mut r = renderer();
    // n = 2 and merge: 2: each view's four VPLs form one group, two on either side of
    // the step. With merge_cos 0.99 the plane bound is the group's disc radius (about
    // 2.5 m here) × tan(acos 0.99) = 0.14: about 0.36 m.
    let merged = |r: &mut Renderer, step: f32| {
        let mut s = spot_over_step(height, outer, step);
        s.vpl_controls.get_mut(&0).unwrap().n = 2;
        let (_, res) = render(r, &graph("merge: 2, merge_cos: 0.99"), &s, 32, 24);
        res.vpls[0].clone()
    };
    let flat = merged(&mut r, 0.0);
    assert_eq!((flat.spawned, flat.merged), (1, 3), "{flat:?}");
    // A 1 m step puts each member 0.5 m off the group's plane: nothing merges.
    let stepped = merged(&mut r, 1.0);
    assert_eq!((stepped.spawned, stepped.merged), (4, 0), "{stepped:?}");
}
