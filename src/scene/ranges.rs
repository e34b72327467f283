//! What a scene hands the GPU, checked for range after every transform: positions, light
//! power and reach, and the camera basis. The shaders compute squares and products of
//! these in f32; past these limits a finite input still overflows to Inf or NaN there.

use super::error::SceneError;
use super::types::{Camera, Light, Mesh, Scene};
use std::path::Path;

/// Largest coordinate of a vertex, light or camera, in metres. f32 spacing at 1e5 is
/// 7.8 mm: vertices, lights and the eye keep sub-centimetre places, so interpolated
/// positions, light vectors and view-space depths move by under a centimetre, and a
/// metre-sized object keeps its shape (rendered at 1e5 or 1e6 m from the origin, a 1 m
/// triangle differs from the same at the origin only along its edges; at 1e7 the spacing
/// is a metre, such geometry collapses and rendered black). Squared distances stay far
/// below f32's range.
pub(crate) const MAX_COORDINATE: f32 = 1e5;
/// Largest texture coordinate magnitude. f32 spacing at 4096 is 2^-11 of a texture
/// repeat, a texel of a 2048-texel texture: interpolated UVs past it land on texels at
/// random (3e38 overflowed to Inf in the sampling and shaded a triangle grey).
pub(crate) const MAX_UV: f32 = 4096.0;
/// Largest light range, in metres (the fallback light reaches twice the scene diagonal).
pub(crate) const MAX_RANGE: f32 = 1e8;
/// Largest intensity × colour channel of a light, in candela. A light this bright at
/// 1 cm from a mirror-like lobe still stays below f32's maximum of 3.4e38.
pub(crate) const MAX_LIGHT_POWER: f32 = 1e15;

impl Scene {
    /// Checks every vertex, light and the camera against the limits above; `file` names
    /// the scene in the error.
    pub fn check_gpu_ranges(&self, file: &Path) -> Result<(), SceneError> {
        for (mi, mesh) in self.meshes.iter().enumerate() {
            if let Some((vi, p)) = mesh
                .positions
                .iter()
                .enumerate()
                .find(|(_, p)| !in_range(**p))
            {
                return Err(SceneError::invalid(
                    file,
                    format!("mesh {mi} (\"{}\") vertex {vi}", mesh.name),
                    format!(
                        "position {p:?} after the scene transform is not finite or beyond ±{MAX_COORDINATE:e} m"
                    ),
                ));
            }
        }
        for (mi, mesh) in self.meshes.iter().enumerate() {
            if let Some((vi, problem)) = bad_texture_coordinate(mesh) {
                return Err(SceneError::invalid(
                    file,
                    format!("mesh {mi} (\"{}\") vertex {vi}", mesh.name),
                    problem,
                ));
            }
        }
        for (i, l) in self.lights.iter().enumerate() {
            check_light_range(l).map_err(|m| SceneError::invalid(file, format!("light {i}"), m))?;
        }
        check_camera(&self.camera).map_err(|m| SceneError::invalid(file, "camera", m))
    }
}

fn in_range(p: glam::Vec3) -> bool {
    p.is_finite() && p.abs().max_element() <= MAX_COORDINATE
}

/// A light's position, reach and power after every transform.
/// The first vertex of `mesh` whose texture coordinates (either set) are not finite or
/// lie beyond ±MAX_UV, and what is wrong with them.
pub(crate) fn bad_texture_coordinate(mesh: &Mesh) -> Option<(usize, String)> {
    let sets = [
        ("texture coordinate", &mesh.uvs),
        ("second texture coordinate", &mesh.uvs1),
    ];
    sets.into_iter().find_map(|(what, uvs)| {
        let (v, uv) = uvs
            .iter()
            .enumerate()
            .find(|(_, uv)| !(uv.is_finite() && uv.abs().max_element() <= MAX_UV))?;
        Some((
            v,
            format!("{what} {uv:?} is not finite or beyond ±{MAX_UV}"),
        ))
    })
}

pub(crate) fn check_light_range(l: &Light) -> Result<(), String> {
    if !in_range(l.position) {
        return Err(format!(
            "position {:?} is not finite or beyond ±{MAX_COORDINATE:e} m",
            l.position
        ));
    }
    if !(l.range > 0.0 && l.range <= MAX_RANGE) {
        return Err(format!(
            "range {} must lie in (0, {MAX_RANGE:e}] m",
            l.range
        ));
    }
    let power = l.intensity * l.color.max_element();
    if !(power.is_finite() && power <= MAX_LIGHT_POWER) {
        return Err(format!(
            "intensity {:?} × colour {:?} is {power:e} cd, over the limit of {MAX_LIGHT_POWER:e}",
            l.intensity, l.color
        ));
    }
    Ok(())
}

/// The view basis must exist: eye and target distinct and in range, up not along the view.
pub(crate) fn check_camera(c: &Camera) -> Result<(), String> {
    if !in_range(c.eye) || !in_range(c.target) {
        return Err(format!(
            "eye {:?} and target {:?} must be finite and within ±{MAX_COORDINATE:e} m",
            c.eye, c.target
        ));
    }
    let view = c.target - c.eye;
    let (v, u) = (view.normalize_or_zero(), c.up.normalize_or_zero());
    if v == glam::Vec3::ZERO || u == glam::Vec3::ZERO || v.cross(u).length() < 1e-4 {
        return Err(format!(
            "up {} is zero or parallel to the view direction {view} (eye {} to target {}): the view has no basis",
            c.up, c.eye, c.target
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn a_bad_second_texture_coordinate_names_its_own_vertex() {
        let ok = glam::Vec2::new(0.5, 0.5);
        let mesh = Mesh {
            uvs: vec![ok; 3],
            uvs1: vec![ok, glam::Vec2::new(f32::NAN, 0.0), ok],
            ..Default::default()
        };
        let (vertex, problem) = bad_texture_coordinate(&mesh).unwrap();
        assert_eq!(vertex, 1);
        assert!(
            problem.starts_with("second texture coordinate"),
            "{problem}"
        );
        assert_eq!(
            bad_texture_coordinate(&Mesh {
                uvs1: vec![ok; 3],
                ..mesh
            }),
            None
        );
    }

    #[test]
    fn refuses_overbright_lights_far_vertices_and_a_degenerate_camera() {
        let l = Light::point(Vec3::ZERO, 1.0, Vec3::splat(3e38), 1.0);
        let e = check_light_range(&l).unwrap_err();
        assert!(e.contains("over the limit of 1e15"), "{e}");
        let l = Light::point(Vec3::ZERO, 1.0, Vec3::ONE, 1e15);
        assert!(check_light_range(&l).is_ok());
        let mut c = Camera::default();
        assert!(check_camera(&c).is_ok());
        c.up = c.target - c.eye;
        let e = check_camera(&c).unwrap_err();
        assert!(e.contains("parallel to the view direction"), "{e}");
        let mut s = Scene::default();
        s.meshes.push(crate::scene::Mesh {
            name: "far".into(),
            positions: vec![Vec3::ZERO, Vec3::new(0.0, 2e7, 0.0)],
            ..Default::default()
        });
        let e = s
            .check_gpu_ranges(Path::new("s.ron"))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("s.ron: mesh 0 (\"far\") vertex 1: position"),
            "{e}"
        );
    }
}
