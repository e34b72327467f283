//! `DeferredShading`: one compute dispatch per group of materials that share their code
//! (`render::materials::shared_code_groups`, as visibility shading groups them) over the
//! frame, reading the G-buffer and storing lit colour; each pixel's material index finds
//! its group and first constant in `material_groups`. From a multisampled G-buffer, one
//! dispatch per material, the mean of every sample's colour
//! (shaders/deferred/deferred_msaa.wgsl, which orders samples by material index). Textured materials sample
//! their textures at the G-buffer's uv with its uv derivatives (group 2, as visibility
//! shading binds them).

use super::{defines, pass_error, PrepareCtx, PreparedPass, Timestamps};
use crate::graph::kinds::deferred_shading::HDR;
use crate::graph::kinds::g_buffer::{G_NORMAL, G_SURFACE, G_UV1};
use crate::graph::Name;
use crate::graph::{DeferredShading, ScheduledPass};
use crate::render::pipelines::PipelineKey;
use crate::render::RenderError;
use std::collections::BTreeMap;
use std::sync::Arc;

pub(super) struct DeferredShadingPass {
    name: Name,
    dispatches: Vec<ShadeDispatch>,
    groups: [u32; 3],
}

/// One material's dispatch: its pipeline, group 0, and its textures (group 2), if any.
struct ShadeDispatch {
    pipeline: Arc<wgpu::ComputePipeline>,
    bind: wgpu::BindGroup,
    textures: Option<wgpu::BindGroup>,
}

/// Whether the G-buffer's surface pair (`g_surface`, `g_uv_grad`) is written and read:
/// where the graph gives it (the G-buffer pass and deferred shading name it alike) and a
/// material of the scene reads the uv, the tangent or the vertex colour. Without such a
/// material the pair would be bandwidth for nothing, so neither pass touches it.
pub(super) fn writes_surface(cx: &PrepareCtx, sp: &ScheduledPass) -> bool {
    sp.roles.slot(G_SURFACE).is_some()
        && cx
            .gpu
            .materials
            .iter()
            .any(|m| m.reads_uv_or_tangent || m.reads_vertex_color)
}

/// Whether the second uv set's pair (`g_uv1`, `g_uv1_grad`) is written and read: where the
/// graph gives it beside the surface pair and a material of the scene samples a texture
/// with TEXCOORD_1.
pub(super) fn writes_uv1(cx: &PrepareCtx, sp: &ScheduledPass) -> bool {
    writes_surface(cx, sp)
        && sp.roles.slot(G_UV1).is_some()
        && cx.gpu.materials.iter().any(|m| m.reads_uv1)
}

pub(super) fn prepare(
    cx: &mut PrepareCtx,
    sp: &ScheduledPass,
    p: &DeferredShading,
) -> Result<DeferredShadingPass, RenderError> {
    // Without a normals texture the G-buffer is the packed one.
    let packed = sp.roles.slot(G_NORMAL).is_none();
    let surface = writes_surface(cx, sp);
    let mut offered = cx.declared(sp)?;
    let lists = cx.shading_lists(sp, p.lights, &mut offered)?;
    let shadows = cx.shading_shadows(sp, &mut offered);
    let has_indirect_lights = cx.scene.features().has_indirect_lights;
    let vpl = super::VplLookup::of(cx, sp);
    // A multisampled G-buffer: every distinct sample shaded, the mean stored. Pixels whose
    // samples hold several materials sum over the materials' dispatches in `hdr`, which
    // each reads back (read-write storage; the MSAA formats already need the adapter's
    // format features).
    let msaa = sp.samples > 1;
    if msaa {
        let flags = cx
            .renderer
            .ctx
            .adapter
            .get_texture_format_features(wgpu::TextureFormat::Rgba32Float)
            .flags;
        let features = cx.device().features();
        if !features.contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES)
            || !flags.contains(wgpu::TextureFormatFeatureFlags::STORAGE_READ_WRITE)
        {
            return Err(pass_error(
                &sp.name,
                format!(
                    "a multisampled G-buffer needs read-write storage of Rgba32Float for '{}' (samples of several materials are summed there), which this adapter ({}) lacks",
                    sp.required(HDR),
                    cx.renderer.ctx.adapter.get_info().name
                ),
            ));
        }
    }
    if let Some(m) = cx
        .gpu
        .materials
        .iter()
        .find(|m| (m.reads_uv_or_tangent || m.reads_vertex_color) && !surface)
    {
        return Err(pass_error(
            &sp.name,
            format!("material '{}' reads textures, the tangent or the vertex colour: its G-buffer needs the surface targets '{G_SURFACE}' and 'g_uv_grad' (uv, tangent, vertex colour and uv derivatives), which this pass does not read", m.name),
        ));
    }
    // A graph without the second uv set's targets shades materials that read one
    // without it, said rather than left to be noticed in the image.
    let uv1 = writes_uv1(cx, sp);
    if let Some(m) = cx.gpu.materials.iter().find(|m| m.reads_uv1 && !uv1) {
        log::warn!(
            "pass '{}': material '{}' samples a texture with TEXCOORD_1, which this G-buffer does not carry (it names no '{G_UV1}' and 'g_uv1_grad'): it samples TEXCOORD_0 there",
            sp.name,
            m.name
        );
    }
    let all: Vec<usize> = (0..cx.gpu.materials.len()).collect();
    // The multisampled shader sums samples material by material: one dispatch each.
    let groups = if msaa {
        all.iter().map(|&i| vec![i]).collect()
    } else {
        let groups = crate::render::materials::shared_code_groups(&cx.gpu.materials, &all);
        offer_material_groups(cx, &groups, &mut offered);
        groups
    };
    let mut dispatches = Vec::new();
    for (slot, group) in groups.iter().enumerate() {
        let m = &cx.gpu.materials[group[0]];
        let textured = m.textures.is_some();
        let mut d = if msaa {
            vec![("MATERIAL_INDEX", group[0].to_string())]
        } else {
            vec![("GROUP_INDEX", format!("{slot}u"))]
        };
        // A group of several runs the shared code (constants from the buffer); a
        // material alone its own code.
        let shared = group.len() > 1;
        if shared {
            d.push(("SHARED_CODE", "1".into()));
        }
        if packed {
            d.push(("G_PACKED", "1".into()));
        }
        if msaa {
            d.push(("G_SAMPLES", sp.samples.to_string()));
        }
        if surface {
            d.push(("G_SURFACE", "1".into()));
        }
        if uv1 {
            d.push(("G_UV1", "1".into()));
        }
        if textured {
            d.push(("MATERIAL_TEXTURED", "1".into()));
        }
        d.extend(lists.define());
        d.extend(crate::render::draws::shadow_defines(shadows));
        d.extend(crate::render::draws::vpl_defines(has_indirect_lights));
        d.extend(super::VplLookup::defines(vpl));
        let key = PipelineKey {
            shader: "deferred/deferred_shading.wgsl".into(),
            defines: defines(&d),
            virtual_code: BTreeMap::from([(
                "material".to_string(),
                m.group_code(shared).to_string(),
            )]),
            state: String::new(),
        };
        let label = crate::render::materials::group_label(&sp.name, &cx.gpu.materials, group);
        let (pipeline, bind, textures) =
            cx.compute_pipeline_with_material(&label, key, "main", &offered, m.textures.as_ref())?;
        dispatches.push(ShadeDispatch {
            pipeline,
            bind,
            textures,
        });
    }
    Ok(DeferredShadingPass {
        name: sp.name.clone(),
        dispatches,
        groups: [cx.size.width.div_ceil(8), cx.size.height.div_ceil(8), 1],
    })
}

/// Offers `material_groups` (per material index: its group and first constant) and
/// `material_constants` (every grouped material's shared-code constants) to the dispatches.
fn offer_material_groups(
    cx: &PrepareCtx,
    groups: &[Vec<usize>],
    offered: &mut crate::render::bind::BindingSet,
) {
    let materials = &cx.gpu.materials;
    let constants = crate::render::materials::GroupConstants::new(materials, groups);
    let mut table = vec![[0u32; 2]; materials.len().max(1)];
    for (g, group) in groups.iter().enumerate() {
        for &i in group {
            table[i] = [g as u32, constants.first[i]];
        }
    }
    let device = cx.device();
    constants.offer(&device, offered);
    let table = crate::render::scene_gpu::storage_buffer(
        &device,
        "material groups",
        bytemuck::cast_slice(&table),
        wgpu::BufferUsages::empty(),
    );
    offered.buffer("material_groups", &table);
}

impl PreparedPass for DeferredShadingPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&self.name),
            timestamp_writes: ts.compute(),
        });
        let [x, y, z] = self.groups;
        for d in &self.dispatches {
            pass.set_pipeline(&d.pipeline);
            pass.set_bind_group(0, &d.bind, &[]);
            if let Some(t) = &d.textures {
                pass.set_bind_group(2, t, &[]);
            }
            pass.dispatch_workgroups(x, y, z);
        }
    }
}
