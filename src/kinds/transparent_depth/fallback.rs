//! `TransparentDepth` into an R32Float depth on an adapter without the compute
//! rasterizer's 64-bit atomics (`compute_raster::FEATURES`): the blended meshes drawn by
//! the raster units into an internal Depth32Float, then copied into the R32Float texture
//! (`compute_raster_fallback::depth_copy`, bit-exact), as `ComputeRaster`'s own fallback
//! does; every frame's report says so.

use super::compute_raster_fallback::{depth_copy, draws_opening, record_depth_copy, DepthCopy};
use super::depth_prepass::{prepare_meshes_into, DepthPrepass};
use super::{PrepareCtx, PreparedPass, Timestamps};
use crate::graph::{slot, Name, ScheduledPass};
use crate::render::draws::MeshSet;
use crate::render::report::{FallbackReport, PassReport};
use crate::render::{RenderError, Renderer};

/// What the report says the pass did instead.
const INSTEAD: &str = "drawn with the hardware rasterizer and copied";

pub(super) struct DrawnAndCopied {
    name: Name,
    draws: DepthPrepass,
    copy: DepthCopy,
    report: FallbackReport,
}

impl DrawnAndCopied {
    pub(super) fn prepare(
        cx: &mut PrepareCtx,
        sp: &ScheduledPass,
        missing: wgpu::Features,
    ) -> Result<Self, RenderError> {
        let report = FallbackReport::new(&sp.name, &cx.renderer.ctx, missing, INSTEAD);
        let (drawn, copy) = depth_copy(cx, sp, sp.required(slot::DEPTH))?;
        Ok(Self {
            name: sp.name.clone(),
            draws: prepare_meshes_into(cx, sp, MeshSet::Transparent, drawn, true)?,
            copy,
            report,
        })
    }
}

impl PreparedPass for DrawnAndCopied {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        self.draws.record_with(encoder, draws_opening(ts));
        record_depth_copy(encoder, &self.name, &self.copy, ts);
    }

    fn report(&self, _r: &Renderer) -> Result<Option<PassReport>, RenderError> {
        Ok(Some(PassReport::Fallback(self.report.clone())))
    }
}
