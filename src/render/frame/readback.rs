//! Reading back what an executed frame wrote: its passes' reports, light statistics,
//! shadow reports, and named buffers and textures (tests and tools).

use super::PreparedFrame;
use crate::gpu::readback::{read_buffer, read_rgba32f};
use crate::render::report::{CullingReport, LightStats, PassReport, ShadowReport};
use crate::render::{RenderError, Renderer};

impl PreparedFrame {
    /// Reads back what the last executed frame's passes and statistics pass counted
    /// (not the image).
    pub fn read_reports(
        &self,
        r: &Renderer,
    ) -> Result<(Vec<CullingReport>, Option<LightStats>), RenderError> {
        let mut culling = Vec::new();
        for (_, pass) in &self.passes {
            if let Some(PassReport::Culling(report)) = pass.report(r)? {
                culling.push(report);
            }
        }
        Ok((culling, self.read_light_stats(r)?))
    }

    /// What every pass that counts something counted in the last executed frame.
    pub(super) fn pass_reports(&self, r: &Renderer) -> Result<Vec<PassReport>, RenderError> {
        let mut out = Vec::new();
        for (_, pass) in &self.passes {
            out.extend(pass.report(r)?);
        }
        Ok(out)
    }

    pub(super) fn read_light_stats(&self, r: &Renderer) -> Result<Option<LightStats>, RenderError> {
        match &self.stats {
            Some(stats) => Ok(Some(stats.read(r)?)),
            None => Ok(None),
        }
    }

    /// What the last executed frame's ray-cast shadow job passes counted.
    pub fn read_shadow_reports(&self, r: &Renderer) -> Result<Vec<ShadowReport>, RenderError> {
        Ok(self
            .pass_reports(r)?
            .into_iter()
            .filter_map(|report| match report {
                PassReport::Shadow(s) => Some(s),
                _ => None,
            })
            .collect())
    }

    /// Errs when `name` shares its physical resource with one used after it: what a
    /// readback would see is the later resource.
    fn check_not_reused(&self, name: &str) -> Result<(), RenderError> {
        let plan = &self.graph.plan;
        let later = plan
            .get(name)
            .and_then(|r| plan.physical[r.physical].serves.last())
            .filter(|last| *last != name);
        match later {
            Some(last) => Err(RenderError::Pass {
                pass: "readback".into(),
                message: format!("'{name}' shares its physical resource with '{last}', used after it in the frame: it no longer holds '{name}' (make '{name}' the output, or keep its readers last)"),
            }),
            None => Ok(()),
        }
    }

    /// Reads back a planned buffer of the last executed frame (tests, inspection).
    pub fn read_buffer(&self, r: &Renderer, name: &str) -> Result<Vec<u8>, RenderError> {
        self.check_not_reused(name)?;
        let buffer = self
            .resources
            .buffer(&self.graph.plan, name)
            .ok_or_else(|| RenderError::Pass {
                pass: "readback".into(),
                message: format!("'{name}' is not a planned buffer"),
            })?;
        Ok(read_buffer(&r.ctx.device, &r.ctx.queue, buffer)?)
    }

    /// Reads back a planned Rgba32Float texture of the last executed frame.
    pub fn read_texture(&self, r: &Renderer, name: &str) -> Result<Vec<[f32; 4]>, RenderError> {
        self.check_not_reused(name)?;
        let texture = self
            .resources
            .texture(&self.graph.plan, name)
            .ok_or_else(|| RenderError::Pass {
                pass: "readback".into(),
                message: format!("'{name}' is not a planned texture"),
            })?;
        Ok(read_rgba32f(&r.ctx.device, &r.ctx.queue, texture)?)
    }

    /// Reads back a planned single-sample texture of 32 bits a texel (R32Float, R32Uint,
    /// Depth32Float) of the last executed frame, each texel's bits as they are (tests
    /// that compare depths and ids exactly, inspection).
    pub fn read_texture_bits(&self, r: &Renderer, name: &str) -> Result<Vec<u32>, RenderError> {
        use wgpu::TextureFormat as F;
        self.check_not_reused(name)?;
        let texture = self
            .resources
            .texture(&self.graph.plan, name)
            .filter(|t| {
                t.sample_count() == 1
                    && matches!(t.format(), F::R32Float | F::R32Uint | F::Depth32Float)
            })
            .ok_or_else(|| RenderError::Pass {
                pass: "readback".into(),
                message: format!(
                    "'{name}' is not a planned single-sample R32Float, R32Uint or Depth32Float texture"
                ),
            })?;
        let bytes = crate::gpu::readback::read_texture(&r.ctx.device, &r.ctx.queue, texture, 4)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}
