//! `ShadowAtlas`: the depth of every shadow-casting light's views (a tile per spot light,
//! six cube faces per point light) in one atlas, all views in one render pass; tiles
//! allocated every frame from each light's size on screen (`shadow::atlas`). Writes the
//! atlas and the view table that shading passes sample it through
//! (`shaders/common/shadows.wgsl`, `SHADOW_ATLAS`).

use super::contracts::InputsCtx;
use super::{Access, BufferLayout, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::{ResourceDesc, TextureSize};
use crate::graph::plan::FrameSize;
pub use crate::shadow::policy::{AtlasFit, AtlasPolicy};
use serde::{Deserialize, Serialize};

/// `ShadowAtlas(filter: Pcf5x5, min_tile: 16, max_tile: 1024, importance: 1.0, ...)`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShadowAtlas {
    /// How shading passes filter the atlas.
    #[serde(default)]
    pub filter: ShadowFilter,
    /// The smallest tile a light is given; below it the light is dropped (reported).
    #[serde(default = "default_min_tile")]
    pub min_tile: u32,
    /// The largest tile a light may ask for.
    #[serde(default = "default_max_tile")]
    pub max_tile: u32,
    /// Tile side wanted per pixel of the light's diameter on screen.
    #[serde(default = "default_importance")]
    pub importance: f32,
    /// Shadowed lights a frame at most (the view table's room; six views each).
    #[serde(default = "default_max_lights")]
    pub max_lights: u32,
    /// Constant depth bias, in the depth format's units (pipeline state).
    #[serde(default = "default_depth_bias")]
    pub depth_bias: u32,
    /// Depth bias per unit of the caster's depth slope (pipeline state).
    #[serde(default = "default_slope_bias")]
    pub slope_bias: f32,
    /// Offset of the shaded point along its normal, in texels of its view.
    #[serde(default = "default_normal_offset")]
    pub normal_offset: f32,
    /// Which shadow-casting lights in view ask for a tile (`All` by default); the others
    /// get ray-cast shadows from a `ShadowRayJobs` pass that reads the view table.
    #[serde(default)]
    pub policy: AtlasPolicy,
    /// When the tiles do not fit: shrink them (`ShrinkTiles`, the default) or drop the
    /// lowest-ranked lights (`DropLights`).
    #[serde(default)]
    pub fit: AtlasFit,
    /// Which units draw the views: the raster pipeline into a Depth32Float atlas, or
    /// the compute rasterizer into an R32Float one (`shaders/shadow/atlas_raster.wgsl`).
    #[serde(default)]
    pub raster: AtlasRaster,
    /// Keep the views whose light, tile and casters did not change since the last frame
    /// instead of drawing them again (`shadow::atlas_cache`).
    #[serde(default)]
    pub cache: bool,
}

/// Who rasterizes the atlas's views.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
pub enum AtlasRaster {
    /// The raster pipeline: depth-only draws, a viewport a view, into Depth32Float.
    #[default]
    Hardware,
    /// Compute: a thread per (view, triangle), 32-bit atomic min of the depth bits into
    /// a buffer, stored into an R32Float atlas that shading compares by hand (compute
    /// cannot store a depth format). Alpha-masked casters are alpha-tested, a run per
    /// material, as visibility shading rebuilds a pixel.
    Compute,
}

/// How a shading pass reads the atlas.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
pub enum ShadowFilter {
    /// 25 hardware-comparison taps on a 5×5 texel grid (AMD TiledLighting11).
    #[default]
    Pcf5x5,
    /// One hardware-comparison tap (the 2×2 bilinear comparison).
    Hardware2x2,
}

fn default_min_tile() -> u32 {
    16
}
fn default_max_tile() -> u32 {
    1024
}
fn default_importance() -> f32 {
    1.0
}
fn default_max_lights() -> u32 {
    512
}
fn default_depth_bias() -> u32 {
    2
}
fn default_slope_bias() -> f32 {
    2.0
}
fn default_normal_offset() -> f32 {
    1.5
}

impl Default for ShadowAtlas {
    fn default() -> Self {
        Self {
            filter: ShadowFilter::default(),
            min_tile: default_min_tile(),
            max_tile: default_max_tile(),
            importance: default_importance(),
            max_lights: default_max_lights(),
            depth_bias: default_depth_bias(),
            slope_bias: default_slope_bias(),
            normal_offset: default_normal_offset(),
            policy: AtlasPolicy::default(),
            fit: AtlasFit::default(),
            raster: AtlasRaster::default(),
            cache: false,
        }
    }
}

/// The slot (and WGSL binding name) of the atlas depth texture.
pub const SHADOW_ATLAS: &str = "shadow_atlas";
pub(crate) const SHADOW_VIEWS: &str = "shadow_views";

/// vec4 words a view takes in the view table: its view-projection (4), its tile in
/// atlas UV (min, max), then (texel scale, normal offset, 0, 0).
pub const VIEW_VEC4S: u64 = 6;

/// Bytes of a view table for `lights` scene lights and `max_views` views: a header
/// vec4, the views, then one u32 per light (its first view + 1, 0 for none; bit 31 for
/// six faces).
pub(crate) fn view_table_bytes(lights: u32, max_views: u64) -> u64 {
    16 * (1 + VIEW_VEC4S * max_views + (lights.max(1) as u64).div_ceil(4))
}

impl ShadowAtlas {
    /// Views the table has room for: six per shadow-casting light (`max_lights`).
    pub fn max_views(&self) -> u64 {
        6 * self.max_lights as u64
    }
}

pub(crate) const SLOTS: &[SlotSpec] = &[
    super::GEOMETRY_READ,
    SlotSpec::new(
        SHADOW_ATLAS,
        SlotType::DepthValues,
        Access::Write,
        Usage::AttachmentOrStorage,
    ),
    SlotSpec::new(SHADOW_VIEWS, SlotType::Buffer, Access::Write, Usage::Bound),
];

/// The atlas texture's side, if it is a single-sample square of a fixed power-of-two size.
pub(crate) fn atlas_side(desc: Option<&ResourceDesc>) -> Option<u32> {
    match desc? {
        ResourceDesc::Texture {
            size: TextureSize::Fixed(w, h),
            samples: 1,
            ..
        } if w == h && w.is_power_of_two() => Some(*w),
        _ => None,
    }
}

pub(crate) fn check(p: &ShadowAtlas, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    let pow2 = |v: u32| v.is_power_of_two() && (4..=16384).contains(&v);
    if !pow2(p.min_tile) || !pow2(p.max_tile) || p.min_tile > p.max_tile {
        errors.push(ctx.bad(format!(
            "min_tile {} and max_tile {} must be powers of two in 4..=16384, min_tile <= max_tile",
            p.min_tile, p.max_tile
        )));
    }
    if !(p.importance.is_finite() && p.importance > 0.0 && p.importance <= 64.0) {
        errors.push(ctx.bad(format!("importance {} must be in (0, 64]", p.importance)));
    }
    if !(1..=65536).contains(&p.max_lights) {
        errors.push(ctx.bad(format!("max_lights {} must be in 1..=65536", p.max_lights)));
    }
    if p.depth_bias > 1 << 20 {
        errors.push(ctx.bad(format!("depth_bias {} is over 2^20", p.depth_bias)));
    }
    for (name, v) in [
        ("slope_bias", p.slope_bias),
        ("normal_offset", p.normal_offset),
    ] {
        if !(v.is_finite() && (0.0..=64.0).contains(&v)) {
            errors.push(ctx.bad(format!("{name} {v} must be in [0, 64]")));
        }
    }
    if let Some(problem) = p.policy.problem() {
        errors.push(ctx.bad(problem));
    }
    if let Some(atlas) = ctx.slot(SHADOW_ATLAS) {
        match atlas_side(ctx.graph.resources.get(atlas).copied()) {
            None => errors.push(ctx.mismatch(
                atlas,
                "the shadow atlas must be a single-sample square texture of a fixed power-of-two size: size: Fixed(4096, 4096)",
            )),
            Some(side) if side < p.max_tile => errors.push(ctx.mismatch(
                atlas,
                format!("the atlas ({side}²) is smaller than max_tile {}", p.max_tile),
            )),
            Some(_) => {}
        }
        check_format(p, ctx, atlas, errors);
    }
}

/// The atlas's format is the raster's: a depth format to draw into, R32Float to store
/// from compute.
fn check_format(p: &ShadowAtlas, ctx: &KindCtx, atlas: &str, errors: &mut Vec<GraphError>) {
    let float = ctx.is_float_depth(atlas);
    match p.raster {
        AtlasRaster::Hardware if float => errors.push(ctx.mismatch(
            atlas,
            "raster: Hardware draws depth into the atlas: declare it format: Depth32Float (R32Float is for raster: Compute)",
        )),
        AtlasRaster::Compute if !float => errors.push(ctx.mismatch(
            atlas,
            "raster: Compute stores depths from compute, which cannot write a depth format: declare the atlas format: R32Float",
        )),
        _ => {}
    }
}

/// A policy that leaves lights out of the atlas needs a `ShadowRayJobs` pass reading the
/// view table: it casts their rays (nothing else would shadow them).
fn check_ray_fallback(p: &ShadowAtlas, ctx: &InputsCtx, errors: &mut Vec<GraphError>) {
    if !p.policy.leaves_lights_to_rays() {
        return;
    }
    let Some(views) = ctx.slot(SHADOW_VIEWS) else {
        return;
    };
    if super::shadow_ray_jobs::jobs_reading_views(ctx, views)
        .next()
        .is_none()
    {
        errors.push(ctx.bad(format!(
            "policy {:?} leaves the other shadow-casting lights to ray-cast shadows, but no ShadowRayJobs pass reads '{views}' (the view table tells it which lights have a map): add it to that pass's reads, as graphs/visibility_hybrid_shadows.ron does, or use policy: All",
            p.policy
        )));
    }
}

impl KindRules for ShadowAtlas {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(self, ctx, errors)
    }
    fn check_inputs(&self, ctx: &InputsCtx, errors: &mut Vec<GraphError>) {
        check_ray_fallback(self, ctx, errors)
    }
    fn buffer_layout(&self, slot: &str, frame: FrameSize) -> Option<BufferLayout> {
        (slot == SHADOW_VIEWS).then(|| BufferLayout::ShadowViews {
            lights: frame.lights,
            max_views: self.max_views(),
            filter: self.filter,
            raster: self.raster,
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::{errors, validate};

    const PASSES: &str = r#"Pass(name: "a", kind: ShadowAtlas(ATLAS), reads: ["geometry"], writes: ["atlas", "views"]),
        Pass(name: "f", kind: ForwardShading(), reads: ["geometry", "lg", "lp", "atlas", "shadow_views=views"], writes: ["depth", "hdr"])"#;

    #[test]
    fn accepts_the_atlas_and_its_readers() {
        validate(&PASSES.replace("ATLAS", ""), "hdr").unwrap();
        validate(
            &PASSES.replace("ATLAS", "filter: Hardware2x2, min_tile: 32, max_tile: 512"),
            "hdr",
        )
        .unwrap();
    }

    #[test]
    fn a_buffer_fills_the_slot_it_is_named_after() {
        // By type order "views" would fill the first free buffer slot (light_lists).
        let e = errors(
            &PASSES
                .replace("ATLAS", "")
                .replace("shadow_views=views", "views"),
            "hdr",
        );
        assert!(e.contains("lights: AllLights reads no light lists"), "{e}");
        validate(
            &PASSES
                .replace("ATLAS", "")
                .replace("shadow_views=views", "views")
                .replace("\"views\"", "\"shadow_views\""),
            "hdr",
        )
        .unwrap();
    }

    #[test]
    fn checks_parameters_and_the_texture() {
        let e = errors(
            &PASSES.replace(
                "ATLAS",
                "min_tile: 24, importance: 0.0, normal_offset: -1.0",
            ),
            "hdr",
        );
        assert!(
            e.contains("min_tile 24 and max_tile 1024 must be powers of two"),
            "{e}"
        );
        assert!(e.contains("importance 0 must be in (0, 64]"), "{e}");
        assert!(e.contains("normal_offset -1 must be in [0, 64]"), "{e}");
        let e = errors(&PASSES.replace("ATLAS", "max_tile: 4096"), "hdr");
        assert!(
            e.contains("the atlas (2048²) is smaller than max_tile 4096"),
            "{e}"
        );
        let e = errors(
            &PASSES
                .replace("ATLAS", "")
                .replace("\"atlas\"", "\"atlas_odd\""),
            "hdr",
        );
        assert!(e.contains("fixed power-of-two size"), "{e}");
    }

    #[test]
    fn the_atlas_format_follows_the_raster() {
        // "atlas" is Depth32Float 2048² (test_support); "atlas_f" an R32Float one.
        let e = errors(&PASSES.replace("ATLAS", "raster: Compute"), "hdr");
        assert!(
            e.contains("raster: Compute stores depths from compute") && e.contains("R32Float"),
            "{e}"
        );
        let float = PASSES.replace("\"atlas\"", "\"atlas_f\"");
        validate(
            &float.replace("ATLAS", "raster: Compute, cache: true"),
            "hdr",
        )
        .unwrap();
        let e = errors(&float.replace("ATLAS", ""), "hdr");
        assert!(
            e.contains("raster: Hardware draws depth into the atlas"),
            "{e}"
        );
    }
}
