//! The viewer's camera: orbit around a target or fly through the scene. Both modes share
//! one state (target, yaw, pitch, distance), so switching modes never jumps the view.

use crate::scene::Camera;
use glam::Vec3;

/// How mouse drags and keys move the camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraMode {
    /// Drag rotates around the target, the wheel changes the distance.
    Orbit,
    /// Drag looks around from the eye, WASD/QE move, the wheel changes the speed.
    Fly,
}

/// Keys held this frame, as a direction in camera space (x right, y up, z forward).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Movement {
    pub(crate) right: f32,
    pub(crate) up: f32,
    pub(crate) forward: f32,
    /// Shift held: move faster.
    pub(crate) fast: bool,
}

/// The viewer's camera state: orbit or fly, driven by mouse drags, the wheel and held keys;
/// [`CameraController::camera`] gives the scene camera for a frame.
#[derive(Clone, Debug)]
pub struct CameraController {
    /// Orbit or fly; switch at any time without the view jumping.
    pub mode: CameraMode,
    target: Vec3,
    /// Radians around world up; 0 looks down -Z.
    yaw: f32,
    /// Radians above the horizon, kept inside ±PITCH_LIMIT.
    pitch: f32,
    distance: f32,
    /// Fly speed in scene units per second.
    pub(crate) speed: f32,
    /// Field of view and clip planes come from the scene's camera.
    lens: Camera,
}

/// Stay short of straight up or down, where the view basis (built with world up) degenerates.
const PITCH_LIMIT: f32 = 1.55;
/// Radians per pixel of mouse drag.
const DRAG_RADIANS: f32 = 0.005;

fn forward(yaw: f32, pitch: f32) -> Vec3 {
    Vec3::new(
        pitch.cos() * yaw.sin(),
        pitch.sin(),
        -pitch.cos() * yaw.cos(),
    )
}

impl CameraController {
    /// Starts where `camera` looks, in orbit mode.
    pub(crate) fn new(camera: &Camera) -> Self {
        let offset = camera.target - camera.eye;
        let distance = offset.length().max(1e-3);
        let dir = offset / distance;
        Self {
            mode: CameraMode::Orbit,
            target: camera.target,
            yaw: dir.x.atan2(-dir.z),
            pitch: dir
                .y
                .clamp(-1.0, 1.0)
                .asin()
                .clamp(-PITCH_LIMIT, PITCH_LIMIT),
            distance,
            // Cross the orbit distance in about two seconds.
            speed: distance * 0.5,
            lens: *camera,
        }
    }

    pub(crate) fn forward(&self) -> Vec3 {
        forward(self.yaw, self.pitch)
    }

    /// Eye position in world space.
    pub(crate) fn eye(&self) -> Vec3 {
        self.target - self.forward() * self.distance
    }

    /// The scene camera for this view.
    pub fn camera(&self) -> Camera {
        Camera {
            eye: self.eye(),
            target: self.target,
            up: Vec3::Y,
            ..self.lens
        }
    }

    /// A mouse drag of `dx`, `dy` pixels.
    pub(crate) fn drag(&mut self, dx: f32, dy: f32) {
        let eye = self.eye();
        self.yaw += dx * DRAG_RADIANS;
        self.pitch = (self.pitch - dy * DRAG_RADIANS).clamp(-PITCH_LIMIT, PITCH_LIMIT);
        if self.mode == CameraMode::Fly {
            // Look around from where we stand.
            self.target = eye + self.forward() * self.distance;
        }
    }

    /// Mouse wheel: orbit moves closer or further, fly changes speed.
    pub(crate) fn scroll(&mut self, lines: f32) {
        let factor = 0.9f32.powf(lines);
        match self.mode {
            CameraMode::Orbit => self.distance = (self.distance * factor).max(1e-3),
            CameraMode::Fly => self.speed = (self.speed / factor).clamp(1e-3, 1e6),
        }
    }

    /// Moves eye and target together for `dt` seconds (both modes; orbit pans).
    pub(crate) fn travel(&mut self, m: Movement, dt: f32) {
        let f = self.forward();
        let right = f.cross(Vec3::Y).normalize_or_zero();
        let dir = right * m.right + Vec3::Y * m.up + f * m.forward;
        let speed = if m.fast { self.speed * 4.0 } else { self.speed };
        self.target += dir.normalize_or_zero() * speed * dt;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene_camera() -> Camera {
        Camera {
            eye: Vec3::new(3.0, 2.0, 5.0),
            target: Vec3::new(0.5, 0.5, -1.0),
            ..Camera::default()
        }
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        // f32 trigonometry round trip on coordinates of magnitude ~5.
        (a - b).length() < 1e-5
    }

    #[test]
    fn starts_exactly_where_the_scene_camera_looks() {
        let c = CameraController::new(&scene_camera()).camera();
        assert!(close(c.eye, scene_camera().eye), "{:?}", c.eye);
        assert!(close(c.target, scene_camera().target));
        assert_eq!(c.fov_y, scene_camera().fov_y);
    }

    #[test]
    fn orbit_keeps_the_target_and_distance() {
        let mut c = CameraController::new(&scene_camera());
        let d = (c.eye() - c.target).length();
        c.drag(120.0, -40.0);
        assert!(close(c.camera().target, scene_camera().target));
        assert!(((c.eye() - c.target).length() - d).abs() < 1e-5);
        assert!(!close(c.eye(), scene_camera().eye));
    }

    #[test]
    fn fly_keeps_the_eye_when_looking_and_moves_along_the_view() {
        let mut c = CameraController::new(&scene_camera());
        c.mode = CameraMode::Fly;
        let eye = c.eye();
        c.drag(-200.0, 70.0);
        assert!(close(c.eye(), eye));
        let f = c.forward();
        c.travel(
            Movement {
                forward: 1.0,
                ..Default::default()
            },
            2.0,
        );
        assert!(close(c.eye(), eye + f * c.speed * 2.0));
    }

    #[test]
    fn switching_modes_does_not_move_the_view() {
        // `camera()` does not read the mode, so what a switch must keep is the state the
        // next mode starts from: fly looks around the eye that orbiting left, and orbit
        // then turns around the target that flying left.
        let mut c = CameraController::new(&scene_camera());
        c.drag(50.0, 10.0);
        let orbit_eye = c.eye();
        c.mode = CameraMode::Fly;
        c.drag(-120.0, 35.0);
        assert!(close(c.eye(), orbit_eye), "fly starts at the orbit's eye");
        let fly_target = c.camera().target;
        assert!(
            !close(fly_target, scene_camera().target),
            "fly turned the view"
        );
        c.mode = CameraMode::Orbit;
        c.drag(80.0, -20.0);
        assert!(
            close(c.camera().target, fly_target),
            "orbit turns around fly's target"
        );
        assert!(!close(c.eye(), orbit_eye), "and moves the eye");
    }

    #[test]
    fn looking_straight_up_or_down_stays_finite() {
        let mut c = CameraController::new(&scene_camera());
        c.drag(0.0, -1e6);
        let view = c.camera().view();
        assert!(view.is_finite(), "{view:?}");
        c.drag(0.0, 2e6);
        assert!(c.camera().view().is_finite());
    }
}
