//! `LightSampling`: stochastic direct lighting with shadow rays. Per pixel of a visibility
//! buffer, the `exact_lights` shadow-casting lights of the pixel's tile list with the largest
//! unshadowed contribution get an exact shadow ray each; the others are estimated by
//! resampled importance sampling (Talbot et al., "Importance Resampling for Global
//! Illumination"): `samples` independent weighted reservoirs, each streaming `candidates`
//! lights drawn uniformly from the list, keep one light in proportion to its unshadowed
//! contribution, and one shadow ray tests it. With `reuse: Biased(..)` or `Unbiased(..)`
//! each reservoir is then combined with the same reservoir of random neighbours (spatial
//! reuse of Bitterli et al., "Spatiotemporal reservoir resampling for real-time ray tracing
//! with dynamic direct lighting"). `VisibilityShading` reading the `light_samples` buffer
//! shades the exact lights and the chosen samples. Runs `shaders/lighting/light_sampling.wgsl`.

use super::shadow_ray_cast::{BVH_NODES, BVH_TRIANGLES};
use super::visibility_buffer::VISIBILITY;
use super::visibility_shading::{TRIANGLES, VERTICES};
use super::{slot, Access, BufferLayout, Contents, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::SceneResource;
use crate::graph::plan::FrameSize;
use serde::{Deserialize, Serialize};

/// `LightSampling(candidates: 8, samples: 1, exact_lights: 4, reuse: Off, seed: 0)`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LightSampling {
    /// Candidates a reservoir streams (M), drawn uniformly from the pixel's tile list.
    #[serde(default = "default_candidates")]
    pub candidates: u32,
    /// Reservoirs a pixel, each one light and one shadow ray (k).
    #[serde(default = "default_samples")]
    pub samples: u32,
    /// Shadow-casting lights a pixel traced exactly (N): those with the largest
    /// unshadowed contribution, left out of the sampling.
    #[serde(default = "default_exact_lights")]
    pub exact_lights: u32,
    /// Where the exact lights are chosen: for each pixel from its whole list, or once for
    /// each 8×8 block of pixels.
    #[serde(default)]
    pub exact_per: ExactPer,
    /// Spatial reuse of the reservoirs over neighbouring pixels.
    #[serde(default)]
    pub reuse: SpatialReuse,
    /// Temporal reuse: 0 for none; else each reservoir also resamples the previous
    /// frame's reservoir of the pixel its surface was seen at (reprojected; rejected where
    /// the position or normal changed), whose candidates count at most
    /// `history` × `candidates`.
    #[serde(default)]
    pub history: u32,
    /// Mixed with the frame counter and the pixel into each pixel's random numbers.
    #[serde(default)]
    pub seed: u32,
    /// Shadow ray origin offset, as `ShadowRayCast`'s.
    #[serde(default = "default_normal_offset")]
    pub normal_offset: f32,
}

/// Where a pixel's `exact_lights` come from.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
pub enum ExactPer {
    /// The lights of the pixel's list with the largest target at the pixel: its list is
    /// walked once a pixel.
    #[default]
    Pixel,
    /// The lights with the largest target at any of four points of the pixel's 8×8 block
    /// (lists walked once a block, by the block's 64 invocations together); each pixel
    /// traces the block's lights that reach it. Exact where the block's points see the
    /// lights that matter to every pixel of it; the estimate stays unbiased either way.
    Block,
}

/// Spatial reuse: each of a pixel's reservoirs resamples its own and the same reservoir
/// of `neighbours` pixels drawn within `radius` pixels (neighbours whose depth or normal
/// differ much are skipped).
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
pub enum SpatialReuse {
    /// No reuse: each pixel keeps its own reservoirs.
    #[default]
    Off,
    /// Normalised by every candidate combined (1/M): biased where a neighbour's sample
    /// could not have been drawn at this pixel (other tile list, exact set or facing).
    Biased {
        /// Neighbours a reservoir resamples.
        neighbours: u32,
        /// Pixels from this one they are drawn within.
        radius: u32,
    },
    /// Normalised only by the candidates of the pixels whose target is non-zero at the
    /// chosen light (the 1/Z weight of Bitterli et al.): unbiased.
    Unbiased {
        /// Neighbours a reservoir resamples.
        neighbours: u32,
        /// Pixels from this one they are drawn within.
        radius: u32,
    },
}

impl SpatialReuse {
    /// (neighbours, radius, unbiased) when on.
    pub fn spatial(self) -> Option<(u32, u32, bool)> {
        match self {
            SpatialReuse::Off => None,
            SpatialReuse::Biased { neighbours, radius } => Some((neighbours, radius, false)),
            SpatialReuse::Unbiased { neighbours, radius } => Some((neighbours, radius, true)),
        }
    }
}

fn default_candidates() -> u32 {
    8
}
fn default_samples() -> u32 {
    1
}
fn default_exact_lights() -> u32 {
    4
}
fn default_normal_offset() -> f32 {
    super::shadow_ray_cast::DEFAULT_NORMAL_OFFSET
}

pub(crate) const LIGHT_SAMPLES: &str = "light_samples";
/// Most of each parameter the shader's private arrays are sized for.
pub(crate) const MAX_CANDIDATES: u32 = 1024;
pub(crate) const MAX_SAMPLES: u32 = 8;
pub(crate) const MAX_EXACT_LIGHTS: u32 = 16;
pub(crate) const MAX_NEIGHBOURS: u32 = 16;
pub(crate) const MAX_RADIUS: u32 = 128;
pub(crate) const MAX_HISTORY: u32 = 64;

/// Words before the per-pixel data: the frame counter, three unused, the previous frame's
/// view-projection (16 f32).
pub(crate) const SAMPLE_HEADER_WORDS: u64 = 20;
/// Words of a pixel's surface kept for the next frame (position, geometric normal).
pub(crate) const SURFACE_WORDS: u64 = 6;
/// Words a reservoir: light index, contribution weight W (f32), candidates M (f32).
pub(crate) const RESERVOIR_WORDS: u64 = 3;

/// The `light_samples` buffer: a header, `exact` light words a pixel (bit 31 set where
/// the light is hidden), then regions of `samples` reservoirs a pixel: the pixel's own
/// (after temporal reuse), after spatial reuse, and with temporal reuse two history
/// regions and two of surfaces, one written and one read each frame; shading reads the
/// own region, or the spatial one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SampleLayout {
    /// Pixels of the frame.
    pub pixels: u64,
    /// Exact lights a pixel.
    pub exact: u32,
    /// Reservoirs a pixel.
    pub samples: u32,
    /// Whether a second region holds the reservoirs after spatial reuse.
    pub spatial: bool,
    /// Whether history regions and surfaces follow (temporal reuse).
    pub history: bool,
}

impl SampleLayout {
    /// The buffer's size in bytes.
    pub fn bytes(&self) -> u64 {
        let regions = 1 + u64::from(self.spatial) + 2 * u64::from(self.history);
        let surfaces = if self.history { 2 * SURFACE_WORDS } else { 0 };
        4 * (SAMPLE_HEADER_WORDS
            + self.pixels * u64::from(self.exact)
            + regions * self.pixels * u64::from(self.samples) * RESERVOIR_WORDS
            + self.pixels * surfaces)
    }
}

pub(crate) const SLOTS: &[SlotSpec] = &[
    SlotSpec::new(
        VISIBILITY,
        SlotType::ColorTexture,
        Access::Read,
        Usage::Sampled,
    ),
    SlotSpec::new(
        VERTICES,
        SlotType::Import(SceneResource::Vertices),
        Access::Read,
        Usage::Bound,
    ),
    SlotSpec::new(
        TRIANGLES,
        SlotType::Import(SceneResource::Triangles),
        Access::Read,
        Usage::Bound,
    ),
    super::LIGHT_GEOMETRY_READ,
    super::LIGHT_PROPERTIES_READ,
    SlotSpec::new(
        slot::LIGHT_LISTS,
        SlotType::Buffer,
        Access::Read,
        Usage::Bound,
    )
    .needs(&[Contents::LightLists]),
    SlotSpec::new(
        BVH_NODES,
        SlotType::Import(SceneResource::BvhNodes),
        Access::Read,
        Usage::Bound,
    ),
    SlotSpec::new(
        BVH_TRIANGLES,
        SlotType::Import(SceneResource::BvhTriangles),
        Access::Read,
        Usage::Bound,
    ),
    SlotSpec::new(LIGHT_SAMPLES, SlotType::Buffer, Access::Write, Usage::Bound),
];

pub(crate) fn check(p: &LightSampling, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    let mut range = |what: &str, v: u32, lo: u32, hi: u32| {
        if !(lo..=hi).contains(&v) {
            errors.push(ctx.bad(format!("{what} {v} must be in {lo}..={hi}")));
        }
    };
    range("candidates", p.candidates, 1, MAX_CANDIDATES);
    range("samples", p.samples, 1, MAX_SAMPLES);
    range("exact_lights", p.exact_lights, 0, MAX_EXACT_LIGHTS);
    if let Some((neighbours, radius, _)) = p.reuse.spatial() {
        range("reuse neighbours", neighbours, 1, MAX_NEIGHBOURS);
        range("reuse radius", radius, 1, MAX_RADIUS);
    }
    range("history", p.history, 0, MAX_HISTORY);
    if !(p.normal_offset.is_finite() && (0.0..=0.1).contains(&p.normal_offset)) {
        errors.push(ctx.bad(format!(
            "normal_offset {} must be in [0, 0.1]",
            p.normal_offset
        )));
    }
    super::visibility_buffer::check_ids(ctx, errors);
}

impl KindRules for LightSampling {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(self, ctx, errors)
    }
    fn buffer_layout(&self, slot: &str, frame: FrameSize) -> Option<BufferLayout> {
        (slot == LIGHT_SAMPLES).then(|| {
            BufferLayout::LightSamples(SampleLayout {
                pixels: frame.width as u64 * frame.height as u64,
                exact: self.exact_lights,
                samples: self.samples,
                spatial: self.reuse.spatial().is_some(),
                history: self.history > 0,
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::errors;

    const READS: &str = r#"reads: ["vis", "vertices", "triangles", "lg", "lp", "lists", "bn", "bt"], writes: ["mask"]"#;

    fn pass(params: &str) -> String {
        format!(
            r#"Pass(name: "c", kind: LightCulling(tile: 16), reads: ["depth", "lg"], writes: ["lists"]),
               Pass(name: "sampling", kind: LightSampling({params}), {READS})"#
        )
    }

    #[test]
    fn refuses_parameters_out_of_range() {
        for (params, message) in [
            ("candidates: 0", "candidates 0 must be in 1..=1024"),
            ("samples: 9", "samples 9 must be in 1..=8"),
            ("exact_lights: 17", "exact_lights 17 must be in 0..=16"),
            (
                "reuse: Unbiased(neighbours: 0, radius: 8)",
                "reuse neighbours 0 must be in 1..=16",
            ),
            (
                "reuse: Biased(neighbours: 4, radius: 0)",
                "reuse radius 0 must be in 1..=128",
            ),
            (
                "normal_offset: 0.5",
                "normal_offset 0.5 must be in [0, 0.1]",
            ),
        ] {
            let e = errors(&pass(params), "pos");
            assert!(e.contains(message), "{params}: {e}");
            assert!(e.contains("sampling"), "the pass is named: {e}");
        }
    }
}
