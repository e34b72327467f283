//! `GBuffer`: every opaque mesh into one packed or two Rgba32Float textures (and the
//! material's surface into two more when the graph gives them). After a
//! depth prepass it loads that depth and only tests against it, so each pixel is
//! written once instead of once per overlapping surface. Multisampled, it draws at the
//! targets' sample count with centroid inputs, as MSAA forward shading does.

use super::{PrepareCtx, PreparedPass, Timestamps};
use crate::graph::kinds::g_buffer::{
    self as kind, G_GEOMETRIC, G_NORMAL, G_POSITION, G_SURFACE, G_UV1, G_UV1_GRAD, G_UV_GRAD,
};
use crate::graph::Name;
use crate::graph::{slot, ScheduledPass};
use crate::render::draws::{color_attachment, depth_attachment, DrawMode, MeshDraws, MeshSet};
use crate::render::RenderError;

pub(super) struct GBuffer {
    name: Name,
    depth: wgpu::TextureView,
    /// False after a depth prepass.
    clear_depth: bool,
    /// Positions, or the packed texture; then normals, geometric normals, the surface
    /// and the uv derivatives, those that are given.
    targets: Vec<wgpu::TextureView>,
    draws: MeshDraws,
}

pub(super) fn prepare(cx: &mut PrepareCtx, sp: &ScheduledPass) -> Result<GBuffer, RenderError> {
    let depth = sp.required(slot::DEPTH);
    let writes_depth = cx.graph.checked.desc.passes[sp.index]
        .writes
        .iter()
        .any(|w| w == depth);
    let packed = kind::packed(&sp.roles);
    let offered = cx.declared(sp)?;
    let geometric = sp.roles.slot(G_GEOMETRIC).is_some();
    let surface = super::deferred_shading::writes_surface(cx, sp);
    let uv1 = super::deferred_shading::writes_uv1(cx, sp);
    let mode = DrawMode::GBuffer {
        writes_depth,
        packed,
        normals: sp.roles.slot(G_NORMAL).is_some(),
        geometric,
        surface,
        uv1,
    };
    // The surface pairs are left unwritten where no material reads them: on GH100 the two
    // Rgba32Float targets cost the G-buffer pass 1.9 ms at 1080p on harada.
    let written = |slot: &str| {
        sp.roles.slot(slot).is_some()
            && match slot {
                G_SURFACE | G_UV_GRAD => surface,
                G_UV1 | G_UV1_GRAD => uv1,
                _ => true,
            }
    };
    // The positions, then the optional targets in the shader's order.
    let optional = &kind::TARGETS[1..];
    let count = 1 + optional.iter().filter(|s| written(s)).count() as u32;
    if let Some(problem) = attachment_problem(count, &cx.device().limits()) {
        return Err(super::pass_error(&sp.name, problem));
    }
    let draws = cx.renderer.mesh_draws(
        cx.gpu,
        mode,
        MeshSet::Opaque,
        sp.samples,
        &sp.name,
        &offered,
    )?;
    let mut targets = vec![cx.view(&sp.name, sp.required(G_POSITION))?];
    for &slot in optional {
        if let Some(name) = sp.roles.slot(slot).filter(|_| written(slot)) {
            targets.push(cx.view(&sp.name, name)?);
        }
    }
    Ok(GBuffer {
        name: sp.name.clone(),
        depth: cx.view(&sp.name, depth)?,
        clear_depth: sp.clears(depth),
        targets,
        draws,
    })
}

/// Why `targets` Rgba32Float colour targets (16 bytes a sample each) exceed the device's
/// colour attachment limits, if they do (wgpu would say so in its own words).
fn attachment_problem(targets: u32, limits: &wgpu::Limits) -> Option<String> {
    let bytes = 16 * targets;
    let (max_targets, max_bytes) = (
        limits.max_color_attachments,
        limits.max_color_attachment_bytes_per_sample,
    );
    (targets > max_targets || bytes > max_bytes).then(|| {
        format!("its {targets} Rgba32Float targets take {bytes} bytes a sample; the device allows {max_targets} colour targets and {max_bytes} bytes a sample (leave out g_geometric, or the surface pairs g_surface, g_uv_grad and g_uv1, g_uv1_grad)")
    })
}

impl PreparedPass for GBuffer {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        // w = -1 marks pixels where nothing was drawn.
        let empty = wgpu::Color {
            r: 0.0,
            g: 0.0,
            b: 0.0,
            a: -1.0,
        };
        let targets: Vec<_> = self
            .targets
            .iter()
            .map(|v| Some(color_attachment(v, Some(empty), None)))
            .collect();
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&self.name),
            color_attachments: &targets,
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
    use super::attachment_problem;

    #[test]
    fn targets_past_the_colour_attachment_limits_are_named() {
        // WebGPU's defaults: 8 targets, 32 bytes a sample.
        let limits = wgpu::Limits::default();
        assert_eq!(attachment_problem(2, &limits), None);
        let e = attachment_problem(4, &limits).unwrap();
        assert!(
            e.contains("its 4 Rgba32Float targets take 64 bytes a sample; the device allows 8 colour targets and 32 bytes"),
            "{e}"
        );
        let wide = wgpu::Limits {
            max_color_attachment_bytes_per_sample: 128,
            ..limits
        };
        assert_eq!(attachment_problem(5, &wide), None);
    }
}
