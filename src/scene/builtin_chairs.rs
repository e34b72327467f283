//! The built-in `chairs` scene, in the spirit of the figure of AMD's Leo demo ray-cast
//! shadow work: a closed room with rows of tables and chairs (turned legs, spindle
//! backs), 512 shadow-casting point lights among them. About 289,000 triangles, most of
//! them in thin cylinders, so it stresses the shadow BVH build and any-hit traversal.
//! Deterministic: same scene every run.

use super::builtin::type_bits;
use super::geometry::MeshBuilder;
use super::lights::{Pcg32, Placement, RandomLights};
use super::types::{Camera, Scene, SurfaceMaterial};
use glam::{Quat, Vec2, Vec3};

/// Room half extents in x and z, and height (m).
const HALF_X: f32 = 15.0;
const HALF_Z: f32 = 10.0;
const HEIGHT: f32 = 5.0;
/// Table grid: columns along x, rows along z, and their spacing.
const COLUMNS: u32 = 8;
const ROWS: u32 = 6;
const STEP_X: f32 = 3.4;
const STEP_Z: f32 = 2.8;
/// Shadow-casting point lights.
pub(crate) const LIGHTS: u32 = 512;

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

/// Appends `src`'s geometry to `dst`.
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

/// A chair at the origin, seat centred on the y axis, facing -Z (the back at +Z):
/// four turned legs, a seat, two back posts, four spindles and a top rail.
/// 1,336 triangles.
fn chair(b: &mut MeshBuilder) {
    for (x, z) in [(-0.19, -0.19), (0.19, -0.19), (-0.19, 0.19), (0.19, 0.19)] {
        b.cylinder(Vec3::new(x, 0.0, z), 0.02, 0.43, 16, 5);
    }
    b.cuboid(
        Vec3::new(-0.225, 0.43, -0.225),
        Vec3::new(0.225, 0.47, 0.225),
    );
    for x in [-0.19, 0.19] {
        b.cylinder(Vec3::new(x, 0.47, 0.2), 0.018, 0.45, 16, 6);
    }
    for x in [-0.12, -0.04, 0.04, 0.12] {
        b.cylinder(Vec3::new(x, 0.47, 0.2), 0.01, 0.39, 12, 3);
    }
    b.cuboid(Vec3::new(-0.21, 0.86, 0.18), Vec3::new(0.21, 0.92, 0.22));
}

/// A 1.6 × 0.8 m table centred on the y axis, 0.76 m high. 652 triangles.
fn table(b: &mut MeshBuilder) {
    b.cuboid(Vec3::new(-0.8, 0.72, -0.4), Vec3::new(0.8, 0.76, 0.4));
    for (x, z) in [(-0.72, -0.32), (0.72, -0.32), (-0.72, 0.32), (0.72, 0.32)] {
        b.cylinder(Vec3::new(x, 0.0, z), 0.03, 0.72, 16, 5);
    }
}

/// The room: a subdivided floor, four inward walls and a ceiling.
fn room(floor: &mut MeshBuilder, walls: &mut MeshBuilder) {
    let cells = Vec2::new(30.0, 20.0);
    let step = Vec2::new(2.0 * HALF_X, 2.0 * HALF_Z) / cells;
    for i in 0..cells.x as u32 {
        for j in 0..cells.y as u32 {
            let o = Vec3::new(
                -HALF_X + step.x * i as f32,
                0.0,
                -HALF_Z + step.y * j as f32,
            );
            floor.quad(o, Vec3::Z * step.y, Vec3::X * step.x, step);
        }
    }
    let (hx, hz, h) = (HALF_X, HALF_Z, HEIGHT);
    walls
        .inward_walls(hx, hz, h, Vec2::new(6.0, 1.0), Vec2::new(4.0, 1.0))
        // Ceiling, facing down.
        .quad(
            Vec3::new(-hx, h, -hz),
            Vec3::X * 2.0 * hx,
            Vec3::Z * 2.0 * hz,
            Vec2::new(6.0, 4.0),
        );
}

/// A room of 30 × 20 × 5 m with 8 × 6 tables, four chairs at each (192 chairs, slightly
/// jittered), 512 shadow-casting point lights between floor and ceiling; 1280×720.
pub(crate) fn chairs() -> Scene {
    use type_bits::*;
    let materials = vec![
        material("chairs_floor", Vec3::new(0.5, 0.45, 0.4), 0.5, 0.0, FLOOR),
        material("chairs_wall", Vec3::new(0.7, 0.68, 0.62), 0.9, 0.0, WALL),
        material("chairs_table", Vec3::new(0.55, 0.35, 0.2), 0.45, 0.0, STONE),
        material("chairs_chair", Vec3::new(0.25, 0.3, 0.35), 0.35, 0.6, METAL),
    ];
    let mut fl = MeshBuilder::new("chairs/floor", 0);
    let mut walls = MeshBuilder::new("chairs/walls", 1);
    room(&mut fl, &mut walls);

    let mut tables = MeshBuilder::new("chairs/tables", 2);
    let mut seats = MeshBuilder::new("chairs/chairs", 3);
    let mut rng = Pcg32::new(0x00c4_a125);
    let x0 = -STEP_X * (COLUMNS - 1) as f32 * 0.5;
    let z0 = -STEP_Z * (ROWS - 1) as f32 * 0.5;
    for i in 0..COLUMNS {
        for j in 0..ROWS {
            let c = Vec3::new(x0 + STEP_X * i as f32, 0.0, z0 + STEP_Z * j as f32);
            let mut t = MeshBuilder::new("table", 2);
            table(&mut t);
            t.transform(Quat::IDENTITY, c);
            append(&mut tables, t);
            // Two chairs on each long side, facing the table.
            for side in [-1.0f32, 1.0] {
                for dx in [-0.4f32, 0.4] {
                    let jitter = Vec3::new(rng.range(-0.05, 0.05), 0.0, rng.range(0.0, 0.12));
                    let yaw = if side > 0.0 {
                        0.0
                    } else {
                        std::f32::consts::PI
                    } + rng.range(-0.12, 0.12);
                    let pos = c + Vec3::new(dx + jitter.x, 0.0, side * (0.62 + jitter.z));
                    let mut ch = MeshBuilder::new("chair", 3);
                    chair(&mut ch);
                    ch.transform(Quat::from_rotation_y(yaw), pos);
                    append(&mut seats, ch);
                }
            }
        }
    }

    let lights = RandomLights {
        count: LIGHTS,
        spot_fraction: 0.0,
        placement: Placement::Box {
            min: Vec3::new(-HALF_X + 0.5, 0.2, -HALF_Z + 0.5),
            max: Vec3::new(HALF_X - 0.5, HEIGHT - 0.5, HALF_Z - 0.5),
        },
        range: (2.0, 4.5),
        intensity: (0.5, 2.5),
        color: (Vec3::splat(0.35), Vec3::ONE),
        spot_cone_deg: (20.0, 35.0),
        seed: 512,
        casts_shadow: true,
        indirect: false,
        material_mask: u32::MAX,
        motion: None,
    }
    .generate(None);

    Scene {
        name: "chairs".into(),
        meshes: vec![fl.build(), walls.build(), tables.build(), seats.build()],
        materials,
        lights,
        camera: Camera {
            eye: Vec3::new(-13.5, 3.0, 8.5),
            target: Vec3::new(1.0, 0.5, -2.0),
            up: Vec3::Y,
            fov_y: 60f32.to_radians(),
            near: 0.1,
            far: 60.0,
        },
        output_size: Some((1280, 720)),
        ambient: Vec3::ZERO,
        ..Default::default()
    }
}
