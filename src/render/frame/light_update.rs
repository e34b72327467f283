//! Per-frame light updates: new light values written over the scene's light buffers,
//! the frame's light count set, and the passes that keep per-light CPU state (shadow
//! atlas allocation, reflective shadow maps' views, VPL spawn parameters, per-light
//! dispatches) told. No pipeline or bind group changes:
//! culling and the light lists are rebuilt by the GPU every frame anyway.

use super::PreparedFrame;
use crate::gpu::structs::GpuFrame;
use crate::render::scene_gpu::SceneGpu;
use crate::render::Renderer;
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
        gpu.write_lights(&r.ctx.queue, lights)?;
        let count = lights.len() as u32;
        self.light_count.store(count, Ordering::Relaxed);
        r.ctx.queue.write_buffer(
            &self.frame_uniform,
            LIGHT_COUNT_OFFSET,
            &count.to_ne_bytes(),
        );
        for (_, pass) in &self.passes {
            pass.follow_lights(r, lights);
        }
        Ok(())
    }

    /// The light count the passes read: the upload's, or the last update's.
    pub fn light_count(&self) -> u32 {
        self.light_count.load(Ordering::Relaxed)
    }

    /// The most lights [`update_lights`](Self::update_lights) takes.
    pub fn light_capacity(&self) -> u32 {
        self.light_capacity
    }
}

/// Where the frame uniform keeps the light count.
const LIGHT_COUNT_OFFSET: u64 = std::mem::offset_of!(GpuFrame, light_count) as u64;

/// The first light that needs a feature the compiled graph was made without.
fn check_features(had: &SceneFeatures, lights: &[Light]) -> Result<(), LightUpdateError> {
    for (index, l) in lights.iter().enumerate() {
        let spot = matches!(l.shape, LightShape::Spot { .. });
        let feature = if !had.has_lights {
            Some("a light")
        } else if l.flags & light_flags::CASTS_SHADOW != 0 && !had.has_shadow_casters {
            Some("a shadow caster")
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
