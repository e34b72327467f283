//! `ComputeRaster` on an adapter without its 64-bit atomics (`compute_raster::FEATURES`):
//! drawn with the hardware rasterizer instead, by the `VisibilityBuffer` pass's own draws
//! (`visibility_buffer::draw_ids`: the same ids and depth as `graphs/visibility_buffer.ron`),
//! into the pass's outputs, and every frame's report says so ([`FallbackReport`]). An
//! R32Float depth is drawn into an internal Depth32Float texture (outside the graph's
//! memory plan) and copied into it by one compute dispatch
//! (`shaders/visibility/compute_raster_depth_copy.wgsl`, bit-exact).
//! Alpha-masked materials are alpha-tested by those draws as the compute path tests them.
//! With the transparent depth in its writes, the blended meshes are drawn too, as
//! `TransparentDepth`'s own fallback draws them (into an internal Depth32Float, copied).
//! Their farthest depth, where it writes that too, is the far plane everywhere (a cleared
//! internal depth, copied): transparent culling then bounds its ranges by the opaque
//! depth alone, as without it (exact, the lists only longer).

use super::compute_raster::{self, FEATURES};
use super::depth_prepass::{prepare_meshes_into, DepthPrepass};
use super::visibility_buffer::{draw_ids, IdTargets, VisibilityBuffer};
use super::{defines, pass_error, PrepareCtx, PreparedPass, Timestamps};
use crate::graph::kinds::compute_raster::VISIBILITY;
use crate::graph::{slot, Name, ScheduledPass};
use crate::render::bind::Bound;
use crate::render::draws::{depth_attachment, MeshSet};
use crate::render::pipelines::PipelineKey;
use crate::render::report::{FallbackReport, PassReport};
use crate::render::{RenderError, Renderer};
use std::collections::BTreeMap;
use std::sync::Arc;

const COPY_SHADER: &str = "visibility/compute_raster_depth_copy.wgsl";
/// The copy's workgroup side (8×8 pixels).
const TILE: u32 = 8;
/// What the report says the pass did instead.
const INSTEAD: &str = "drawn with the hardware rasterizer";

/// The compute rasterizer where the device has its features, else the hardware fallback.
pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
) -> Result<Box<dyn PreparedPass>, RenderError> {
    let missing = FEATURES - cx.device().features();
    if missing.is_empty() {
        return Ok(Box::new(compute_raster::prepare_compute(cx, sp)?));
    }
    Ok(Box::new(HardwareRaster::prepare(cx, sp, missing)?))
}

/// The dispatch copying the drawn Depth32Float into an R32Float depth: its pipeline,
/// bindings and workgroup grid.
pub(super) type DepthCopy = (Arc<wgpu::ComputePipeline>, wgpu::BindGroup, [u32; 3]);

struct HardwareRaster {
    name: Name,
    draws: VisibilityBuffer,
    /// An R32Float depth: the copy from the drawn Depth32Float.
    copy: Option<DepthCopy>,
    /// The transparent depth, where the pass writes it: the blended meshes' draws into
    /// an internal Depth32Float and the copy from it.
    glass: Option<(DepthPrepass, DepthCopy)>,
    /// Their farthest depth: an internal depth cleared to the far plane, and its copy.
    far: Option<(wgpu::TextureView, DepthCopy)>,
    report: FallbackReport,
}

impl HardwareRaster {
    fn prepare(
        cx: &mut PrepareCtx,
        sp: &ScheduledPass,
        missing: wgpu::Features,
    ) -> Result<Self, RenderError> {
        let report = FallbackReport::new(&sp.name, &cx.renderer.ctx, missing, INSTEAD);
        if !cx
            .device()
            .features()
            .contains(wgpu::Features::PRIMITIVE_INDEX)
        {
            return Err(pass_error(
                &sp.name,
                format!(
                    "adapter {} lacks {missing} for the compute rasterizer, and PRIMITIVE_INDEX for its hardware fallback (the visibility buffer's draws): neither can write triangle ids here",
                    report.adapter
                ),
            ));
        }
        let depth = sp.required(slot::DEPTH);
        let ids = cx.view(&sp.name, sp.required(VISIBILITY))?;
        // A depth format is drawn into directly; an R32Float depth is drawn into an
        // internal Depth32Float, then copied.
        let (drawn, copy) = if cx.float_depth(depth) {
            let (drawn, copy) = depth_copy(cx, sp, depth)?;
            (drawn, Some(copy))
        } else {
            (cx.view(&sp.name, depth)?, None)
        };
        let target = IdTargets {
            depth: drawn,
            clear_depth: true,
            writes_depth: true,
            ids,
        };
        let glass = match sp.roles.slot(slot::TRANSPARENT_DEPTH) {
            Some(glass) => {
                let (drawn, copy) = depth_copy(cx, sp, glass)?;
                let draws = prepare_meshes_into(cx, sp, MeshSet::Transparent, drawn, true)?;
                Some((draws, copy))
            }
            None => None,
        };
        let far = match sp.roles.slot(slot::TRANSPARENT_FAR) {
            Some(far) => Some(depth_copy(cx, sp, far)?),
            None => None,
        };
        Ok(Self {
            name: sp.name.clone(),
            draws: draw_ids(cx, sp, target)?,
            copy,
            glass,
            far,
            report,
        })
    }
}

/// The internal Depth32Float of the frame's size that draws write for the pass's R32Float
/// texture `resource`, and the dispatch copying it there (bit-exact: a depth load gives
/// the stored f32).
pub(super) fn depth_copy(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    resource: &str,
) -> Result<(wgpu::TextureView, DepthCopy), RenderError> {
    let (width, height) = (cx.size.width, cx.size.height);
    let depth = cx.view(&sp.name, resource)?;
    let device = cx.device();
    let drawn = device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some("hardware fallback depth"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Depth32Float,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        })
        .create_view(&Default::default());
    let mut offered = cx.declared(sp)?;
    offered.offer("drawn_depth", Bound::View(drawn.clone()));
    offered.offer("depth", Bound::View(depth));
    let key = PipelineKey {
        shader: COPY_SHADER.into(),
        defines: defines(&[]),
        virtual_code: BTreeMap::new(),
        state: "copy_depth".into(),
    };
    let (pipeline, bind) = cx.compute_pipeline(&sp.name, key, "copy_depth", &offered)?;
    let groups = [width.div_ceil(TILE), height.div_ceil(TILE), 1];
    Ok((drawn, (pipeline, bind, groups)))
}

/// The timestamps of draws that a depth copy follows: the draws open the pair.
pub(super) fn draws_opening(ts: Timestamps<'_>) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
    ts.render().map(|t| wgpu::RenderPassTimestampWrites {
        end_of_pass_write_index: None,
        ..t
    })
}

/// The copy after the draws into the internal depth, closing the timestamp pair.
pub(super) fn record_depth_copy(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    (pipeline, bind, groups): &DepthCopy,
    ts: Timestamps<'_>,
) {
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: ts.compute().map(|t| wgpu::ComputePassTimestampWrites {
            beginning_of_pass_write_index: None,
            ..t
        }),
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind, &[]);
    pass.dispatch_workgroups(groups[0], groups[1], groups[2]);
}

impl PreparedPass for HardwareRaster {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        // The blended meshes' depth first, untimed: the pair brackets the ids' draws.
        if let Some((draws, copy)) = &self.glass {
            draws.record_with(encoder, None);
            record_depth_copy(encoder, &self.name, copy, Timestamps(None));
        }
        if let Some((cleared, copy)) = &self.far {
            drop(encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(&self.name),
                color_attachments: &[],
                depth_stencil_attachment: Some(depth_attachment(cleared, true)),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            }));
            record_depth_copy(encoder, &self.name, copy, Timestamps(None));
        }
        let Some(copy) = &self.copy else {
            self.draws.record_with(encoder, ts.render());
            return;
        };
        self.draws.record_with(encoder, draws_opening(ts));
        record_depth_copy(encoder, &self.name, copy, ts);
    }

    fn report(&self, _r: &Renderer) -> Result<Option<PassReport>, RenderError> {
        Ok(Some(PassReport::Fallback(self.report.clone())))
    }
}
