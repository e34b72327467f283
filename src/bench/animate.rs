//! Timing moving lights (a sweep's `animate:`): before every frame the lights move on by
//! `animate` seconds and are written with `PreparedFrame::update_lights`, so each frame
//! culls, lists and (with an atlas) allocates shadows for lights that moved. Scenes whose
//! lights have no motion of their own (and every light count a sweep generates) orbit the
//! centre of the scene's bounds about +Y at [`ORBIT_DEG_PER_S`].

use super::timing::{self, Method, PointTimes};
use crate::render::{PreparedFrame, RenderError, Renderer, SceneGpu};
use crate::scene::motion::{animate_into, LightMotion, Motion, Orbit};
use crate::scene::Scene;

/// Degrees per second of the orbit given to lights without motion.
pub(crate) const ORBIT_DEG_PER_S: f32 = 30.0;

/// The scene's motion, or every light orbiting the centre of its bounds.
pub(crate) fn motion_for(scene: &Scene) -> Vec<LightMotion> {
    if scene.has_motion() {
        return scene.light_motion.clone();
    }
    let (lo, hi) = scene.bounds().unwrap_or_default();
    vec![LightMotion {
        first: 0,
        count: scene.lights.len() as u32,
        motion: Motion {
            orbit: Some(Orbit {
                centre: (lo + hi) * 0.5,
                axis: glam::Vec3::Y,
                speed_deg: ORBIT_DEG_PER_S,
            }),
            ..Default::default()
        },
    }]
}

/// [`timing::time_point`] with the lights moved before every frame; afterwards every
/// frame is given the scene's own lights back (what the reference images show).
pub(crate) fn time_moving(
    frames: &[&PreparedFrame],
    scene: &Scene,
    gpu: &SceneGpu,
    renderer: &Renderer,
    method: &Method,
    step: f64,
) -> Result<PointTimes, RenderError> {
    let motion = motion_for(scene);
    let mut lights = Vec::with_capacity(scene.lights.len());
    let mut frame = 0u64;
    let times = timing::time_point_with(frames, renderer, method, &mut |g| {
        frame += 1;
        animate_into(&scene.lights, &motion, frame as f64 * step, &mut lights);
        Ok(frames[g].update_lights(renderer, gpu, &lights)?)
    })?;
    for f in frames {
        f.update_lights(renderer, gpu, &scene.lights)?;
    }
    Ok(times)
}
