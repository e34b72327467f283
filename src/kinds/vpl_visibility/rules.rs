//! `VplVisibility`: which virtual point lights each block of pixels sees. One any-hit ray
//! against the shadow BVH per (block, VPL in reach) from the block's covered pixel
//! nearest its centre, its surface read as the ray-cast shadow passes read it (a
//! G-buffer or a visibility buffer: [`super::shadow_ray_jobs::SurfaceSource`]); writes a
//! bit per VPL and block that shading passes reading `vpl_visibility` multiply the VPL's
//! light by. Runs `shaders/indirect/vpl_visibility.wgsl`.

use super::shadow_ray_jobs::{check_surface_source, SURFACE_SLOTS};
use super::{Access, BufferLayout, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::plan::FrameSize;
use serde::{Deserialize, Serialize};

/// `VplVisibility(block: 8, max_vpls: 1024)`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(deny_unknown_fields)]
pub struct VplVisibility {
    /// Pixels per side of a block that shares one ray per VPL: 1 (a ray per pixel and
    /// VPL), 2, 4, 8 or 16.
    #[serde(default = "default_block")]
    pub block: u32,
    /// VPLs given a visibility bit (a multiple of 32, at most 16384); VPLs past it light
    /// without visibility.
    #[serde(default = "default_max_vpls")]
    pub max_vpls: u32,
}

fn default_block() -> u32 {
    8
}

fn default_max_vpls() -> u32 {
    1024
}

impl Default for VplVisibility {
    fn default() -> Self {
        Self {
            block: default_block(),
            max_vpls: default_max_vpls(),
        }
    }
}

impl VplVisibility {
    /// Words of visibility bits a block.
    pub fn words(&self) -> u32 {
        self.max_vpls / 32
    }
    /// Blocks across and down a `width`×`height` frame.
    pub fn blocks(&self, width: u32, height: u32) -> (u32, u32) {
        (width.div_ceil(self.block), height.div_ceil(self.block))
    }
}

pub(crate) const VPL_VISIBILITY: &str = "vpl_visibility";

pub(crate) const SLOTS: &[SlotSpec] = &[
    SURFACE_SLOTS[0],
    SURFACE_SLOTS[1],
    SURFACE_SLOTS[2],
    SURFACE_SLOTS[3],
    SURFACE_SLOTS[4],
    super::LIGHT_GEOMETRY_READ,
    super::LIGHT_PROPERTIES_READ,
    SlotSpec::new(
        super::shadow_ray_cast::BVH_NODES,
        SlotType::Import(crate::graph::model::SceneResource::BvhNodes),
        Access::Read,
        Usage::Bound,
    ),
    SlotSpec::new(
        super::shadow_ray_cast::BVH_TRIANGLES,
        SlotType::Import(crate::graph::model::SceneResource::BvhTriangles),
        Access::Read,
        Usage::Bound,
    ),
    SlotSpec::new(
        VPL_VISIBILITY,
        SlotType::Buffer,
        Access::Write,
        Usage::Bound,
    ),
];

pub(crate) fn check(p: &VplVisibility, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    if !matches!(p.block, 1 | 2 | 4 | 8 | 16) {
        errors.push(ctx.bad(format!(
            "block {} must be 1, 2, 4, 8 or 16 (pixels per side)",
            p.block
        )));
    }
    if p.max_vpls == 0 || !p.max_vpls.is_multiple_of(32) || p.max_vpls > 16384 {
        errors.push(ctx.bad(format!(
            "max_vpls {} must be a multiple of 32 in 32..=16384",
            p.max_vpls
        )));
    }
    check_surface_source(ctx, errors);
}

impl KindRules for VplVisibility {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(self, ctx, errors)
    }
    fn buffer_layout(&self, slot: &str, frame: FrameSize) -> Option<BufferLayout> {
        (slot == VPL_VISIBILITY).then(|| {
            let (x, y) = self.blocks(frame.width, frame.height);
            BufferLayout::VplVisibility {
                block: self.block,
                words: self.words(),
                blocks: u64::from(x) * u64::from(y),
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::errors;

    #[test]
    fn checks_block_vpls_and_surfaces() {
        let e = errors(
            r#"Pass(name: "v", kind: VplVisibility(block: 3, max_vpls: 40), reads: ["visibility", "vertices", "triangles", "lg", "lp", "bn", "bt"], writes: ["mask"])"#,
            "hdr",
        );
        assert!(e.contains("block 3 must be 1, 2, 4, 8 or 16"), "{e}");
        assert!(e.contains("max_vpls 40 must be a multiple of 32"), "{e}");
        let e = errors(
            r#"Pass(name: "v", kind: VplVisibility(), reads: ["lg", "lp", "bn", "bt"], writes: ["mask"])"#,
            "hdr",
        );
        assert!(
            e.contains("VplVisibility needs the pixels' surfaces"),
            "{e}"
        );
    }
}
