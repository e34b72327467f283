//! Built-in procedural scenes: `atrium` (the default scene), `harada` and
//! `depth_discontinuity` (for the Forward+ work). Deterministic: same scene every run.

use super::geometry::MeshBuilder;
use super::lights::{Pcg32, Placement, RandomLights};
use super::types::{Camera, Scene, SurfaceMaterial};
use glam::{Quat, Vec2, Vec3};

/// Names accepted by [`by_name`] (and by `builtin:` in a scene RON).
pub const NAMES: &[&str] = &["atrium", "harada", "depth_discontinuity", "chairs", "glass"];

/// A built-in scene by name.
pub fn by_name(name: &str) -> Option<Scene> {
    match name {
        "atrium" => Some(atrium()),
        "harada" => Some(harada()),
        "depth_discontinuity" => Some(depth_discontinuity()),
        "chairs" => Some(super::builtin_chairs::chairs()),
        "glass" => Some(super::builtin_glass::glass_scene()),
        _ => None,
    }
}

fn material(
    name: &str,
    rgb: Vec3,
    roughness: f32,
    metallic: f32,
    type_bit: u32,
) -> SurfaceMaterial {
    SurfaceMaterial {
        name: name.into(),
        base_color: rgb.extend(1.0),
        roughness,
        metallic,
        type_bit,
        ..Default::default()
    }
}

/// Material type bits of the built-in scenes (for light material masks).
pub mod type_bits {
    pub(crate) const FLOOR: u32 = 1;
    pub(crate) const STONE: u32 = 2;
    pub(crate) const METAL: u32 = 4;
    pub(crate) const WALL: u32 = 8;
}

/// A subdivided horizontal floor (y = `y`) over `min..max` in x/z, facing +Y.
fn floor(b: &mut MeshBuilder, min: Vec2, max: Vec2, y: f32, cells: u32) {
    let step = (max - min) / cells as f32;
    for i in 0..cells {
        for j in 0..cells {
            let o = Vec3::new(min.x + step.x * i as f32, y, min.y + step.y * j as f32);
            b.quad(o, Vec3::Z * step.y, Vec3::X * step.x, step);
        }
    }
}

/// A classical column: plinth, shaft, capital.
fn column(b: &mut MeshBuilder, base: Vec3, radius: f32, height: f32, segments: u32) {
    let plinth = radius * 1.4;
    b.cuboid(
        base + Vec3::new(-plinth, 0.0, -plinth),
        base + Vec3::new(plinth, radius * 0.6, plinth),
    );
    b.cylinder(
        base + Vec3::Y * radius * 0.6,
        radius,
        height - radius * 1.2,
        segments,
        6,
    );
    b.cuboid(
        base + Vec3::new(-plinth, height - radius * 0.6, -plinth),
        base + Vec3::new(plinth, height, plinth),
    );
}

/// The default scene: a two-storey atrium. A floor of 40 × 30 m, walls, two colonnades of
/// nine columns carrying arches, an upper gallery with a balustrade, a second order of
/// columns and arches, and a stepped monument and crates on the floor for depth variation.
/// 1,024 lights (half point, half spot) fill the hall; the camera looks down the length of the
/// colonnade so depth varies strongly across the image.
pub fn atrium() -> Scene {
    use type_bits::*;
    let materials = vec![
        material(
            "atrium_floor",
            Vec3::new(0.55, 0.52, 0.48),
            0.35,
            0.0,
            FLOOR,
        ),
        material("atrium_stone", Vec3::new(0.75, 0.72, 0.66), 0.6, 0.0, STONE),
        material("atrium_bronze", Vec3::new(0.8, 0.5, 0.25), 0.3, 1.0, METAL),
        material("atrium_wall", Vec3::new(0.6, 0.35, 0.3), 0.8, 0.0, WALL),
    ];
    let (hx, hz, h) = (20.0f32, 15.0f32, 16.0f32);

    let mut fl = MeshBuilder::new("atrium/floor", 0);
    floor(&mut fl, Vec2::new(-hx, -hz), Vec2::new(hx, hz), 0.0, 24);

    let mut walls = MeshBuilder::new("atrium/walls", 3);
    // Inward-facing walls.
    walls.inward_walls(hx, hz, h, Vec2::new(8.0, 4.0), Vec2::new(6.0, 4.0));

    let mut stone = MeshBuilder::new("atrium/colonnade", 1);
    let (col_h, gallery_y, upper_h) = (6.0f32, 8.4f32, 4.0f32);
    for side in [-1.0f32, 1.0] {
        let z = side * 8.0;
        for i in 0..9 {
            let x = -16.0 + 4.0 * i as f32;
            column(&mut stone, Vec3::new(x, 0.0, z), 0.5, col_h, 24);
            column(&mut stone, Vec3::new(x, gallery_y, z), 0.3, upper_h, 16);
            if i < 8 {
                let c = Vec3::new(x + 2.0, col_h, z);
                stone.arch(c, Vec3::X, 1.3, 2.0, 1.2, 16);
                let c = Vec3::new(x + 2.0, gallery_y + upper_h, z);
                stone.arch(c, Vec3::X, 1.6, 2.0, 0.7, 12);
            }
        }
        // Gallery slab from the colonnade to the wall, at the springing + arch height.
        let (z0, z1) = if side < 0.0 { (-hz, -7.0) } else { (7.0, hz) };
        stone.cuboid(
            Vec3::new(-hx, gallery_y - 0.4, z0),
            Vec3::new(hx, gallery_y, z1),
        );
        // Entablature over the lower arches.
        stone.cuboid(
            Vec3::new(-17.0, col_h + 2.0, z - 0.6),
            Vec3::new(17.0, gallery_y - 0.4, z + 0.6),
        );
        // Upper cornice.
        stone.cuboid(
            Vec3::new(-17.0, gallery_y + upper_h + 2.0, z - 0.4),
            Vec3::new(17.0, gallery_y + upper_h + 2.5, z + 0.4),
        );
    }

    let mut metal = MeshBuilder::new("atrium/balustrade_and_monument", 2);
    for side in [-1.0f32, 1.0] {
        let z = side * 7.2;
        for i in 0..=68 {
            let x = -17.0 + 0.5 * i as f32;
            metal.cuboid(
                Vec3::new(x - 0.04, gallery_y, z - 0.04),
                Vec3::new(x + 0.04, gallery_y + 1.0, z + 0.04),
            );
        }
        metal.cuboid(
            Vec3::new(-17.0, gallery_y + 1.0, z - 0.08),
            Vec3::new(17.0, gallery_y + 1.1, z + 0.08),
        );
    }
    // Stepped monument in the middle and scattered crates.
    for k in 0..6 {
        let r = 3.0 - 0.45 * k as f32;
        let y = 0.35 * k as f32;
        stone.cuboid(Vec3::new(-r, y, -r), Vec3::new(r, y + 0.35, r));
    }
    metal.cylinder(Vec3::new(0.0, 2.1, 0.0), 0.35, 3.5, 32, 8);
    let mut rng = Pcg32::new(0xa7_12_10);
    for _ in 0..40 {
        let p = rng.vec3_in(Vec3::new(-18.0, 0.0, -6.0), Vec3::new(18.0, 0.0, 6.0));
        if p.x.abs() < 4.0 && p.z.abs() < 4.0 {
            continue;
        }
        let s = rng.range(0.3, 0.9);
        let mut crate_b = MeshBuilder::new("crate", 0);
        crate_b.cuboid(Vec3::new(-s, 0.0, -s), Vec3::new(s, 2.0 * s, s));
        crate_b.transform(Quat::from_rotation_y(rng.range(0.0, 1.5)), p);
        append(&mut metal, crate_b);
    }

    let lights = RandomLights {
        count: 1024,
        spot_fraction: 0.5,
        placement: Placement::Box {
            min: Vec3::new(-19.0, 0.3, -14.0),
            max: Vec3::new(19.0, 15.0, 14.0),
        },
        range: (1.5, 4.0),
        intensity: (0.5, 3.0),
        color: (Vec3::splat(0.3), Vec3::ONE),
        spot_cone_deg: (20.0, 40.0),
        seed: 1024,
        casts_shadow: false,
        indirect: false,
        material_mask: u32::MAX,
        motion: None,
    }
    .generate(None);

    Scene {
        name: "atrium".into(),
        meshes: vec![fl.build(), walls.build(), stone.build(), metal.build()],
        materials,
        lights,
        camera: Camera {
            eye: Vec3::new(-18.0, 2.5, 11.0),
            target: Vec3::new(8.0, 5.0, -6.0),
            up: Vec3::Y,
            fov_y: 60f32.to_radians(),
            near: 0.1,
            far: 100.0,
        },
        output_size: Some((1920, 1080)),
        ambient: Vec3::ZERO,
        ..Default::default()
    }
}

fn append(dst: &mut MeshBuilder, src: MeshBuilder) {
    let base = dst.mesh.positions.len() as u32;
    let s = src.mesh;
    dst.mesh.positions.extend(s.positions);
    dst.mesh.normals.extend(s.normals);
    dst.mesh.uvs.extend(s.uvs);
    dst.mesh
        .indices
        .extend(s.indices.into_iter().map(|i| i + base));
}

/// In the spirit of Harada et al.'s Forward+ benchmark: a 40 × 40 m floor with a 12 × 12 grid
/// of boxes of random heights, 3,072 lights (two thirds point, one third spot) near the
/// ground, 1280×720.
pub fn harada() -> Scene {
    use type_bits::*;
    let materials = vec![
        material("harada_floor", Vec3::splat(0.5), 0.5, 0.0, FLOOR),
        material("harada_box", Vec3::new(0.7, 0.7, 0.75), 0.4, 0.0, STONE),
    ];
    let mut fl = MeshBuilder::new("harada/floor", 0);
    floor(&mut fl, Vec2::splat(-20.0), Vec2::splat(20.0), 0.0, 16);
    let mut boxes = MeshBuilder::new("harada/boxes", 1);
    let mut rng = Pcg32::new(3072);
    for i in 0..12 {
        for j in 0..12 {
            let c = Vec3::new(-16.5 + 3.0 * i as f32, 0.0, -16.5 + 3.0 * j as f32);
            let half = rng.range(0.4, 1.1);
            let height = rng.range(0.5, 4.0);
            boxes.cuboid(
                c - Vec3::new(half, 0.0, half),
                c + Vec3::new(half, height, half),
            );
        }
    }
    let lights = RandomLights {
        count: 3072,
        spot_fraction: 1.0 / 3.0,
        placement: Placement::Box {
            min: Vec3::new(-20.0, 0.1, -20.0),
            max: Vec3::new(20.0, 3.0, 20.0),
        },
        range: (1.0, 2.5),
        intensity: (0.3, 1.5),
        color: (Vec3::splat(0.2), Vec3::ONE),
        spot_cone_deg: (25.0, 45.0),
        seed: 2012,
        casts_shadow: false,
        indirect: false,
        material_mask: u32::MAX,
        motion: None,
    }
    .generate(None);
    Scene {
        name: "harada".into(),
        meshes: vec![fl.build(), boxes.build()],
        materials,
        lights,
        camera: Camera {
            eye: Vec3::new(0.0, 14.0, 26.0),
            target: Vec3::new(0.0, 0.0, -2.0),
            up: Vec3::Y,
            fov_y: 55f32.to_radians(),
            near: 0.5,
            far: 120.0,
        },
        output_size: Some((1280, 720)),
        ..Default::default()
    }
}

/// Near objects against a far background: pillars and boxes 2–8 m from the camera, a floor,
/// and a wall 60 m away; 2,048 lights spread through the whole depth range. Tiles on an object
/// edge span near and far depths, which is what 2.5D culling (and half-z) is for.
pub fn depth_discontinuity() -> Scene {
    use type_bits::*;
    let materials = vec![
        material("dd_floor", Vec3::splat(0.45), 0.6, 0.0, FLOOR),
        material("dd_wall", Vec3::new(0.6, 0.6, 0.65), 0.9, 0.0, WALL),
        material("dd_near", Vec3::new(0.8, 0.3, 0.2), 0.3, 0.0, STONE),
    ];
    let mut fl = MeshBuilder::new("dd/floor", 0);
    floor(
        &mut fl,
        Vec2::new(-30.0, -60.0),
        Vec2::new(30.0, 5.0),
        0.0,
        20,
    );
    let mut wall = MeshBuilder::new("dd/far_wall", 1);
    wall.quad(
        Vec3::new(-30.0, 0.0, -60.0),
        Vec3::X * 60.0,
        Vec3::Y * 30.0,
        Vec2::new(12.0, 6.0),
    );
    let mut near = MeshBuilder::new("dd/near_objects", 2);
    for (k, x) in [-3.0f32, -1.2, 0.8, 2.6].into_iter().enumerate() {
        let z = -2.5 - 1.5 * k as f32;
        near.cylinder(Vec3::new(x, 0.0, z), 0.25, 4.0, 32, 4);
    }
    near.cuboid(Vec3::new(-0.6, 0.0, -3.2), Vec3::new(0.2, 0.8, -2.4));
    near.cuboid(Vec3::new(1.5, 0.0, -8.0), Vec3::new(3.5, 2.5, -7.0));
    let lights = RandomLights {
        count: 2048,
        spot_fraction: 0.25,
        placement: Placement::Box {
            min: Vec3::new(-25.0, 0.2, -59.0),
            max: Vec3::new(25.0, 12.0, 0.0),
        },
        range: (1.0, 3.0),
        intensity: (0.5, 2.0),
        color: (Vec3::splat(0.2), Vec3::ONE),
        spot_cone_deg: (20.0, 35.0),
        seed: 4096,
        casts_shadow: false,
        indirect: false,
        material_mask: u32::MAX,
        motion: None,
    }
    .generate(None);
    Scene {
        name: "depth_discontinuity".into(),
        meshes: vec![fl.build(), wall.build(), near.build()],
        materials,
        lights,
        camera: Camera {
            eye: Vec3::new(0.0, 1.6, 3.0),
            target: Vec3::new(0.0, 2.0, -60.0),
            up: Vec3::Y,
            fov_y: 60f32.to_radians(),
            near: 0.1,
            far: 80.0,
        },
        output_size: Some((1280, 720)),
        ..Default::default()
    }
}
