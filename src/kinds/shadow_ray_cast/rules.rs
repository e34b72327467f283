//! `ShadowRayCast`: one invocation per job, dispatched indirectly from the job count: an
//! any-hit ray against the scene BVH from the pixel's position offset along its geometric
//! normal (which its jobs pass read from a G-buffer or a visibility buffer,
//! [`super::shadow_ray_jobs::SurfaceSource`], and stored in the job buffer); a hit sets the
//! light's bit in the pixel's mask. Runs `shaders/shadow/shadow_ray_cast.wgsl`. The
//! surface slots stay declared, as the jobs pass's: the shader reads the stored copy.

use super::shadow_ray_jobs::{check_surface_source, SHADOW_JOBS, SHADOW_MASK, SURFACE_SLOTS};
use super::{Access, Contents, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::SceneResource;
use serde::{Deserialize, Serialize};

/// `ShadowRayCast(normal_offset: 1e-4)`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShadowRayCast {
    /// Origin offset along the geometric normal, relative to the position's largest
    /// coordinate (at least 1): what keeps a surface from shadowing itself.
    #[serde(default = "default_normal_offset")]
    pub normal_offset: f32,
}

/// The default origin offset (also what naive tracing in the light loop uses).
pub(crate) const DEFAULT_NORMAL_OFFSET: f32 = 1e-4;

fn default_normal_offset() -> f32 {
    DEFAULT_NORMAL_OFFSET
}

pub(crate) const BVH_NODES: &str = "bvh_nodes";
pub(crate) const BVH_TRIANGLES: &str = "bvh_triangles";

pub(crate) const SLOTS: &[SlotSpec] = &[
    SlotSpec::new(SHADOW_JOBS, SlotType::Buffer, Access::Read, Usage::Bound)
        .needs(&[Contents::ShadowJobs]),
    SURFACE_SLOTS[0],
    SURFACE_SLOTS[1],
    SURFACE_SLOTS[2],
    SURFACE_SLOTS[3],
    SURFACE_SLOTS[4],
    super::LIGHT_GEOMETRY_READ,
    SlotSpec::new(
        BVH_NODES,
        SlotType::Import(SceneResource::BvhNodes),
        Access::Read,
        Usage::Bound,
    ),
    SlotSpec::new(
        BVH_TRIANGLES,
        SlotType::Import(SceneResource::BvhTriangles),
        Access::Read,
        Usage::Bound,
    ),
    SlotSpec::new(SHADOW_MASK, SlotType::Buffer, Access::Write, Usage::Bound),
];

pub(crate) fn check(p: &ShadowRayCast, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    if !(p.normal_offset.is_finite() && (0.0..=0.1).contains(&p.normal_offset)) {
        errors.push(ctx.bad(format!(
            "normal_offset {} must be in [0, 0.1]",
            p.normal_offset
        )));
    }
    check_surface_source(ctx, errors);
}

impl KindRules for ShadowRayCast {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(self, ctx, errors)
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::errors;

    #[test]
    fn checks_offset() {
        let e = errors(
            r#"Pass(name: "r", kind: ShadowRayCast(normal_offset: -1.0), reads: ["lists", "pos", "nrm", "lg", "bn", "bt"], writes: ["small_buf"])"#,
            "pos",
        );
        assert!(
            e.contains("normal_offset -1 must be in [0, 0.1]") || e.contains("reads resource"),
            "{e}"
        );
    }
}
