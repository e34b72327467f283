//! The slot table's vocabulary: what a slot takes, from which list, how the GPU uses it,
//! and the rows several kinds share.

use super::layout::Contents;
use super::shadow_atlas;
use crate::graph::model::SceneResource;

/// Slot names shared by several kinds; each is also the WGSL binding name the kind's
/// shader uses for it (attachments are not bindings).
pub mod slot {
    pub(crate) const GEOMETRY: &str = "geometry";
    pub(crate) const DEPTH: &str = "depth";
    pub(crate) const COLOR: &str = "color";
    pub(crate) const LIGHT_GEOMETRY: &str = "light_geometry";
    pub(crate) const LIGHT_PROPERTIES: &str = "light_properties";
    /// The per-tile light lists a `LightCulling` pass writes (also `LightLinkedList`'s
    /// links).
    pub const LIGHT_LISTS: &str = "light_lists";
    /// The nearest transparent depth a culling pass bounds its tiles with.
    pub(crate) const TRANSPARENT_DEPTH: &str = "transparent_depth";
    /// The farthest transparent depth (R32Float): where given, the far end of a
    /// transparent culling range instead of the opaque depth, when nearer.
    pub(crate) const TRANSPARENT_FAR: &str = "transparent_far";
}

/// What a slot takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SlotType {
    /// A depth texture (Depth32Float or Depth16Unorm).
    DepthTexture,
    /// A depth texture, or a single-sample R32Float texture of depth values (what a
    /// compute-only frame writes: compute cannot store depth formats). Only kinds whose
    /// shaders read either take it (`FLOAT_DEPTH` selects `texture_2d<f32>`).
    DepthValues,
    /// Any texture that is not depth (the kind's checks narrow the format).
    ColorTexture,
    /// A storage buffer the graph declares.
    Buffer,
    /// A scene import of this kind.
    Import(SceneResource),
    /// A light array: the scene's import, or (by name only) a buffer a `VplSpawn` pass
    /// wrote with the scene's lights and its virtual lights after them.
    Lights(SceneResource),
}

impl SlotType {
    pub(super) fn describe(self) -> String {
        match self {
            SlotType::DepthTexture => "a depth texture".into(),
            SlotType::DepthValues => "a depth texture (or an R32Float texture of depths)".into(),
            SlotType::ColorTexture => "a colour texture".into(),
            SlotType::Buffer => "a buffer".into(),
            SlotType::Import(from) => format!("an Import of {from:?}"),
            SlotType::Lights(from) => {
                format!("an Import of {from:?} (or a VplSpawn pass's buffer, by name)")
            }
        }
    }
    /// Whether a resource of type `ty` fills a slot of this type; `by_name`: the
    /// resource is named after the slot (or names it); `float_depth`: it is an R32Float
    /// texture (a colour texture that may hold depths; the kind checks its samples).
    pub(super) fn takes(self, ty: SlotType, by_name: bool, float_depth: bool) -> bool {
        match self {
            SlotType::Lights(from) => {
                ty == SlotType::Import(from) || (by_name && ty == SlotType::Buffer)
            }
            SlotType::DepthValues => ty == SlotType::DepthTexture || float_depth,
            _ => self == ty,
        }
    }
}

/// Which of the pass's lists a slot's resource belongs in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// The resource goes in the pass's reads.
    Read,
    /// The resource goes in the pass's writes.
    Write,
    /// Reads or writes: a depth attachment that is tested against, or written first.
    ReadOrWrite,
}

impl Access {
    pub(super) fn allows(self, write: bool) -> bool {
        match self {
            Access::Read => !write,
            Access::Write => write,
            Access::ReadOrWrite => true,
        }
    }
    pub(super) fn describe(self) -> &'static str {
        match self {
            Access::Read => "in reads",
            Access::Write => "in writes",
            Access::ReadOrWrite => "in reads or writes",
        }
    }
}

/// How the pass's GPU work uses a texture slot (for the plan's texture usages).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Usage {
    /// A render-pass attachment.
    Attachment,
    /// Sampled or loaded in a shader.
    Sampled,
    /// A storage texture.
    Storage,
    /// Drawn into or stored from compute, whichever the pass picks on this device (the
    /// compute rasterizer and its hardware fallback): a depth format is an attachment,
    /// R32Float a storage texture, any other format both.
    AttachmentOrStorage,
    /// Tested against as a depth attachment, or (an R32Float texture of depths) loaded
    /// in the shader, which then tests itself.
    AttachmentOrSampled,
    /// Buffers and imports: bound as storage or uniform.
    Bound,
}

/// One row of a kind's slot table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SlotSpec {
    /// The slot's name: what `slot=resource` entries and same-named resources match.
    pub name: &'static str,
    /// What resource the slot takes.
    pub ty: SlotType,
    pub(crate) access: Access,
    /// Whether the pass runs without it.
    pub optional: bool,
    /// How the pass's GPU work uses the resource (for texture usages).
    pub usage: Usage,
    /// A read buffer's contract: what its writer must publish on it (one of these);
    /// empty: anything. Checked by validation (`contracts.rs`).
    pub needs: &'static [Contents],
}

impl SlotSpec {
    /// A required slot that reads or writes (`access`) a resource of type `ty`, used as
    /// `usage`.
    pub const fn new(name: &'static str, ty: SlotType, access: Access, usage: Usage) -> Self {
        Self {
            name,
            ty,
            access,
            optional: false,
            usage,
            needs: &[],
        }
    }
    /// The same slot, optional.
    pub const fn optional(self) -> Self {
        Self {
            optional: true,
            ..self
        }
    }
    /// A read buffer that one of its writers must have laid out as one of `contents`.
    pub const fn needs(self, contents: &'static [Contents]) -> Self {
        Self {
            needs: contents,
            ..self
        }
    }
}

/// Rows several kinds share: the scene's geometry (optional; drawn, never bound) and the
/// two light arrays, read.
pub(crate) const GEOMETRY_READ: SlotSpec = SlotSpec::new(
    slot::GEOMETRY,
    SlotType::Import(SceneResource::Geometry),
    Access::Read,
    Usage::Bound,
)
.optional();
pub(crate) const LIGHT_GEOMETRY_READ: SlotSpec = SlotSpec::new(
    slot::LIGHT_GEOMETRY,
    SlotType::Lights(SceneResource::LightGeometry),
    Access::Read,
    Usage::Bound,
);
pub(crate) const LIGHT_PROPERTIES_READ: SlotSpec = SlotSpec::new(
    slot::LIGHT_PROPERTIES,
    SlotType::Lights(SceneResource::LightProperties),
    Access::Read,
    Usage::Bound,
);
/// The tile lists of a `LightCulling` pass (or a `LightLinkedList`'s links), read by the
/// passes that walk them; optional: without them a pass visits every light.
pub(crate) const LIGHT_LISTS_READ: SlotSpec = SlotSpec::new(
    slot::LIGHT_LISTS,
    SlotType::Buffer,
    Access::Read,
    Usage::Bound,
)
.optional()
.needs(&[Contents::LightLists, Contents::LightLinks]);

/// Rows every shading pass shares: a ShadowAtlas pass's atlas (Depth32Float, or R32Float
/// from its compute raster) and view table, read.
pub(crate) const SHADOW_ATLAS_READ: SlotSpec = SlotSpec::new(
    shadow_atlas::SHADOW_ATLAS,
    SlotType::DepthValues,
    Access::Read,
    Usage::Sampled,
)
.optional();
pub(crate) const SHADOW_VIEWS_READ: SlotSpec = SlotSpec::new(
    shadow_atlas::SHADOW_VIEWS,
    SlotType::Buffer,
    Access::Read,
    Usage::Bound,
)
.optional()
.needs(&[Contents::ShadowViews]);

/// Rows of the shading passes that trace shadow rays in their light loop: the scene's
/// BVH, both halves.
pub(crate) const BVH_NODES_READ: SlotSpec = SlotSpec::new(
    super::shadow_ray_cast::BVH_NODES,
    SlotType::Import(SceneResource::BvhNodes),
    Access::Read,
    Usage::Bound,
)
.optional();
pub(crate) const BVH_TRIANGLES_READ: SlotSpec = SlotSpec::new(
    super::shadow_ray_cast::BVH_TRIANGLES,
    SlotType::Import(SceneResource::BvhTriangles),
    Access::Read,
    Usage::Bound,
)
.optional();

/// Row of the shading passes that hide VPLs from the pixels they cannot see: a
/// `VplVisibility` pass's bits.
pub(crate) const VPL_VISIBILITY_READ: SlotSpec = SlotSpec::new(
    super::vpl_visibility::VPL_VISIBILITY,
    SlotType::Buffer,
    Access::Read,
    Usage::Bound,
)
.optional()
.needs(&[Contents::VplVisibility]);
