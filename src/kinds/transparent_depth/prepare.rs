//! `TransparentDepth`: every blended mesh, both faces, depth only, into its own texture
//! (the nearest depth wins whatever the order, so no sorting). A depth texture is drawn
//! by the depth prepass's draw over the transparent mesh set; an R32Float one by the
//! compute rasterizer over the blended triangles (`compute_raster::RasterSource::Blended`),
//! or, on an adapter without its 64-bit atomics, drawn into an internal Depth32Float and
//! copied (`fallback.rs`).

use super::compute_raster::{self, RasterSource, FEATURES};
use super::depth_prepass;
use super::transparent_depth_fallback::DrawnAndCopied;
use super::{PrepareCtx, PreparedPass};
use crate::graph::{slot, ScheduledPass};
use crate::render::draws::MeshSet;
use crate::render::RenderError;

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
) -> Result<Box<dyn PreparedPass>, RenderError> {
    if !cx.float_depth(sp.required(slot::DEPTH)) {
        return Ok(Box::new(depth_prepass::prepare_meshes(
            cx,
            sp,
            MeshSet::Transparent,
        )?));
    }
    let missing = FEATURES - cx.device().features();
    if missing.is_empty() {
        return Ok(Box::new(compute_raster::prepare_source(
            cx,
            sp,
            RasterSource::Blended,
        )?));
    }
    Ok(Box::new(DrawnAndCopied::prepare(cx, sp, missing)?))
}
