//! `ReflectiveShadowMaps(raster: Compute)`: the maps' views rasterized in compute, off
//! the raster units (a GH100 runs graphics on a few of its SMs and compute on all).
//!
//! The triangles go through the shadow atlas's compute rasterizer
//! (`shadow_atlas_raster`, `shaders/shadow/atlas_raster.wgsl`) over the RSM view table:
//! the opaque meshes, each view given the shadow chunks (`shadow::chunks`) whose bounds
//! touch its frustum (the hardware pass draws every mesh whole into every view: a
//! chunk outside draws nothing), no depth bias. Its first pass keeps each texel's
//! nearest depth by a 32-bit atomic min; its second (IDS) the nearest triangle, by an
//! atomic max of its visibility id where the depth matches (ties go to the later draw,
//! as the hardware pass's LessEqual test). Two 32-bit passes rather than one
//! 64-bit atomic of (depth, id): they need no device feature (`ComputeRaster`'s 64-bit
//! atomic min is an optional one, with a hardware fallback), and the second pass only
//! redoes the small views' setup. Then `shaders/indirect/rsm_raster.wgsl`: a resolve
//! dispatch per material with triangles stores the normal, flux and position of its
//! texels (the hardware pass's fragment code, `indirect/rsm_texel.wgsl`), and a store
//! writes the depth, clears the texels nothing covers and puts the buffers back.
//! All in one compute pass.

use super::shadow_atlas_raster::{ComputeAtlas, RasterTarget};
use super::{defines, grid, pass_error, PrepareCtx, Timestamps};
use crate::graph::kinds::reflective_shadow_maps::{ReflectiveShadowMaps, VIEW_VEC4S};
use crate::graph::ScheduledPass;
use crate::indirect::rsm_views::RsmLayout;
use crate::render::pipelines::PipelineKey;
use crate::render::RenderError;
use crate::shadow::chunks::Chunk;
use crate::shadow::view_bounds::{box_in_frustum, frustum_planes};
use std::collections::BTreeMap;
use std::sync::Arc;

const SHADER: &str = "indirect/rsm_raster.wgsl";
/// Texels per side of a resolve or store workgroup's piece of a tile.
const PIECE: u32 = 16;

/// A pipeline with its bind groups (group 0, and the material's textures in group 2).
struct Dispatch {
    pipeline: Arc<wgpu::ComputePipeline>,
    bind: wgpu::BindGroup,
    textures: Option<wgpu::BindGroup>,
}

impl Dispatch {
    fn run(&self, pass: &mut wgpu::ComputePass<'_>, groups: [u32; 3]) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind, &[]);
        if let Some(t) = &self.textures {
            pass.set_bind_group(2, t, &[]);
        }
        pass.dispatch_workgroups(groups[0], groups[1], groups[2]);
    }
}

pub(super) struct ComputeRsm {
    raster: ComputeAtlas,
    /// One per material with opaque triangles.
    resolves: Vec<Dispatch>,
    store: Dispatch,
    /// (pieces, workgroups per dimension, texels a row, tile).
    params: wgpu::Buffer,
    pieces: wgpu::Buffer,
    /// Each caster mesh's world bounds and shadow chunks, in draw order.
    meshes: Vec<([glam::Vec3; 2], Arc<[Chunk]>)>,
    tile: u32,
    width: u32,
    max_groups: u32,
    queue: wgpu::Queue,
    /// Pieces listed by the last upload.
    listed: std::sync::Mutex<u32>,
}

impl ComputeRsm {
    /// The compute path for pass `sp` with parameters `p`, over maps of `width`×`height`
    /// and the view table `views`.
    pub(super) fn prepare(
        cx: &mut PrepareCtx,
        sp: &ScheduledPass,
        p: &ReflectiveShadowMaps,
        (width, height): (u32, u32),
        views: &wgpu::Buffer,
    ) -> Result<Self, RenderError> {
        let device = cx.device();
        let casters = cx.gpu.opaque_draws();
        // Alpha-masked casters are alpha-tested by runs of their own.
        let raster = ComputeAtlas::prepare(
            cx,
            &sp.name,
            &casters,
            RasterTarget::Buffers { width, height },
            views,
            VIEW_VEC4S,
            0,
            0.0,
        )?;
        let Some(ids) = raster.ids().cloned() else {
            return Err(pass_error(
                &sp.name,
                "the raster kept no triangle ids".into(),
            ));
        };
        let geometry = cx
            .gpu
            .visibility_geometry(&device, cx.scene)
            .map_err(|m| pass_error(&sp.name, m))?;
        let (vertices, triangles, material_triangles) = (
            geometry.vertices.clone(),
            geometry.triangles.clone(),
            geometry.material_triangles.clone(),
        );
        let ranges = geometry.material_ranges.clone();
        let meshes = casters
            .iter()
            .map(|&m| (cx.gpu.meshes[m].bounds, cx.gpu.meshes[m].chunks.clone()))
            .collect();
        let step = p.tile.min(PIECE);
        let most_pieces = (width / step) as u64 * (height / step) as u64;
        let storage = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(16),
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let pieces = storage(
            "rsm raster pieces",
            16 * most_pieces,
            wgpu::BufferUsages::STORAGE,
        );
        let params = storage("rsm raster parameters", 16, wgpu::BufferUsages::UNIFORM);
        // The declared slots (the lights, the view table and the four textures, under
        // their slot names) and the pass's own buffers.
        let mut offered = cx.declared(sp)?;
        for (name, buffer) in [
            ("rsm_params", &params),
            ("rsm_pieces", &pieces),
            ("rsm_depth_bits", raster.depth()),
            ("rsm_ids", &ids),
            ("vertices", &vertices),
            ("triangles", &triangles),
            ("material_triangles", &material_triangles),
        ] {
            offered.buffer(name, buffer);
        }
        let key = |d: &[(&str, String)], entry: &str, code: Option<&str>| PipelineKey {
            shader: SHADER.into(),
            defines: defines(d),
            virtual_code: code
                .map(|c| BTreeMap::from([("material".to_string(), c.to_string())]))
                .unwrap_or_default(),
            state: entry.into(),
        };
        let piece = ("STORE_CELL", PIECE.to_string());
        let (pipeline, bind) = cx.compute_pipeline(
            &sp.name,
            key(&[piece.clone(), ("STORE", "1".into())], "store", None),
            "store",
            &offered,
        )?;
        let store = Dispatch {
            pipeline,
            bind,
            textures: None,
        };
        let mut resolves = Vec::new();
        for (index, &[first, end]) in ranges.iter().enumerate() {
            if first == end {
                continue;
            }
            let m = &cx.gpu.materials[index];
            let mut d = vec![
                piece.clone(),
                ("RESOLVE", "1".into()),
                ("MATERIAL_INDEX", format!("{index}u")),
            ];
            if m.textures.is_some() {
                d.push(("MATERIAL_TEXTURED", "1".into()));
            }
            let (code, textures) = (m.wgsl_for_compute().to_string(), m.textures.clone());
            let label = format!("{} (material '{}')", sp.name, m.name);
            let (pipeline, bind, textures) = cx.compute_pipeline_with_material(
                &label,
                key(&d, "resolve", Some(&code)),
                "resolve",
                &offered,
                textures.as_ref(),
            )?;
            resolves.push(Dispatch {
                pipeline,
                bind,
                textures,
            });
        }
        Ok(ComputeRsm {
            raster,
            resolves,
            store,
            params,
            pieces,
            meshes,
            tile: p.tile,
            width,
            max_groups: device.limits().max_compute_workgroups_per_dimension.max(1),
            queue: cx.renderer.ctx.queue.clone(),
            listed: std::sync::Mutex::new(0),
        })
    }

    /// Lists the work for `layout`'s views (written before the next submission): per
    /// view a job for each run of chunks whose bounds touch its frustum (as the atlas
    /// culls its views), and its tile's pieces.
    pub(super) fn upload(&self, layout: &RsmLayout) {
        let mut jobs = self.raster.job_lists();
        let mut rects = Vec::new();
        let mut pieces: Vec<[u32; 4]> = Vec::new();
        let step = self.tile.min(PIECE);
        for (v, view) in layout.views.iter().enumerate() {
            let v = v as u32;
            rects.push([view.x, view.y, self.tile, 0]);
            let planes = frustum_planes(view.view_proj);
            for (draw, ([lo, hi], chunks)) in self.meshes.iter().enumerate() {
                if !box_in_frustum(&planes, *lo, *hi) {
                    continue;
                }
                for c in chunks
                    .iter()
                    .filter(|c| box_in_frustum(&planes, c.min, c.max))
                {
                    jobs.push(v, draw, c.first, c.count);
                }
            }
            for py in (0..self.tile).step_by(step as usize) {
                for px in (0..self.tile).step_by(step as usize) {
                    pieces.push([view.x + px, view.y + py, step, v]);
                }
            }
        }
        // The store's pieces carry their view; the raster's are not used (no store).
        let work = jobs.finish(rects, Vec::new());
        self.raster.upload(&work);
        if !pieces.is_empty() {
            let room = (self.pieces.size() / 16) as usize;
            pieces.truncate(room);
            self.queue
                .write_buffer(&self.pieces, 0, bytemuck::cast_slice(&pieces));
        }
        let params = [pieces.len() as u32, self.max_groups, self.width, self.tile];
        self.queue
            .write_buffer(&self.params, 0, bytemuck::cast_slice(&params));
        *self.listed.lock().unwrap_or_else(|e| e.into_inner()) = pieces.len() as u32;
    }

    /// The raster, the resolves and the store: one compute pass (after the view table's
    /// copy, recorded before it).
    pub(super) fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        ts: Timestamps<'_>,
    ) {
        self.raster.clear_lists(encoder);
        let listed = *self.listed.lock().unwrap_or_else(|e| e.into_inner());
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: ts.compute(),
        });
        self.raster.record_into(&mut pass);
        if listed == 0 {
            return;
        }
        let groups = grid(listed, 1, self.max_groups);
        for resolve in &self.resolves {
            resolve.run(&mut pass, groups);
        }
        self.store.run(&mut pass, groups);
    }
}
