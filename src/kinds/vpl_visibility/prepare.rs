//! `VplVisibility`: one workgroup a block of pixels, its rays cast in the loop
//! (shaders/indirect/vpl_visibility.wgsl). The VPL count is read on the GPU from the
//! light arrays VplSpawn wrote, so nothing is read back within the frame.

use super::{defines, PrepareCtx, PreparedPass, Timestamps};
use crate::graph::kinds::shadow_ray_cast::DEFAULT_NORMAL_OFFSET;
use crate::graph::kinds::vpl_visibility::VplVisibility;
use crate::graph::Name;
use crate::graph::ScheduledPass;
use crate::render::pipelines::PipelineKey;
use crate::render::RenderError;
use std::collections::BTreeMap;
use std::sync::Arc;

pub(super) struct VplVisibilityPass {
    name: Name,
    pipeline: Arc<wgpu::ComputePipeline>,
    bind: wgpu::BindGroup,
    groups: [u32; 2],
}

impl PreparedPass for VplVisibilityPass {
    fn record(&self, encoder: &mut wgpu::CommandEncoder, ts: Timestamps<'_>) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&self.name),
            timestamp_writes: ts.compute(),
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind, &[]);
        pass.dispatch_workgroups(self.groups[0], self.groups[1], 1);
    }
}

pub(super) fn prepare(
    cx: &mut PrepareCtx<'_>,
    sp: &ScheduledPass,
    p: &VplVisibility,
) -> Result<VplVisibilityPass, RenderError> {
    let offered = cx.declared(sp)?;
    let mut d = vec![
        ("VPL_BLOCK", format!("{}u", p.block)),
        ("VPL_WORDS", format!("{}u", p.words())),
        ("SHADOW_NORMAL_OFFSET", format!("{DEFAULT_NORMAL_OFFSET:?}")),
    ];
    d.extend(super::shadow_ray_jobs::surface_define(&sp.roles));
    let key = PipelineKey {
        shader: "indirect/vpl_visibility.wgsl".into(),
        defines: defines(&d),
        virtual_code: BTreeMap::new(),
        state: String::new(),
    };
    let (pipeline, bind) = cx.compute_pipeline(&sp.name, key, "main", &offered)?;
    let (x, y) = p.blocks(cx.size.width, cx.size.height);
    Ok(VplVisibilityPass {
        name: sp.name.clone(),
        pipeline,
        bind,
        groups: [x, y],
    })
}

/// How a shading pass looks VPL visibility up: the bits' layout as the `VplVisibility`
/// pass writing its `vpl_visibility` read published it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct VplLookup {
    block: u32,
    words: u32,
}

impl VplLookup {
    /// The shading pass's lookup, if it reads `vpl_visibility` and the scene has
    /// indirect lights (without them the visibility pass does not run and there are
    /// no VPLs to hide).
    pub(crate) fn of(cx: &PrepareCtx, sp: &ScheduledPass) -> Option<Self> {
        use crate::graph::kinds::vpl_visibility::VPL_VISIBILITY;
        if !cx.scene.features().has_indirect_lights {
            return None;
        }
        let name = sp.roles.slot(VPL_VISIBILITY)?;
        match cx.graph.plan.get(name).and_then(|r| r.layout) {
            Some(crate::graph::BufferLayout::VplVisibility { block, words, .. }) => {
                Some(Self { block, words })
            }
            _ => None,
        }
    }
    /// The light loop's defines (shaders/indirect/vpl_lookup.wgsl).
    pub(crate) fn defines(lookup: Option<Self>) -> Vec<(&'static str, String)> {
        match lookup {
            None => vec![],
            Some(l) => vec![
                ("VPL_VISIBILITY", "1".into()),
                ("VPL_BLOCK", format!("{}u", l.block)),
                ("VPL_WORDS", format!("{}u", l.words)),
            ],
        }
    }
}
