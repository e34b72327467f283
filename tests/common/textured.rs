//! A textured scene with every kind of material compute shading and the compute
//! rasterizer must handle (textures made here, deterministic).

use super::random_scene;
use glam::{Vec2, Vec3};
use lightgraph::scene::{AlphaMode, Mesh, Scene, SurfaceMaterial, TextureImage};
use std::sync::Arc;

/// An sRGB checker of two colours, `cells` cells a side, alpha in vertical stripes.
pub fn checker(name: &str, size: u32, cells: u32, a: [u8; 3], b: [u8; 3]) -> TextureImage {
    let mut rgba8 = Vec::with_capacity((size * size * 4) as usize);
    for y in 0..size {
        for x in 0..size {
            let odd = (x * cells / size + y * cells / size) % 2 == 1;
            let c = if odd { a } else { b };
            // Alpha in stripes (for the masked material): opaque, then cut out.
            let alpha = if (x * 4 / size).is_multiple_of(2) {
                255
            } else {
                20
            };
            rgba8.extend([c[0], c[1], c[2], alpha]);
        }
    }
    TextureImage {
        name: name.into(),
        width: size,
        height: size,
        rgba8,
        srgb: true,
    }
}

/// A tangent-space normal map of sine bumps (linear).
pub fn bumps(size: u32) -> TextureImage {
    let mut rgba8 = Vec::with_capacity((size * size * 4) as usize);
    for y in 0..size {
        for x in 0..size {
            let (u, v) = (x as f32 / size as f32, y as f32 / size as f32);
            let n = Vec3::new(
                0.5 * (u * 6.0 * std::f32::consts::TAU).sin(),
                0.5 * (v * 4.0 * std::f32::consts::TAU).cos(),
                1.0,
            )
            .normalize();
            let q = |c: f32| ((c * 0.5 + 0.5) * 255.0).round() as u8;
            rgba8.extend([q(n.x), q(n.y), q(n.z), 255]);
        }
    }
    TextureImage {
        name: "bumps".into(),
        width: size,
        height: size,
        rgba8,
        srgb: false,
    }
}

/// One quad, counter-clockwise seen from the side `u x v` points to, uv over [0, 2]².
pub fn quad(name: &str, centre: Vec3, u: Vec3, v: Vec3, material: usize) -> Mesh {
    let n = u.cross(v).normalize();
    let mut m = Mesh {
        name: name.into(),
        material,
        ..Default::default()
    };
    for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        m.positions.push(centre + u * a + v * b);
        m.normals.push(n);
        m.uvs.push(Vec2::new(a + 1.0, b + 1.0));
        m.tangents.push(u.normalize().extend(1.0));
    }
    m.indices.extend([0, 1, 2, 0, 2, 3]);
    m
}

/// Adds to `s` a double-sided quad at `centre` spanning ±`u`, ±`v`, textured with the
/// mip-mapped stripes `checker` makes (alpha 255 and 20), alpha-masked at 0.5, or opaque
/// where `solid`: what the compute rasterizers' alpha tests are checked on.
pub fn push_striped_quad(s: &mut Scene, name: &str, centre: Vec3, u: Vec3, v: Vec3, solid: bool) {
    let tex = Arc::new(checker("stripes", 64, 8, [230, 120, 40], [40, 90, 200]));
    s.materials.push(SurfaceMaterial {
        name: "stripes".into(),
        base_color_texture: Some(tex),
        alpha_mode: if solid {
            AlphaMode::Opaque
        } else {
            AlphaMode::Mask(0.5)
        },
        double_sided: true,
        ..Default::default()
    });
    let m = s.materials.len() - 1;
    s.meshes.push(quad(name, centre, u, v, m));
}

/// The culling scene's room with every kind of material compute shading must handle: a
/// glossy checker floor with a normal map, an alpha-masked striped panel facing the
/// camera and a double-sided one showing its back face (masked too), lit by 200 lights.
pub fn textured_scene() -> Scene {
    let mut s = random_scene(200, 23);
    s.name = "textured".into();
    let tex = Arc::new(checker("checker", 64, 8, [230, 120, 40], [40, 90, 200]));
    s.materials[0] = SurfaceMaterial {
        name: "floor".into(),
        base_color_texture: Some(tex.clone()),
        normal_texture: Some(Arc::new(bumps(128))),
        roughness: 0.35,
        metallic: 0.2,
        ..Default::default()
    };
    s.materials.push(SurfaceMaterial {
        name: "masked".into(),
        base_color_texture: Some(tex),
        alpha_mode: AlphaMode::Mask(0.5),
        double_sided: true,
        roughness: 0.5,
        ..Default::default()
    });
    let masked = s.materials.len() - 1;
    // Facing the camera (+z), then its back to the camera (normal -z).
    s.meshes.push(quad(
        "panel_front",
        Vec3::new(-2.5, 2.0, -6.0),
        Vec3::X * 1.5,
        Vec3::Y * 1.5,
        masked,
    ));
    s.meshes.push(quad(
        "panel_back",
        Vec3::new(2.5, 2.0, -6.0),
        Vec3::Y * 1.5,
        Vec3::X * 1.5,
        masked,
    ));
    assert!(s.features().has_alpha_mask);
    s
}
