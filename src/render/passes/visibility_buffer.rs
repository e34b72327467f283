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
    require_primitive_index(
        cx.device().features(),
        &cx.renderer.ctx.adapter.get_info().name,
        &sp.name,
    )?;
    let depth = sp.required(slot::DEPTH);
    let writes_depth = cx.graph.checked.desc.passes[sp.index]
        .writes
        .iter()
        .any(|w| w == depth);
    let offered = cx.declared(sp)?;
    let draws = cx.renderer.mesh_draws(
        cx.gpu,
        DrawMode::Visibility { writes_depth },
        MeshSet::Opaque,
        sp.samples,
        &sp.name,
        &offered,
    )?;
    Ok(VisibilityBuffer {
        name: sp.name.clone(),
        depth: cx.view(&sp.name, depth)?,
        clear_depth: sp.clears(depth),
        ids: cx.view(&sp.name, sp.required(VISIBILITY))?,
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

impl PreparedPass for VisibilityBuffer {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
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
            timestamp_writes: ts.render(),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        self.draws.record(&mut pass);
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
