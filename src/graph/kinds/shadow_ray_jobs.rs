//! `ShadowRayJobs`: one job (pixel, light) for every shadow-casting light that reaches
//! and faces a pixel, walked from its light list; compacted per workgroup; writes the
//! casting pass's indirect dispatch and clears each pixel's hit mask. Runs
//! `shaders/shadow/shadow_ray_jobs.wgsl`.

use super::g_buffer::{G_GEOMETRIC, G_GEOMETRIC_READ, G_POSITION, G_POSITION_READ};
use super::{slot, Access, BufferLayout, Contents, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::plan::FrameSize;
use serde::{Deserialize, Serialize};

/// `ShadowRayJobs(jobs_per_pixel: 16.0)`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShadowRayJobs {
    /// Job buffer capacity, as jobs per output pixel on average (the paper's scene casts
    /// about 7.6 a pixel); jobs past it are dropped, counted and reported (lit unshadowed).
    #[serde(default = "default_jobs_per_pixel")]
    pub jobs_per_pixel: f32,
}

fn default_jobs_per_pixel() -> f32 {
    16.0
}

pub(crate) const SHADOW_JOBS: &str = "shadow_jobs";
pub(crate) const SHADOW_MASK: &str = "shadow_mask";

/// Words before the jobs: wanted, dropped, pixels over 128 casters, unused, then the
/// indirect dispatch (x, y, z, unused).
pub(crate) const JOB_HEADER_WORDS: u64 = 8;
/// A job: pixel index, then light index | caster number << 24.
pub(crate) const JOB_WORDS: u64 = 2;
/// Mask words a pixel (128 casters).
pub(crate) const MASK_WORDS: u64 = 4;

impl ShadowRayJobs {
    /// Jobs the buffer holds at `width`×`height`.
    pub fn capacity(&self, width: u32, height: u32) -> u64 {
        ((width as f64 * height as f64 * self.jobs_per_pixel as f64).ceil() as u64).max(1)
    }
}

/// Bytes of a job buffer holding `capacity` jobs.
pub(crate) fn job_buffer_bytes(capacity: u64) -> u64 {
    4 * (JOB_HEADER_WORDS + JOB_WORDS * capacity)
}

pub(crate) const SLOTS: &[SlotSpec] = &[
    G_POSITION_READ,
    G_GEOMETRIC_READ,
    super::LIGHT_GEOMETRY_READ,
    super::LIGHT_PROPERTIES_READ,
    SlotSpec::new(
        slot::LIGHT_LISTS,
        SlotType::Buffer,
        Access::Read,
        Usage::Bound,
    )
    .needs(&[Contents::LightLists]),
    SlotSpec::new(SHADOW_JOBS, SlotType::Buffer, Access::Write, Usage::Bound),
    SlotSpec::new(SHADOW_MASK, SlotType::Buffer, Access::Write, Usage::Bound),
];

pub(crate) fn check(p: &ShadowRayJobs, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    if !(p.jobs_per_pixel.is_finite() && p.jobs_per_pixel > 0.0 && p.jobs_per_pixel <= 128.0) {
        errors.push(ctx.bad(format!(
            "jobs_per_pixel {} must be in (0, 128] (at most 128 casters a pixel)",
            p.jobs_per_pixel
        )));
    }
    ctx.require_single_rgba32f(
        &[G_POSITION, G_GEOMETRIC],
        "ray-cast shadows read world positions and geometric normals from single-sample Rgba32Float G-buffer textures (not the packed G-buffer)",
        errors,
    );
}

impl KindRules for ShadowRayJobs {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(self, ctx, errors)
    }
    fn buffer_layout(&self, slot: &str, frame: FrameSize) -> Option<BufferLayout> {
        match slot {
            SHADOW_JOBS => Some(BufferLayout::ShadowJobs {
                capacity: self.capacity(frame.width, frame.height),
            }),
            SHADOW_MASK => Some(BufferLayout::ShadowMask {
                pixels: frame.width as u64 * frame.height as u64,
            }),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::errors;

    #[test]
    fn checks_capacity_and_inputs() {
        let e = errors(
            r#"Pass(name: "g", kind: GBuffer, reads: ["geometry"], writes: ["depth", "pos", "nrm", "geo"]),
               Pass(name: "c", kind: LightCulling(tile: 16), reads: ["depth", "lg"], writes: ["lists"]),
               Pass(name: "j", kind: ShadowRayJobs(jobs_per_pixel: 0.0), reads: ["pos", "geo", "lg", "lp", "lists"], writes: ["jobs", "mask"])"#,
            "pos",
        );
        assert!(e.contains("jobs_per_pixel 0 must be in (0, 128]"), "{e}");
        let e = errors(
            r#"Pass(name: "g", kind: GBuffer, reads: ["geometry"], writes: ["depth", "pos", "nrm", "geo"]),
               Pass(name: "j", kind: ShadowRayJobs(), reads: ["pos", "geo", "lg", "lp"], writes: ["jobs", "mask"])"#,
            "pos",
        );
        assert!(
            e.contains("ShadowRayJobs needs a buffer in reads (slot 'light_lists')"),
            "{e}"
        );
    }
}
