//! The perspective camera: a node's world matrix and lens checked into a scene [`Camera`].

use super::Importer;
use crate::scene::error::SceneError;
use crate::scene::types::{Camera, MAX_FAR_OVER_NEAR};
use glam::{Mat4, Vec3};

/// (element name, world matrix, (yfov, znear, zfar)).
pub(super) type FoundCamera = (String, Mat4, (f32, f32, Option<f32>));

impl Importer {
    pub(super) fn make_camera(
        &mut self,
        element: &str,
        world: Mat4,
        lens: (f32, f32, Option<f32>),
        bounds: Option<(Vec3, Vec3)>,
    ) -> Result<Camera, SceneError> {
        let eye = world.transform_point3(Vec3::ZERO);
        let fwd = world.transform_vector3(-Vec3::Z).normalize_or_zero();
        let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
        let (yfov, znear, zfar) = lens;
        if !eye.is_finite() || fwd == Vec3::ZERO || up == Vec3::ZERO || !fwd.is_finite() {
            return Err(self.err(element, "camera node transform is degenerate"));
        }
        if !(yfov.is_finite() && yfov > 0.0 && yfov < std::f32::consts::PI) {
            return Err(self.err(element, format!("yfov {yfov} must lie in (0, pi)")));
        }
        if !(znear.is_finite() && znear > 0.0) {
            return Err(self.err(element, format!("znear {znear} must be > 0")));
        }
        // Past the farthest corner of the scene nothing is drawn.
        let scene_far = bounds.map(|(lo, hi)| {
            let c = (lo + hi) * 0.5;
            ((eye - c).length() + (hi - lo).length()).max(znear * 10.0)
        });
        let far = match zfar {
            // A far plane past the scene that f32 depth cannot resolve from this near
            // plane (CAD exports write 1e6) is pulled in to the scene: the image is the
            // same and depth keeps its precision. One that cuts the scene is kept.
            Some(f) if f.is_finite() && f > znear && f / znear > MAX_FAR_OVER_NEAR => {
                match scene_far {
                    Some(s) if s < f => {
                        self.warnings.push(format!(
                            "{element}: zfar {f} is over 2^24 × znear {znear}, past what f32 depth resolves; the far plane is pulled in to the scene's farthest point ({s})"
                        ));
                        s
                    }
                    _ => f,
                }
            }
            Some(f) if f.is_finite() && f > znear => f,
            Some(f) => {
                return Err(self.err(
                    element,
                    format!("zfar {f} must be finite and > znear {znear}"),
                ))
            }
            // Infinite projection: reach past the farthest corner of the scene.
            None => scene_far.unwrap_or(1000.0_f32.max(znear * 10.0)),
        };
        if let Some(m) = Camera::lens_error(yfov.to_degrees(), znear, far) {
            return Err(self.err(element, format!("camera lens: {m}")));
        }
        Ok(Camera {
            eye,
            target: eye + fwd,
            up,
            fov_y: yfov,
            near: znear,
            far,
        })
    }
}
