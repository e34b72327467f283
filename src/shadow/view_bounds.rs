//! Where a light or a box lies in a view: a frustum's planes and the conservative
//! sphere and box tests against them, a light's size on screen (what its atlas tile is
//! sized by) and the most pixels its range can reach (what bounds its shadow rays).

use crate::scene::{Camera, Light};
use glam::{Mat4, Vec3, Vec4};

/// The planes of a view-projection's frustum (wgpu depth 0..1), inward-facing, each
/// `(n, d)` with `n·p + d >= 0` inside.
pub(crate) fn frustum_planes(view_proj: Mat4) -> [Vec4; 6] {
    let r = [
        view_proj.row(0),
        view_proj.row(1),
        view_proj.row(2),
        view_proj.row(3),
    ];
    let planes = [
        r[3] + r[0],
        r[3] - r[0],
        r[3] + r[1],
        r[3] - r[1],
        r[2],
        r[3] - r[2],
    ];
    planes.map(|p| p / p.truncate().length().max(f32::MIN_POSITIVE))
}

/// Whether a sphere touches the frustum (conservative near the corners).
pub(crate) fn sphere_in_frustum(planes: &[Vec4; 6], center: Vec3, radius: f32) -> bool {
    planes
        .iter()
        .all(|p| p.truncate().dot(center) + p.w >= -radius)
}

/// Whether an axis-aligned box touches the frustum (conservative near the corners).
pub(crate) fn box_in_frustum(planes: &[Vec4; 6], min: Vec3, max: Vec3) -> bool {
    planes.iter().all(|p| {
        let n = p.truncate();
        let corner = Vec3::select(n.cmpge(Vec3::ZERO), max, min);
        n.dot(corner) + p.w >= 0.0
    })
}

/// The light's diameter on screen in pixels (the frame's height when the camera is
/// inside its range).
pub(crate) fn screen_size(light: &Light, camera: &Camera, height: u32) -> f32 {
    let d = light.position.distance(camera.eye);
    if d <= light.range {
        return height as f32;
    }
    let half_angle = (light.range / d).asin();
    let px = half_angle.tan() / (camera.fov_y * 0.5).tan() * height as f32;
    px.min(height as f32)
}

/// The most pixels whose surface a light's range can reach: the pixel centres inside the
/// screen box of its range sphere's bounding box (the whole frame when a corner of that
/// box is not in front of the camera). A shadow ray is cast only from a pixel whose
/// surface lies in range, so this bounds the light's rays.
pub(crate) fn ray_pixels_bound(light: &Light, view_proj: &Mat4, width: u32, height: u32) -> f64 {
    let frame = f64::from(width) * f64::from(height);
    let r = light.range;
    let (mut lo, mut hi) = (glam::Vec2::splat(f32::MAX), glam::Vec2::splat(f32::MIN));
    for k in 0..8 {
        let corner = light.position
            + glam::Vec3::new(
                if k & 1 == 0 { -r } else { r },
                if k & 2 == 0 { -r } else { r },
                if k & 4 == 0 { -r } else { r },
            );
        let c = *view_proj * corner.extend(1.0);
        if !(c.w > 0.0 && c.z >= 0.0) {
            return frame;
        }
        let ndc = glam::Vec2::new(c.x, c.y) / c.w;
        lo = lo.min(ndc);
        hi = hi.max(ndc);
    }
    let lo = lo.clamp(glam::Vec2::splat(-1.0), glam::Vec2::ONE);
    let hi = hi.clamp(glam::Vec2::splat(-1.0), glam::Vec2::ONE);
    // A span of s pixels holds at most s + 1 pixel centres.
    let span = |a: f32, b: f32, pixels: u32| {
        (f64::from((b - a) * 0.5) * f64::from(pixels) + 1.0).min(f64::from(pixels))
    };
    (span(lo.x, hi.x, width) * span(lo.y, hi.y, height)).min(frame)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(position: Vec3, range: f32) -> Light {
        Light::point(position, range, Vec3::ONE, 1.0)
    }

    /// The ray bound holds every pixel whose surface a light reaches: here, every pixel
    /// centre inside the exact screen ellipse of a sphere in front of the camera, found
    /// by a ray per pixel; the whole frame when the camera is inside the range.
    #[test]
    fn the_ray_bound_holds_the_pixels_in_range() {
        let (w, h) = (160u32, 90u32);
        let cam = Camera {
            eye: Vec3::new(0.0, 2.0, 20.0),
            target: Vec3::ZERO,
            ..Default::default()
        };
        let view_proj = cam.projection(w as f32 / h as f32) * cam.view();
        let inv = view_proj.inverse();
        for light in [
            point(Vec3::new(0.0, 0.0, 0.0), 3.0),
            point(Vec3::new(6.0, 2.0, 5.0), 1.5),
            point(Vec3::new(-9.0, -3.0, -4.0), 4.0),
        ] {
            let bound = ray_pixels_bound(&light, &view_proj, w, h);
            let mut inside = 0.0;
            for y in 0..h {
                for x in 0..w {
                    let ndc = glam::Vec2::new(
                        (x as f32 + 0.5) / w as f32 * 2.0 - 1.0,
                        1.0 - (y as f32 + 0.5) / h as f32 * 2.0,
                    );
                    let far = inv.project_point3(ndc.extend(1.0));
                    let dir = (far - cam.eye).normalize();
                    // The ray meets the sphere: some point of it is in range.
                    let t = (light.position - cam.eye).dot(dir).max(0.0);
                    if (cam.eye + dir * t).distance(light.position) <= light.range {
                        inside += 1.0;
                    }
                }
            }
            assert!(
                inside > 0.0 && inside <= bound,
                "{inside} pixels, bound {bound}"
            );
            assert!(bound < f64::from(w * h), "{bound}: not the whole frame");
        }
        let around = point(cam.eye, 1.0);
        assert_eq!(
            ray_pixels_bound(&around, &view_proj, w, h),
            f64::from(w * h)
        );
    }
}
