//! `ReflectiveShadowMaps`: every indirect light's reflective shadow map in one atlas
//! (Harada, McKee, Yang, "Forward+"; AMD's TiledLighting11 sample: 32×32 a light): depth, normal, reflected flux and
//! world position, a tile per spot light and six cube faces per point light, all views
//! in one render pass. Writes the four textures and the view table the `VplSpawn` pass
//! reads (`src/indirect/rsm_views.rs` allocates the tiles). With `raster: Compute` the
//! views are rasterized in compute instead (`prepare`'s `raster.rs`), into an R32Float
//! depth.

use super::{Access, BufferLayout, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::{ResourceDesc, TextureFormat, TextureSize};
use crate::graph::plan::FrameSize;
use serde::{Deserialize, Serialize};

/// `ReflectiveShadowMaps(tile: 32, max_lights: 64, raster: Hardware)`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(deny_unknown_fields)]
pub struct ReflectiveShadowMaps {
    /// Texels per side of a view's tile (each view of a light gets one).
    #[serde(default = "default_tile")]
    pub tile: u32,
    /// Indirect lights a frame at most (six views each at most): the view table's room.
    #[serde(default = "default_max_lights")]
    pub max_lights: u32,
    /// Which units draw the views: the raster pipeline (a Depth32Float depth), or the
    /// compute rasterizer (an R32Float depth).
    #[serde(default)]
    pub raster: RsmRaster,
}

/// Who rasterizes the maps' views.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, Hash)]
pub enum RsmRaster {
    /// The raster pipeline: every view in one render pass (a viewport each), the
    /// material's RSM fragment stage writing the three targets over a depth attachment.
    #[default]
    Hardware,
    /// Compute: the nearest depth of each texel by a 32-bit atomic min, then the
    /// nearest triangle's id where the depth matches, then per material the texels of
    /// its triangles set up and stored (`shaders/indirect/rsm_raster.wgsl`). The depth
    /// is stored into an R32Float texture (compute cannot store a depth format).
    /// Alpha-masked casters are alpha-tested in compute, a run per material.
    Compute,
}

fn default_tile() -> u32 {
    32
}
fn default_max_lights() -> u32 {
    64
}

impl Default for ReflectiveShadowMaps {
    fn default() -> Self {
        Self {
            tile: default_tile(),
            max_lights: default_max_lights(),
            raster: RsmRaster::default(),
        }
    }
}

impl ReflectiveShadowMaps {
    /// Views the table has room for: six per indirect light (`max_lights`).
    pub fn max_views(&self) -> u64 {
        6 * self.max_lights as u64
    }
}

pub(crate) const RSM_DEPTH: &str = "rsm_depth";
pub(crate) const RSM_NORMAL: &str = "rsm_normal";
pub(crate) const RSM_FLUX: &str = "rsm_flux";
pub(crate) const RSM_POSITION: &str = "rsm_position";
pub(crate) const RSM_VIEWS: &str = "rsm_views";

/// vec4 words of a view in the table: view-projection (4); (tile x, tile y, light, n)
/// as u32; (texel solid angle on the axis, intensity scale, VPL range, distance clamp);
/// (light position, material mask bits); (view axis, first candidate as u32 bits).
pub const VIEW_VEC4S: u64 = 8;

/// Bytes of a view table with room for `max_views`: a header vec4, then the views.
pub(crate) fn view_table_bytes(max_views: u64) -> u64 {
    16 * (1 + VIEW_VEC4S * max_views)
}

pub(crate) const SLOTS: &[SlotSpec] = &[
    super::GEOMETRY_READ,
    super::LIGHT_GEOMETRY_READ,
    super::LIGHT_PROPERTIES_READ,
    SlotSpec::new(
        RSM_DEPTH,
        SlotType::DepthValues,
        Access::Write,
        Usage::AttachmentOrStorage,
    ),
    SlotSpec::new(
        RSM_NORMAL,
        SlotType::ColorTexture,
        Access::Write,
        Usage::AttachmentOrStorage,
    ),
    SlotSpec::new(
        RSM_FLUX,
        SlotType::ColorTexture,
        Access::Write,
        Usage::AttachmentOrStorage,
    ),
    SlotSpec::new(
        RSM_POSITION,
        SlotType::ColorTexture,
        Access::Write,
        Usage::AttachmentOrStorage,
    ),
    SlotSpec::new(RSM_VIEWS, SlotType::Buffer, Access::Write, Usage::Bound),
];

/// The (width, height) of a fixed-size single-sample texture.
pub(crate) fn fixed_size(desc: Option<&ResourceDesc>) -> Option<(u32, u32, TextureFormat)> {
    match desc? {
        ResourceDesc::Texture {
            size: TextureSize::Fixed(w, h),
            samples: 1,
            format,
            ..
        } => Some((*w, *h, *format)),
        _ => None,
    }
}

pub(crate) fn check(p: &ReflectiveShadowMaps, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    if !(p.tile.is_power_of_two() && (4..=1024).contains(&p.tile)) {
        errors.push(ctx.bad(format!(
            "tile {} must be a power of two in 4..=1024",
            p.tile
        )));
    }
    if !(1..=4096).contains(&p.max_lights) {
        errors.push(ctx.bad(format!("max_lights {} must be in 1..=4096", p.max_lights)));
    }
    let mut size = None;
    for slot in [RSM_DEPTH, RSM_NORMAL, RSM_FLUX, RSM_POSITION] {
        let Some(name) = ctx.slot(slot) else { continue };
        match fixed_size(ctx.graph.resources.get(name).copied()) {
            None => errors.push(ctx.mismatch(
                name,
                "a reflective shadow map is a single-sample texture of a fixed size: size: Fixed(1024, 1024)",
            )),
            Some((w, h, format)) => {
                if slot == RSM_DEPTH {
                    check_depth_format(p, ctx, name, errors);
                } else if format != TextureFormat::Rgba32Float {
                    errors.push(ctx.mismatch(name, format!("slot '{slot}' takes an Rgba32Float texture")));
                }
                if p.tile == 0
                    || !w.is_multiple_of(p.tile)
                    || !h.is_multiple_of(p.tile)
                    || w < p.tile
                    || h < p.tile
                {
                    errors.push(ctx.mismatch(
                        name,
                        format!("{w}×{h} is not a whole number of {}-texel tiles", p.tile),
                    ));
                }
                match size {
                    None => size = Some((w, h)),
                    Some(s) if s != (w, h) => errors.push(ctx.mismatch(
                        name,
                        format!("the four maps must be one size: {}×{} and {w}×{h}", s.0, s.1),
                    )),
                    Some(_) => {}
                }
            }
        }
    }
}

/// The depth's format is the raster's: a depth format to draw into, R32Float to store
/// from compute.
fn check_depth_format(
    p: &ReflectiveShadowMaps,
    ctx: &KindCtx,
    depth: &str,
    errors: &mut Vec<GraphError>,
) {
    let float = ctx.is_float_depth(depth);
    match p.raster {
        RsmRaster::Hardware if float => errors.push(ctx.mismatch(
            depth,
            "raster: Hardware draws the maps' depth as an attachment: declare it format: Depth32Float (R32Float is for raster: Compute)",
        )),
        RsmRaster::Compute if !float => errors.push(ctx.mismatch(
            depth,
            "raster: Compute stores the maps' depth from compute, which cannot write a depth format: declare it format: R32Float",
        )),
        _ => {}
    }
}

impl KindRules for ReflectiveShadowMaps {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(self, ctx, errors)
    }
    fn buffer_layout(&self, slot: &str, _frame: FrameSize) -> Option<BufferLayout> {
        (slot == RSM_VIEWS).then(|| BufferLayout::RsmViews {
            max_views: self.max_views(),
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::{errors, validate};

    const PASSES: &str = r#"Pass(name: "r", kind: ReflectiveShadowMaps(RSM), reads: ["geometry", "lg", "lp"], writes: ["rsm_depth", "rsm_normal", "rsm_flux", "rsm_position", "rsm_views"]),
        Pass(name: "v", kind: VplSpawn(), reads: ["rsm_normal", "rsm_flux", "rsm_position", "rsm_views", "lg", "lp"], writes: ["light_geometry", "light_properties"]),
        Pass(name: "f", kind: ForwardShading(), reads: ["geometry", "light_geometry", "light_properties"], writes: ["depth", "hdr"])"#;

    #[test]
    fn accepts_maps_spawn_and_readers() {
        validate(&PASSES.replace("RSM", ""), "hdr").unwrap();
        validate(&PASSES.replace("RSM", "tile: 16, max_lights: 8"), "hdr").unwrap();
    }

    #[test]
    fn checks_parameters_and_textures() {
        let e = errors(&PASSES.replace("RSM", "tile: 24, max_lights: 0"), "hdr");
        assert!(errors(&PASSES.replace("RSM", "tile: 0"), "hdr").contains("tile 0 must be"));
        assert!(e.contains("tile 24 must be a power of two"), "{e}");
        assert!(e.contains("max_lights 0 must be in 1..=4096"), "{e}");
        let e = errors(&PASSES.replace("RSM", "tile: 512"), "hdr");
        assert!(e.contains("not a whole number of 512-texel tiles"), "{e}");
        let e = errors(
            &PASSES.replace("RSM", "").replace(
                "\"rsm_flux\", \"rsm_position\", \"rsm_views\"]",
                "\"small\", \"rsm_position\", \"rsm_views\"]",
            ),
            "hdr",
        );
        assert!(e.contains("fixed size"), "{e}");
    }

    #[test]
    fn the_depth_format_follows_the_raster() {
        // "rsm_depth" is Depth32Float, "rsm_depth_f" R32Float (test_support).
        let e = errors(&PASSES.replace("RSM", "raster: Compute"), "hdr");
        assert!(
            e.contains("raster: Compute stores the maps' depth from compute")
                && e.contains("R32Float")
                && e.contains("rsm_depth"),
            "{e}"
        );
        let float = PASSES.replace("\"rsm_depth\"", "\"rsm_depth=rsm_depth_f\"");
        validate(&float.replace("RSM", "raster: Compute"), "hdr").unwrap();
        let e = errors(&float.replace("RSM", ""), "hdr");
        assert!(
            e.contains("raster: Hardware draws the maps' depth") && e.contains("rsm_depth_f"),
            "{e}"
        );
    }

    #[test]
    fn a_light_buffer_fills_a_light_slot_only_by_name() {
        // "lists" is a buffer: by type order it may not take the light_geometry slot.
        let e = errors(
            r#"Pass(name: "f", kind: ForwardShading(), reads: ["geometry", "lists", "lp"], writes: ["depth", "hdr"])"#,
            "hdr",
        );
        assert!(e.contains("light_geometry"), "{e}");
    }
}
