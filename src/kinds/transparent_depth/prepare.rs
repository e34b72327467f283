//! `TransparentDepth`: every blended mesh, both faces, depth only, into its own texture:
//! the depth prepass's draw over the transparent mesh set (the nearest depth wins
//! whatever the order, so no sorting).

use super::depth_prepass::{self, DepthPrepass};
use super::PrepareCtx;
use crate::graph::ScheduledPass;
use crate::render::draws::MeshSet;
use crate::render::RenderError;

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
) -> Result<DepthPrepass, RenderError> {
    depth_prepass::prepare_meshes(cx, sp, MeshSet::Transparent)
}
