//! Timing moving lights (a sweep's `animate:`): before every frame the lights move on by
//! `animate` seconds on the GPU (`PreparedFrame::set_light_motion` once, then
//! `move_lights_to`), so each frame culls, lists and (with an atlas) allocates shadows
//! for lights that moved. Scenes whose
//! lights have no motion of their own (and every light count a sweep generates) orbit the
//! centre of the scene's bounds about +Y at [`ORBIT_DEG_PER_S`].

use super::timing::{self, Method, PointTimes};
use crate::render::{PreparedFrame, RenderError, Renderer, SceneGpu};
use crate::scene::motion::{LightMotion, Motion, Orbit};
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

/// What timing moving lights measured.
pub struct MovingTimes {
    /// The GPU's times, as for still lights.
    pub times: PointTimes,
    /// Per graph, the CPU milliseconds of every light update before a frame (warm-up
    /// and timed): `PreparedFrame::move_lights_to` (each motion's phase and its write,
    /// the moving casters' and indirect lights' evaluation, the passes' light state).
    /// The shadow atlas's reallocation runs when the frame is recorded and is not in it;
    /// the GPU's evaluation is the `light_motion` entry of the pass times.
    pub update_cpu_ms: Vec<Vec<f64>>,
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
) -> Result<MovingTimes, RenderError> {
    let motion = motion_for(scene);
    for f in frames {
        f.set_light_motion(renderer, gpu, &scene.lights, &motion)?;
    }
    let mut frame = 0u64;
    let mut update_cpu_ms = vec![Vec::new(); frames.len()];
    let times = timing::time_point_with(frames, renderer, method, &mut |g| {
        frame += 1;
        let start = std::time::Instant::now();
        frames[g].move_lights_to(renderer, frame as f64 * step)?;
        update_cpu_ms[g].push(start.elapsed().as_secs_f64() * 1e3);
        Ok(())
    })?;
    for f in frames {
        f.update_lights(renderer, gpu, &scene.lights)?;
    }
    Ok(MovingTimes {
        times,
        update_cpu_ms,
    })
}
