//! The built-in `glass` scene, for transparency: a floor, a back wall and two boxes, with
//! tinted glass quads (glTF `alphaMode: BLEND`) in front of, between and behind the
//! boxes, one seen from its back face and one against the empty sky (no opaque surface
//! behind it); 48 lights spread through every layer. Deterministic: same scene every run.

use super::builtin::type_bits;
use super::geometry::MeshBuilder;
use super::lights::{Placement, RandomLights};
use super::types::{AlphaMode, Camera, Scene, SurfaceMaterial};
use glam::{Vec2, Vec3, Vec4};

/// Lights in the scene.
pub(crate) const LIGHTS: u32 = 48;

fn opaque(name: &str, rgb: Vec3, type_bit: u32) -> SurfaceMaterial {
    SurfaceMaterial {
        name: name.into(),
        base_color: rgb.extend(1.0),
        roughness: 0.7,
        type_bit,
        ..Default::default()
    }
}

fn glass(name: &str, rgba: Vec4) -> SurfaceMaterial {
    SurfaceMaterial {
        name: name.into(),
        base_color: rgba,
        roughness: 0.2,
        alpha_mode: AlphaMode::Blend,
        double_sided: true,
        type_bit: type_bits::STONE,
        ..Default::default()
    }
}

pub(crate) fn glass_scene() -> Scene {
    let materials = vec![
        opaque("glass/floor", Vec3::splat(0.5), type_bits::FLOOR),
        opaque("glass/wall", Vec3::new(0.6, 0.6, 0.65), type_bits::WALL),
        opaque("glass/box", Vec3::new(0.8, 0.4, 0.2), type_bits::METAL),
        glass("glass/blue", Vec4::new(0.3, 0.5, 0.9, 0.4)),
        glass("glass/green", Vec4::new(0.3, 0.9, 0.4, 0.5)),
        glass("glass/red", Vec4::new(0.9, 0.3, 0.3, 0.6)),
    ];
    let mut floor = MeshBuilder::new("glass/floor", 0);
    floor.quad(
        Vec3::new(-12.0, 0.0, 4.0),
        Vec3::X * 24.0,
        Vec3::NEG_Z * 34.0,
        Vec2::new(6.0, 8.0),
    );
    let mut wall = MeshBuilder::new("glass/back_wall", 1);
    // Only 5 m high: the top of the frame is empty sky behind the high quad.
    wall.quad(
        Vec3::new(-12.0, 0.0, -30.0),
        Vec3::X * 24.0,
        Vec3::Y * 5.0,
        Vec2::new(6.0, 2.0),
    );
    let mut near_box = MeshBuilder::new("glass/near_box", 2);
    near_box.cuboid(Vec3::new(-3.0, 0.0, -9.0), Vec3::new(-1.0, 2.5, -7.0));
    let mut far_box = MeshBuilder::new("glass/far_box", 2);
    far_box.cuboid(Vec3::new(1.0, 0.0, -19.0), Vec3::new(4.0, 3.5, -16.0));
    // (name, material, corner, u, v): u × v is the front face's normal.
    let quads = [
        // In front of everything, facing the camera.
        (
            "glass/front",
            3,
            Vec3::new(-2.5, 0.3, -4.0),
            Vec3::X * 3.5,
            Vec3::Y * 2.2,
        ),
        // Between the boxes, seen from its back face (normal away from the camera).
        (
            "glass/between",
            4,
            Vec3::new(2.0, 0.0, -12.0),
            Vec3::Y * 3.0,
            Vec3::X * 4.0,
        ),
        // Behind the far box, in front of the wall: partly hidden by the box.
        (
            "glass/behind",
            5,
            Vec3::new(-1.0, 0.5, -24.0),
            Vec3::X * 7.0,
            Vec3::Y * 3.5,
        ),
        // High up against the empty sky: no opaque surface behind it.
        (
            "glass/sky",
            3,
            Vec3::new(-6.0, 5.5, -20.0),
            Vec3::X * 6.0,
            Vec3::Y * 3.0,
        ),
        // Overlapping the front quad from behind, at an angle.
        (
            "glass/slant",
            4,
            Vec3::new(-1.0, 0.0, -6.5),
            Vec3::new(3.0, 0.0, 1.5),
            Vec3::Y * 2.8,
        ),
    ];
    let mut meshes = vec![
        floor.build(),
        wall.build(),
        near_box.build(),
        far_box.build(),
    ];
    for (name, material, o, u, v) in quads {
        let mut q = MeshBuilder::new(name, material);
        q.quad(o, u, v, Vec2::ONE);
        meshes.push(q.build());
    }
    let lights = RandomLights {
        count: LIGHTS,
        spot_fraction: 0.25,
        placement: Placement::Box {
            min: Vec3::new(-8.0, 0.2, -28.0),
            max: Vec3::new(8.0, 8.0, -2.0),
        },
        range: (1.5, 5.0),
        intensity: (4.0, 12.0),
        color: (Vec3::splat(0.3), Vec3::ONE),
        spot_cone_deg: (25.0, 45.0),
        seed: 1515,
        casts_shadow: false,
        indirect: false,
        material_mask: u32::MAX,
        motion: None,
    }
    .generate(None);
    Scene {
        name: "glass".into(),
        meshes,
        materials,
        lights,
        camera: Camera {
            eye: Vec3::new(0.0, 2.5, 3.0),
            target: Vec3::new(0.0, 2.5, -20.0),
            up: Vec3::Y,
            fov_y: 60f32.to_radians(),
            near: 0.1,
            far: 60.0,
        },
        output_size: Some((1280, 720)),
        // A little ambient light shows the glass where no light reaches.
        ambient: Vec3::splat(0.04),
        ..Default::default()
    }
}
