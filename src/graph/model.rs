//! The graph file format: plain serde data, exactly what a RON file says.

pub use super::kinds::deferred_shading::DeferredShading;
pub use super::kinds::forward_shading::ForwardShading;
pub use super::kinds::light_culling::{LightCulling, ListMode};
pub use super::kinds::light_linked_list::LightLinkedList;
pub use super::kinds::light_sampling::LightSampling;
pub use super::kinds::reflective_shadow_maps::ReflectiveShadowMaps;
pub use super::kinds::shadow_atlas::ShadowAtlas;
pub use super::kinds::shadow_ray_cast::ShadowRayCast;
pub use super::kinds::shadow_ray_jobs::ShadowRayJobs;
pub use super::kinds::transparent_shading::TransparentShading;
pub use super::kinds::visibility_shading::VisibilityShading;
pub use super::kinds::vpl_spawn::{VplFalloff, VplSpawn};
pub use super::name::Name;
use serde::{Deserialize, Serialize};

/// A whole graph file (`graphs/*.ron`).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(rename = "Graph", deny_unknown_fields)]
pub struct GraphDesc {
    /// The graph's name, used in reports and the Graphviz output.
    pub name: String,
    /// Free text on what the graph does; ignored by the compiler.
    #[serde(default)]
    pub description: String,
    /// The textures, buffers and scene imports the passes use.
    pub resources: Vec<ResourceDesc>,
    /// The passes, in any order: they run in dependency order.
    pub passes: Vec<PassDesc>,
    /// The resource presented as the frame (a colour texture).
    pub output: Name,
    /// Passes kept even though nothing reads what they write (statistics, readbacks).
    #[serde(default)]
    pub side_effects: Vec<Name>,
}

/// A named resource. Sizes are plain data relative to the output.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum ResourceDesc {
    /// A texture the graph allocates.
    Texture {
        /// The name passes read and write it by.
        name: Name,
        /// Its texel format.
        format: TextureFormat,
        /// Its size in texels, relative to the output by default.
        #[serde(default)]
        size: TextureSize,
        /// MSAA sample count (1, 2, 4, 8 or 16 where the device allows; 1 by default).
        #[serde(default = "one")]
        samples: u32,
    },
    /// A storage buffer the graph allocates.
    Buffer {
        /// The name passes read and write it by.
        name: Name,
        /// Its size in bytes; `Auto` lets the built-in pass that writes it size it.
        #[serde(default)]
        size: BufferSize,
    },
    /// Data owned by the scene, bound read-only.
    Import {
        /// The name passes read it by.
        name: Name,
        /// Which scene data it is.
        from: SceneResource,
    },
}

fn one() -> u32 {
    1
}

impl ResourceDesc {
    /// The resource's name as passes refer to it.
    pub fn name(&self) -> &str {
        self.shared_name()
    }
    /// The name as shared text, for the compile steps to keep without copying it.
    pub(crate) fn shared_name(&self) -> &Name {
        match self {
            ResourceDesc::Texture { name, .. }
            | ResourceDesc::Buffer { name, .. }
            | ResourceDesc::Import { name, .. } => name,
        }
    }
}

/// The texel formats graph textures can have; each maps to the wgpu format of the same
/// name.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TextureFormat {
    /// 8-bit RGBA in 0..=1 (LDR colour).
    Rgba8Unorm,
    /// 16-bit float RGBA (HDR colour at half the memory of Rgba32Float).
    Rgba16Float,
    /// 32-bit float RGBA (HDR colour, G-buffer channels).
    Rgba32Float,
    /// One 32-bit float channel.
    R32Float,
    /// Two 32-bit float channels.
    Rg32Float,
    /// One 32-bit unsigned integer channel (triangle ids of the visibility buffer).
    R32Uint,
    /// 32-bit float depth (depth prepass, G-buffer and shadow depth).
    Depth32Float,
    /// Half the memory of Depth32Float (shadow atlases: 512 MiB instead of 1 GiB at 16384²).
    Depth16Unorm,
}

impl TextureFormat {
    pub(crate) fn is_depth(self) -> bool {
        matches!(
            self,
            TextureFormat::Depth32Float | TextureFormat::Depth16Unorm
        )
    }
    pub(crate) fn to_wgpu(self) -> wgpu::TextureFormat {
        use wgpu::TextureFormat as W;
        match self {
            TextureFormat::Rgba8Unorm => W::Rgba8Unorm,
            TextureFormat::Rgba16Float => W::Rgba16Float,
            TextureFormat::Rgba32Float => W::Rgba32Float,
            TextureFormat::R32Float => W::R32Float,
            TextureFormat::Rg32Float => W::Rg32Float,
            TextureFormat::R32Uint => W::R32Uint,
            TextureFormat::Depth32Float => W::Depth32Float,
            TextureFormat::Depth16Unorm => W::Depth16Unorm,
        }
    }
}

/// A texture's size, relative to the output (the frame) unless fixed.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq)]
pub enum TextureSize {
    /// The output's size.
    #[default]
    Output,
    /// The output's size times a factor, rounded up, at least 1.
    Scaled(f32),
    /// A fixed width and height in texels, independent of the output.
    Fixed(u32, u32),
}

/// A buffer's size in bytes, fixed or relative to the frame.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum BufferSize {
    /// Sized by the built-in pass that writes it (e.g. per-tile light lists from the
    /// culling pass's tile size and capacity).
    #[default]
    Auto,
    /// A fixed number of bytes.
    Bytes(u64),
    /// `bytes` for every `tile`×`tile` tile of the output.
    PerTile {
        /// The tile side in output pixels.
        tile: u32,
        /// Bytes per tile.
        bytes: u64,
    },
    /// Bytes per output pixel.
    PerPixel(u64),
    /// Bytes per light the frame is sized for (`FrameSize::lights`, at least one).
    PerLight(u64),
}

/// What a scene provides to the graph.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SceneResource {
    /// Light positions, ranges and cones: all culling needs.
    LightGeometry,
    /// Light colours, intensities, flags and material masks.
    LightProperties,
    /// Vertex and index buffers of every mesh.
    Geometry,
    /// The shadow BVH's nodes over every scene triangle (`src/shadow/bvh.rs`), built
    /// when the scene has shadow-casting lights.
    BvhNodes,
    /// The shadow BVH's triangles, in the order its leaves name them.
    BvhTriangles,
    /// Opaque meshes merged for vertex fetching (`render::visibility_geometry`): 12
    /// floats a vertex, world space.
    Vertices,
    /// Three merged-vertex indices a triangle; a visibility id indexes it.
    Triangles,
    /// Each material's `[first, end)` triangle ids.
    MaterialTriangles,
}

/// A scene feature a pass can be conditional on (`when:`).
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Hash)]
pub enum SceneFeature {
    /// The scene has blended (transparent) materials.
    Transparent,
    /// The scene has alpha-masked materials.
    AlphaMask,
    /// The scene has lights that cast shadows.
    ShadowCasters,
    /// The scene has indirect lights (light bounced through reflective shadow maps).
    IndirectLights,
    /// The scene has spot lights.
    SpotLights,
    /// The scene has at least one light.
    Lights,
    /// Not a scene feature: refused at validation (MSAA is chosen by the graph's
    /// textures, `samples: 4`, so a condition on it would be constant). Kept in the enum
    /// so the error can say so instead of ron's "unknown variant".
    Msaa,
}

impl SceneFeature {
    /// Whether the scene has this feature; always false for `Msaa`.
    pub fn holds(self, f: &crate::scene::SceneFeatures) -> bool {
        match self {
            SceneFeature::Transparent => f.has_transparent,
            SceneFeature::AlphaMask => f.has_alpha_mask,
            SceneFeature::ShadowCasters => f.has_shadow_casters,
            SceneFeature::IndirectLights => f.has_indirect_lights,
            SceneFeature::SpotLights => f.has_spot_lights,
            SceneFeature::Lights => f.has_lights,
            SceneFeature::Msaa => false,
        }
    }
}

/// One pass of the graph file: its kind and parameters, what it reads and writes, and when
/// it runs.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(rename = "Pass", deny_unknown_fields)]
pub struct PassDesc {
    /// The pass's unique name; errors and timings use it.
    pub name: Name,
    /// What the pass does, with its parameters.
    pub kind: PassKind,
    /// Resources it reads; `slot=resource` entries name the slot of a built-in kind.
    #[serde(default)]
    pub reads: Vec<Name>,
    /// Resources it writes; `slot=resource` entries name the slot of a built-in kind.
    #[serde(default)]
    pub writes: Vec<Name>,
    /// A scene feature the pass needs: the pass is dropped when the scene lacks it.
    #[serde(default)]
    pub when: Option<SceneFeature>,
    /// `slot=resource` entries of reads and writes, split off by the parser: (slot,
    /// resource). Built-in kinds match these by name; the rest by type and order.
    #[serde(skip)]
    pub named_slots: Vec<(Name, Name)>,
}

impl PassDesc {
    /// The slot a `slot=resource` entry named for `resource`.
    pub(crate) fn explicit_slot(&self, resource: &str) -> Option<&str> {
        self.named_slots
            .iter()
            .find(|(_, r)| r == resource)
            .map(|(s, _)| s.as_str())
    }

    /// Splits `slot=resource` entries of reads and writes into `named_slots`, leaving
    /// plain resource names in the lists.
    pub(crate) fn split_named_slots(&mut self) {
        for list in [&mut self.reads, &mut self.writes] {
            for entry in list.iter_mut() {
                if let Some((slot, resource)) = entry.split_once('=') {
                    let (slot, resource) = (Name::from(slot.trim()), Name::from(resource.trim()));
                    self.named_slots.push((slot, resource.clone()));
                    *entry = resource;
                }
            }
        }
    }
}

/// How a culling pass bounds a tile in depth.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Hash, Default)]
#[serde(deny_unknown_fields)]
pub enum CullVariant {
    /// One list per tile between the tile's min and max depth.
    #[default]
    Frustum,
    /// Two lists per tile, split at the middle of the depth range.
    HalfZ,
    /// 2.5D: 32 depth cells, a light survives if its cells meet the tile's occupied cells.
    DepthMask,
    /// A 3D grid: `slices` exponential depth slices per tile, one list per cell.
    Clustered {
        /// Exponential depth slices per tile.
        slices: u32,
    },
}

impl CullVariant {
    /// The `VARIANT` define and `ListParams::variant` of the culling shader.
    pub fn code(self) -> u32 {
        match self {
            CullVariant::Frustum => 0,
            CullVariant::HalfZ => 1,
            CullVariant::DepthMask => 2,
            CullVariant::Clustered { .. } => 3,
        }
    }
}

/// Where light lists come from for forward shading.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Hash, Default)]
pub enum LightSource {
    /// Every light at every pixel: the reference.
    #[default]
    AllLights,
    /// The lists written by a `LightCulling` or `LightLinkedList` pass (read as a buffer).
    Culled,
}

/// How many workgroups a `Compute` pass dispatches.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Hash)]
#[serde(deny_unknown_fields)]
pub enum Dispatch {
    /// One invocation per output pixel, in workgroups of the given size.
    PerPixel {
        /// The workgroup's size in x and y (must match the shader's `@workgroup_size`).
        workgroup: (u32, u32),
    },
    /// One workgroup per `tile`×`tile` tile.
    PerTile {
        /// The tile side in output pixels.
        tile: u32,
    },
    /// One invocation per light, in workgroups of `workgroup`.
    PerLight {
        /// The workgroup's size in x (must match the shader's `@workgroup_size`).
        workgroup: u32,
    },
    /// Fixed workgroup counts in x, y and z.
    Fixed(u32, u32, u32),
}

pub use super::kinds::PassKind;

pub(super) fn default_entry() -> String {
    "main".into()
}
pub(super) fn default_fragment_entry() -> String {
    "fs_main".into()
}

/// The shader of a generic pass (`Compute`, `Fullscreen`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GenericShader<'a> {
    /// The WGSL file, relative to the shader root.
    pub file: &'a str,
    /// The entry point's name (`main` for compute, `fs_main` for fullscreen by default).
    pub entry: &'a str,
    /// Compute or fragment.
    pub stage: naga::ShaderStage,
}

impl PassKind {
    /// The WGSL file a generic pass runs, relative to the shader root.
    pub(crate) fn shader_file(&self) -> Option<&str> {
        self.generic_shader().map(|g| g.file)
    }
}
