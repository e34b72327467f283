//! `VisibilityBuffer`: every opaque mesh's depth and triangle ids (see
//! `render::visibility_geometry` for the id convention, shared with the compute
//! rasterizer). Needs the adapter's `PRIMITIVE_INDEX`.

use super::{pass_error, PrepareCtx, PreparedPass, Timestamps};
use crate::graph::kinds::visibility_buffer::VISIBILITY;
use crate::graph::Name;
use crate::graph::{slot, ScheduledPass};
use crate::render::draws::{color_attachment, depth_attachment, DrawMode, MeshDraws, MeshSet};
use crate::render::visibility_geometry::NO_TRIANGLE;
use crate::render::RenderError;

pub(super) struct VisibilityBuffer {
    name: Name,
    depth: wgpu::TextureView,
    clear_depth: bool,
    ids: wgpu::TextureView,
    draws: MeshDraws,
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
) -> Result<VisibilityBuffer, RenderError> {
    let depth = sp.required(slot::DEPTH);
    let writes_depth = cx.graph.checked.desc.passes[sp.index]
        .writes
        .iter()
        .any(|w| w == depth);
    let target = IdTargets {
        depth: cx.view(&sp.name, depth)?,
        clear_depth: sp.clears(depth),
        writes_depth,
        ids: cx.view(&sp.name, sp.required(VISIBILITY))?,
    };
    draw_ids(cx, sp, target)
}

/// Where the opaque meshes' ids are drawn: the ids (cleared to `NO_TRIANGLE`) over a
/// single-sample Depth32Float depth, cleared to 1.0 or loaded.
pub(super) struct IdTargets {
    pub depth: wgpu::TextureView,
    pub clear_depth: bool,
    pub writes_depth: bool,
    pub ids: wgpu::TextureView,
}

/// The hardware visibility pass's draws into `target`, for `sp` (this kind's pass, or the
/// compute rasterizer's hardware fallback, which draws the same ids).
pub(super) fn draw_ids(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    target: IdTargets,
) -> Result<VisibilityBuffer, RenderError> {
    require_primitive_index(
        cx.device().features(),
        &cx.renderer.ctx.adapter.get_info().name,
        &sp.name,
    )?;
    let offered = cx.declared(sp)?;
    let draws = cx.renderer.mesh_draws(
        cx.gpu,
        DrawMode::Visibility {
            writes_depth: target.writes_depth,
        },
        MeshSet::Opaque,
        sp.samples,
        &sp.name,
        &offered,
    )?;
    Ok(VisibilityBuffer {
        name: sp.name.clone(),
        depth: target.depth,
        clear_depth: target.clear_depth,
        ids: target.ids,
        draws,
    })
}

/// Triangle ids come from `@builtin(primitive_index)`: refused, naming the pass and the
/// adapter, where the device lacks it.
fn require_primitive_index(
    features: wgpu::Features,
    adapter: &str,
    pass: &str,
) -> Result<(), RenderError> {
    if features.contains(wgpu::Features::PRIMITIVE_INDEX) {
        return Ok(());
    }
    Err(pass_error(
        pass,
        format!(
            "the visibility buffer writes triangle ids from the primitive index, which this adapter ({adapter}) does not offer (wgpu feature PRIMITIVE_INDEX)"
        ),
    ))
}

impl VisibilityBuffer {
    /// The draws in one render pass, with `timestamp_writes` (a fallback that runs more
    /// after it writes only the start).
    pub(super) fn record_with(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        // Integer targets clear to the colour's red as an integer: NO_TRIANGLE is exact in f64.
        let empty = wgpu::Color {
            r: f64::from(NO_TRIANGLE),
            g: 0.0,
            b: 0.0,
            a: 0.0,
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&self.name),
            color_attachments: &[Some(color_attachment(&self.ids, Some(empty), None))],
            depth_stencil_attachment: Some(depth_attachment(&self.depth, self.clear_depth)),
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        self.draws.record(&mut pass);
    }
}

impl PreparedPass for VisibilityBuffer {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        self.record_with(encoder, ts.render());
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn refuses_an_adapter_without_primitive_index() {
        let e = super::require_primitive_index(wgpu::Features::empty(), "SomeGPU", "vis")
            .unwrap_err()
            .to_string();
        assert!(e.contains("vis") && e.contains("SomeGPU"), "{e}");
        assert!(e.contains("PRIMITIVE_INDEX"), "{e}");
        super::require_primitive_index(wgpu::Features::PRIMITIVE_INDEX, "SomeGPU", "vis").unwrap();
    }
}
