//! `ReflectiveShadowMaps`: lays out every indirect light's views (`indirect::rsm_views`),
//! uploads the view table, and draws the scene into each view's tile in one render pass
//! (normal, flux and position targets over depth; the view as the instance index). The
//! layout depends only on the lights (not the camera): made at prepare, and again on the
//! CPU for every light update, written into the same table (no pipeline or bind group
//! changes). With `raster: Compute` the views are rasterized in compute instead
//! (`reflective_shadow_maps_raster`; alpha-masked casters alpha-tested in a run of their
//! material's own).

use super::reflective_shadow_maps_raster::ComputeRsm;
use super::{pass_error, PrepareCtx, PreparedPass, Timestamps};
use crate::graph::kinds::reflective_shadow_maps::{
    fixed_size, ReflectiveShadowMaps, RsmRaster, RSM_DEPTH, RSM_FLUX, RSM_NORMAL, RSM_POSITION,
    RSM_VIEWS,
};
use crate::graph::Name;
use crate::graph::ScheduledPass;
use crate::indirect::rsm_views::{layout, layout_lights, view_table, RsmLayout};
use crate::render::draws::{color_attachment, depth_attachment, DrawMode, MeshDraws, MeshSet};
use crate::render::{RenderError, Renderer};
use crate::scene::{Light, VplControls};
use std::collections::BTreeMap;
use std::sync::Mutex;

/// What laying out the views again for new lights needs.
#[derive(Clone)]
pub(super) struct RsmLayoutRules {
    pub params: ReflectiveShadowMaps,
    pub width: u32,
    pub height: u32,
    /// The scene's VPL controls by light index.
    pub controls: BTreeMap<u32, VplControls>,
}

impl RsmLayoutRules {
    pub fn layout(&self, lights: &[Light]) -> RsmLayout {
        layout_lights(
            lights,
            &self.controls,
            self.params.tile,
            self.width,
            self.height,
            self.params.max_lights,
        )
    }
}

pub(super) struct RsmPass {
    name: Name,
    tile: u32,
    rules: RsmLayoutRules,
    /// Each view's tile origin, as the last layout placed them.
    origins: Mutex<Vec<(u32, u32)>>,
    views: wgpu::Buffer,
    staging: wgpu::Buffer,
    table_bytes: u64,
    raster: Raster,
}

/// Who draws the views.
enum Raster {
    Hardware(Box<HardwareMaps>),
    Compute(Box<ComputeRsm>),
}

/// One render pass: the mesh draws, a viewport a view, over the depth attachment.
struct HardwareMaps {
    depth: wgpu::TextureView,
    targets: [wgpu::TextureView; 3],
    draws: MeshDraws,
}

/// The maps drawn by the raster units.
fn hardware_maps(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    views: &wgpu::Buffer,
) -> Result<HardwareMaps, RenderError> {
    let mut offered = cx.declared(sp)?;
    offered.buffer("rsm_views", views);
    let draws = cx.renderer.mesh_draws(
        cx.gpu,
        DrawMode::Rsm,
        MeshSet::Opaque,
        1,
        &sp.name,
        &offered,
    )?;
    let depth = cx.view(&sp.name, sp.required(RSM_DEPTH))?;
    let target = |slot: &str| cx.view(&sp.name, sp.required(slot));
    Ok(HardwareMaps {
        depth,
        targets: [
            target(RSM_NORMAL)?,
            target(RSM_FLUX)?,
            target(RSM_POSITION)?,
        ],
        draws,
    })
}

/// The maps' size and the views laid out on them, as both RSM passes compute it.
pub(super) fn rsm_layout(
    cx: &PrepareCtx,
    pass: &str,
    p: &ReflectiveShadowMaps,
    flux: &str,
) -> Result<(u32, u32, RsmLayout), RenderError> {
    let desc = cx
        .graph
        .checked
        .desc
        .resources
        .iter()
        .find(|r| r.name() == flux);
    let (w, h, _) = fixed_size(desc)
        .ok_or_else(|| pass_error(pass, format!("'{flux}' is not a fixed-size texture")))?;
    Ok((w, h, layout(cx.scene, p.tile, w, h, p.max_lights)))
}

/// [`rsm_layout`]'s inputs, kept to lay the views out again for new lights.
pub(super) fn rsm_layout_rules(
    cx: &PrepareCtx,
    p: &ReflectiveShadowMaps,
    width: u32,
    height: u32,
) -> RsmLayoutRules {
    RsmLayoutRules {
        params: *p,
        width,
        height,
        controls: cx.scene.vpl_controls.clone(),
    }
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    p: &ReflectiveShadowMaps,
) -> Result<RsmPass, RenderError> {
    let (w, h, l) = rsm_layout(cx, &sp.name, p, sp.required(RSM_FLUX))?;
    let views = cx.buffer(&sp.name, sp.required(RSM_VIEWS))?;
    let table = view_table(&l, p.tile, w, h, p.max_views());
    let table_bytes = (table.len() * 16) as u64;
    if views.size() < table_bytes {
        return Err(pass_error(
            &sp.name,
            format!(
                "buffer '{}' holds {} bytes; the view table needs {table_bytes} (size: Auto)",
                sp.required(RSM_VIEWS),
                views.size()
            ),
        ));
    }
    let device = cx.device();
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("rsm view table (upload)"),
        size: table_bytes,
        usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    cx.renderer
        .ctx
        .queue
        .write_buffer(&staging, 0, bytemuck::cast_slice(&table));
    let raster = match p.raster {
        RsmRaster::Hardware => Raster::Hardware(Box::new(hardware_maps(cx, sp, &views)?)),
        RsmRaster::Compute => {
            let compute = ComputeRsm::prepare(cx, sp, p, (w, h), &views)?;
            compute.upload(&l);
            Raster::Compute(Box::new(compute))
        }
    };
    Ok(RsmPass {
        name: sp.name.clone(),
        tile: p.tile,
        rules: rsm_layout_rules(cx, p, w, h),
        origins: Mutex::new(l.views.iter().map(|v| (v.x, v.y)).collect()),
        views,
        staging,
        table_bytes,
        raster,
    })
}

impl PreparedPass for RsmPass {
    fn follow_lights(&self, r: &Renderer, lights: &[Light]) {
        let l = self.rules.layout(lights);
        let table = view_table(
            &l,
            self.tile,
            self.rules.width,
            self.rules.height,
            self.rules.params.max_views(),
        );
        r.ctx
            .queue
            .write_buffer(&self.staging, 0, bytemuck::cast_slice(&table));
        *self.origins.lock().unwrap_or_else(|e| e.into_inner()) =
            l.views.iter().map(|v| (v.x, v.y)).collect();
        if let Raster::Compute(compute) = &self.raster {
            compute.upload(&l);
        }
    }

    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        encoder.copy_buffer_to_buffer(&self.staging, 0, &self.views, 0, self.table_bytes);
        let HardwareMaps {
            depth,
            targets,
            draws,
        } = match &self.raster {
            Raster::Hardware(maps) => &**maps,
            Raster::Compute(compute) => return compute.record(encoder, &self.name, ts),
        };
        // The maps are small (a few MiB at most): clearing them whole costs nothing and
        // leaves unused tiles at zero flux.
        let clear = Some(wgpu::Color::TRANSPARENT);
        let colors: Vec<_> = targets
            .iter()
            .map(|t| Some(color_attachment(t, clear, None)))
            .collect();
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&self.name),
            color_attachments: &colors,
            depth_stencil_attachment: Some(depth_attachment(depth, true)),
            timestamp_writes: ts.render(),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let origins = self.origins.lock().unwrap_or_else(|e| e.into_inner());
        draws.record_tiles(&mut pass, &origins, self.tile);
    }
}
