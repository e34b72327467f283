//! `LightCulling`: per-tile light lists from the prepass depth (Frustum, HalfZ,
//! DepthMask, Clustered), with an optional coarse stage. Runs `shaders/cull/light_culling.wgsl`.
//! A multisampled depth is read sample by sample. With a `transparent_depth` (a
//! TransparentDepth pass's) the lists are for transparent surfaces: a tile spans, over
//! its pixels that hold one, from the nearest transparent depth to the opaque depth
//! behind it (seed 004).

use super::{slot, Access, KindCtx, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::CullVariant;
use crate::graph::plan::ListLayout;
use serde::{Deserialize, Serialize};

/// `LightCulling(tile: 16, variant: Frustum, capacity: 256, coarse: 4)`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(deny_unknown_fields)]
pub struct LightCulling {
    /// Pixels per tile side: 8 or 16 (one workgroup of tile×tile invocations).
    pub tile: u32,
    #[serde(default)]
    pub variant: CullVariant,
    /// Most lights a tile (or a half, or a cluster) can list.
    #[serde(default = "default_capacity")]
    pub capacity: u32,
    /// Tiles per side of a coarse tile culled first: fine tiles then test only
    /// their coarse tile's lights instead of every light. 0 or 1 turns it off.
    #[serde(default = "default_coarse")]
    pub coarse: u32,
}

fn default_capacity() -> u32 {
    256
}
fn default_coarse() -> u32 {
    4
}

impl LightCulling {
    pub fn list_layout(&self, width: u32, height: u32) -> ListLayout {
        ListLayout::new(self.tile, self.variant, self.capacity, width, height)
    }
}

pub const SLOTS: &[SlotSpec] = &[
    SlotSpec::new(
        slot::DEPTH,
        SlotType::DepthTexture,
        Access::Read,
        Usage::Sampled,
    ),
    super::LIGHT_GEOMETRY_READ,
    SlotSpec::new(
        slot::LIGHT_LISTS,
        SlotType::Buffer,
        Access::Write,
        Usage::Bound,
    ),
    SlotSpec::new(
        slot::TRANSPARENT_DEPTH,
        SlotType::DepthTexture,
        Access::Read,
        Usage::Sampled,
    )
    .optional(),
];

pub fn check(p: &LightCulling, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    if let (Some(depth), Some(t)) = (ctx.slot(slot::DEPTH), ctx.slot(slot::TRANSPARENT_DEPTH)) {
        let (ds, ts) = (ctx.samples(depth), ctx.samples(t));
        if ds != ts {
            errors.push(ctx.mismatch(
                t,
                format!("transparent depth has {ts} sample(s) but depth '{depth}' has {ds}: culling compares them sample by sample"),
            ));
        }
    }
    if !matches!(p.tile, 8 | 16) {
        errors.push(ctx.bad(format!(
            "tile size {} is not supported (8 or 16: one workgroup of tile×tile invocations)",
            p.tile
        )));
    }
    if p.capacity == 0 || p.capacity > 4096 {
        errors.push(ctx.bad(format!("capacity {} must be in 1..=4096", p.capacity)));
    }
    if p.coarse > 16 {
        errors.push(ctx.bad(format!(
            "coarse {} must be in 0..=16 tiles per side (0 or 1: no coarse stage)",
            p.coarse
        )));
    }
    if let CullVariant::Clustered { slices } = p.variant {
        if slices == 0 || slices > 64 {
            errors.push(ctx.bad(format!("clustered slices {slices} must be in 1..=64")));
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::{errors, PREPASS};

    #[test]
    fn checks_parameters() {
        let e = errors(
            &format!(
                r#"{PREPASS} Pass(name: "c", kind: LightCulling(tile: 12, capacity: 0, coarse: 17, variant: Clustered(slices: 65)), reads: ["depth", "lg"], writes: ["lists"])"#
            ),
            "hdr",
        );
        for want in [
            "tile size 12",
            "capacity 0",
            "coarse 17",
            "clustered slices 65",
        ] {
            assert!(e.contains(want), "{want}: {e}");
        }
    }

    #[test]
    fn lists_must_be_written_and_depths_alike() {
        let e = errors(
            &format!(
                r#"{PREPASS} Pass(name: "c", kind: LightCulling(tile: 16), reads: ["depth", "lg", "lists"])"#
            ),
            "hdr",
        );
        assert!(
            e.contains("LightCulling needs a buffer in writes (slot 'light_lists')"),
            "{e}"
        );
        crate::graph::kinds::test_support::validate(
            r#"Pass(name: "pre", kind: DepthPrepass, writes: ["depth4"]), Pass(name: "c", kind: LightCulling(tile: 16), reads: ["depth4", "lg"], writes: ["lists"]), Pass(name: "s", kind: ForwardShading(lights: Culled), reads: ["depth4", "lg", "lp", "lists"], writes: ["hdr4"])"#,
            "hdr",
        )
        .map_err(|e| e.to_string())
        .or_else(|e| {
            // The graph's output is never written; the MSAA culling itself must pass.
            assert!(!e.contains("pass 'c'"), "{e}");
            Ok::<(), String>(())
        })
        .unwrap();
        let e = errors(
            r#"Pass(name: "pre", kind: DepthPrepass, writes: ["depth4"]), Pass(name: "tp", kind: TransparentDepth, writes: ["depth"]), Pass(name: "c", kind: LightCulling(tile: 16), reads: ["depth4", "transparent_depth=depth", "lg"], writes: ["lists"])"#,
            "hdr",
        );
        assert!(
            e.contains("transparent depth has 1 sample(s) but depth 'depth4' has 4"),
            "{e}"
        );
    }
}
