//! Per-frame light updates: new light values written over the scene's light buffers,
//! the frame's light count set, and the passes that keep per-light CPU state (shadow
//! atlas allocation, reflective shadow maps' views, VPL spawn parameters, per-light
//! dispatches) told. No pipeline or bind group changes:
//! culling and the light lists are rebuilt by the GPU every frame anyway.

use super::PreparedFrame;
use crate::gpu::structs::GpuFrame;
use crate::render::light_motion::{LightMotionStep, StepError};
use crate::render::scene_gpu::SceneGpu;
use crate::render::Renderer;
use crate::scene::motion::LightMotion;
use crate::scene::{light_flags, Light, LightShape, SceneFeatures};
use std::sync::atomic::Ordering;

/// Why a light update was refused; nothing was written.
#[derive(Debug, thiserror::Error)]
pub enum LightUpdateError {
    /// More lights than the light buffers have room for.
    #[error("light update of {count} lights is over the capacity of {capacity} set at upload (SceneGpu::upload_with_light_capacity)")]
    OverCapacity {
        /// Lights in the update.
        count: usize,
        /// Room in the light buffers, set at upload.
        capacity: u32,
    },
    /// A light has a value the shaders cannot use (not finite, negative range...).
    #[error("light update: light {index}: {problem}")]
    BadLight {
        /// The light's index in the update.
        index: usize,
        /// What is wrong with it.
        problem: String,
    },
    /// A light needs a scene feature (shadows, spot cones, indirect light) that the graph
    /// was compiled without.
    #[error("light update: light {index} adds {feature}, which the scene had none of when the graph was compiled (passes for it were dropped or specialised away): compile and prepare again")]
    NewFeature {
        /// The light's index in the update.
        index: usize,
        /// The feature it adds.
        feature: &'static str,
    },
    /// Two motions move one light: the GPU evaluates one motion per light.
    #[error(
        "light motion: light {index} is in the runs of two motions; give each light one motion"
    )]
    OverlappingMotion {
        /// The light's index in the scene.
        index: usize,
    },
    /// The motion step could not be built (its shader, or a device limit).
    #[error("light motion: {0}")]
    MotionStep(String),
    /// [`PreparedFrame::move_lights_to`] without a motion set.
    #[error("light motion: no motion is set on this frame (PreparedFrame::set_light_motion)")]
    NoMotion,
    /// A pass cannot show the lights with the room it was prepared with (the VPL
    /// candidates of more or larger indirect lights).
    #[error("light update: pass '{pass}' cannot follow moving lights: {problem}")]
    Pass {
        /// The pass's name.
        pass: String,
        /// Why not.
        problem: String,
    },
}

impl PreparedFrame {
    /// Replaces the scene's lights for the next frames: writes `lights` into `gpu`'s
    /// light buffers (one queue write each), sets the light count every pass reads (one
    /// write of the frame uniform) and updates the passes that keep per-light state.
    ///
    /// `gpu` must be the upload this frame was prepared with. At most its
    /// `light_capacity` lights; each checked like a scene file's light; no light may bring
    /// a feature (shadow casting, indirect, spot or point shape, a material mask) the
    /// scene had none of at compile time.
    pub fn update_lights(
        &self,
        r: &Renderer,
        gpu: &SceneGpu,
        lights: &[Light],
    ) -> Result<(), LightUpdateError> {
        self.check_update(lights)?;
        gpu.write_lights(&r.ctx.queue, lights)?;
        // The caller places the lights from now on.
        *self.motion.lock().unwrap_or_else(|e| e.into_inner()) = None;
        self.lights_changed(r, lights);
        Ok(())
    }

    /// Makes scene-file motion move the lights on the GPU: uploads `lights` (as placed,
    /// the scene's `lights`) and their `motion` (the scene's `light_motion`) once, and
    /// from the next frame on a dispatch before the passes writes every light moved to
    /// the time of the last [`move_lights_to`](Self::move_lights_to) (0 until then) over
    /// `gpu`'s light buffers. The CPU evaluates only the moving lights whose places it
    /// needs (shadow casters, indirect lights). Refused as
    /// [`update_lights`](Self::update_lights) refuses `lights`, and for two motions over
    /// one light. [`update_lights`](Self::update_lights) ends it.
    pub fn set_light_motion(
        &self,
        r: &Renderer,
        gpu: &SceneGpu,
        lights: &[Light],
        motion: &[LightMotion],
    ) -> Result<(), LightUpdateError> {
        self.check_update(lights)?;
        let mut step = LightMotionStep::new(r, gpu, lights, motion).map_err(|e| match e {
            StepError::Overlap(index) => LightUpdateError::OverlappingMotion { index },
            StepError::Render(e) => LightUpdateError::MotionStep(e.to_string()),
        })?;
        let at_0 = step.move_to(&r.ctx.queue, 0.0);
        self.lights_changed(r, at_0.unwrap_or(lights));
        *self.motion.lock().unwrap_or_else(|e| e.into_inner()) = Some(step);
        Ok(())
    }

    /// Moves the lights of [`set_light_motion`](Self::set_light_motion) to time `t`
    /// seconds for the next frame: writes each motion's phase (a few bytes per motion,
    /// whatever the light count) and evaluates on the CPU the moving shadow casters and
    /// indirect lights, which the passes that keep per-light state then follow.
    pub fn move_lights_to(&self, r: &Renderer, t: f64) -> Result<(), LightUpdateError> {
        let mut motion = self.motion.lock().unwrap_or_else(|e| e.into_inner());
        let step = motion.as_mut().ok_or(LightUpdateError::NoMotion)?;
        if let Some(lights) = step.move_to(&r.ctx.queue, t) {
            for (_, pass) in &self.passes {
                pass.follow_lights(r, lights);
            }
        }
        Ok(())
    }

    /// Whether the lights move on the GPU ([`set_light_motion`](Self::set_light_motion)).
    pub fn has_light_motion(&self) -> bool {
        self.motion
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .is_some()
    }

    /// What every light update checks: room, the compiled features, the passes' room.
    fn check_update(&self, lights: &[Light]) -> Result<(), LightUpdateError> {
        if lights.len() > self.light_capacity as usize {
            return Err(LightUpdateError::OverCapacity {
                count: lights.len(),
                capacity: self.light_capacity,
            });
        }
        check_features(&self.light_features, lights)?;
        for (name, pass) in &self.passes {
            pass.can_follow_lights(lights)
                .map_err(|problem| LightUpdateError::Pass {
                    pass: name.to_string(),
                    problem,
                })?;
        }
        Ok(())
    }

    /// The light count and the passes' per-light state follow `lights`.
    fn lights_changed(&self, r: &Renderer, lights: &[Light]) {
        let count = lights.len() as u32;
        let caster_end = crate::gpu::structs::caster_end(lights);
        self.light_count.set(count, caster_end);
        // light_count and caster_end are neighbours in the uniform.
        r.ctx.queue.write_buffer(
            &self.frame_uniform,
            LIGHT_COUNT_OFFSET,
            bytemuck::cast_slice(&[count, caster_end]),
        );
        for (_, pass) in &self.passes {
            pass.follow_lights(r, lights);
        }
    }

    /// The light count the passes read: the upload's, or the last update's.
    pub fn light_count(&self) -> u32 {
        self.light_count.get()
    }

    /// The most lights [`update_lights`](Self::update_lights) takes.
    pub fn light_capacity(&self) -> u32 {
        self.light_capacity
    }
}

/// The light count of a prepared frame and its casters' end: the numbers the CPU side
/// reads them from (the frame uniform's `light_count` and `caster_end`, which the GPU
/// reads, are written from them). Shared with the passes that size work by the count at
/// record (a `Compute` pass dispatched `PerLight`).
#[derive(Clone, Debug, Default)]
pub(crate) struct LightCount(std::sync::Arc<[std::sync::atomic::AtomicU32; 2]>);

impl LightCount {
    /// `n` lights, the casters among the first `caster_end`.
    pub fn new(n: u32, caster_end: u32) -> Self {
        Self(std::sync::Arc::new([n.into(), caster_end.into()]))
    }
    /// The lights passes loop over now.
    pub fn get(&self) -> u32 {
        self.0[0].load(Ordering::Relaxed)
    }
    /// One past the highest index of a light that casts a shadow now.
    pub fn caster_end(&self) -> u32 {
        self.0[1].load(Ordering::Relaxed)
    }
    fn set(&self, n: u32, caster_end: u32) {
        self.0[0].store(n, Ordering::Relaxed);
        self.0[1].store(caster_end, Ordering::Relaxed);
    }
}

/// Where the frame uniform keeps the light count; `caster_end` follows it.
const LIGHT_COUNT_OFFSET: u64 = std::mem::offset_of!(GpuFrame, light_count) as u64;
const _: () = assert!(
    std::mem::offset_of!(GpuFrame, caster_end) == std::mem::offset_of!(GpuFrame, light_count) + 4
);

/// The first light that needs a feature the compiled graph was made without.
fn check_features(had: &SceneFeatures, lights: &[Light]) -> Result<(), LightUpdateError> {
    for (index, l) in lights.iter().enumerate() {
        let spot = matches!(l.shape, LightShape::Spot { .. });
        let feature = if !had.has_lights {
            Some("a light")
        } else if l.flags & light_flags::CASTS_SHADOW != 0 && !had.has_shadow_casters {
            Some("a shadow caster")
        } else if l.flags & light_flags::CASTS_SHADOW == 0 && !had.has_unshadowed_lights {
            Some("a light that casts no shadow")
        } else if l.flags & light_flags::INDIRECT != 0 && !had.has_indirect_lights {
            Some("an indirect light")
        } else if spot && !had.has_spot_lights {
            Some("a spot light")
        } else if !spot && !had.has_point_lights {
            Some("a point light")
        } else if l.material_mask != u32::MAX && !had.has_material_masks {
            Some("a material mask")
        } else {
            None
        };
        if let Some(feature) = feature {
            return Err(LightUpdateError::NewFeature { index, feature });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{check_features, LightUpdateError};
    use crate::scene::{light_flags, Light, SceneFeatures};
    use glam::Vec3;

    fn light(flags: u32) -> Light {
        Light {
            flags,
            ..Light::point(Vec3::ZERO, 1.0, Vec3::ONE, 1.0)
        }
    }

    /// A scene whose every light casts was compiled with the light loop skipped
    /// (`SAMPLED_ONLY` beside a LightSampling pass): an update bringing a light without
    /// shadows is refused, naming it, and one of casting lights is taken.
    #[test]
    fn a_light_without_shadows_is_new_to_an_all_casting_scene() {
        let all_casting = SceneFeatures {
            has_lights: true,
            has_point_lights: true,
            has_shadow_casters: true,
            ..Default::default()
        };
        let casting = light(light_flags::CASTS_SHADOW);
        assert!(check_features(&all_casting, &[casting, casting]).is_ok());
        match check_features(&all_casting, &[casting, light(0)]) {
            Err(LightUpdateError::NewFeature { index, feature }) => {
                assert_eq!(index, 1);
                assert_eq!(feature, "a light that casts no shadow");
            }
            other => panic!("expected NewFeature, got {other:?}"),
        }
        let mixed = SceneFeatures {
            has_unshadowed_lights: true,
            ..all_casting
        };
        assert!(check_features(&mixed, &[casting, light(0)]).is_ok());
    }
}
