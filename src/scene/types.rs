use crate::material::model::TextureSampling;
use glam::{Mat4, Vec2, Vec3, Vec4};
use serde::{Deserialize, Serialize};

/// A triangle mesh already transformed to world space.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Mesh name from the source file (glTF mesh or built-in part), for messages and
    /// statistics.
    pub name: String,
    /// Vertex positions in world space, metres.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals in world space, one per position.
    pub normals: Vec<Vec3>,
    /// Texture coordinates (glTF `TEXCOORD_0`), one per position; empty when the mesh has none.
    pub uvs: Vec<Vec2>,
    /// The second set (glTF `TEXCOORD_1`), one per position; empty when the mesh has none
    /// (read as zero).
    pub uvs1: Vec<Vec2>,
    /// xyz tangent, w handedness (glTF convention).
    pub tangents: Vec<Vec4>,
    /// Linear RGBA vertex colours (glTF `COLOR_0`), one per position; empty when the mesh
    /// has none (read as white).
    pub colors: Vec<Vec4>,
    /// Triangle list; always present (non-indexed input gets 0..n).
    pub indices: Vec<u32>,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// With a blended material (glass), still cast shadows (scene files:
    /// `blended_cast_shadows` on a model). Blended meshes cast none by default; opaque and
    /// alpha-masked meshes always do.
    pub blended_casts_shadow: bool,
}

/// How a surface lets light through (glTF `alphaMode`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum AlphaMode {
    /// Fully opaque; alpha is ignored.
    #[default]
    Opaque,
    /// Alpha-tested: fragments with alpha below the cutoff (0..1) are discarded.
    Mask(f32),
    /// Alpha-blended; drawn by the transparency passes after the opaque ones.
    Blend,
}

impl AlphaMode {
    /// Alpha-tested (`Mask`), whatever its cutoff.
    pub fn is_masked(self) -> bool {
        matches!(self, AlphaMode::Mask(_))
    }

    /// The alpha a masked fragment must reach to be kept; 0 (everything kept) otherwise.
    pub fn cutoff(self) -> f32 {
        match self {
            AlphaMode::Mask(c) => c,
            _ => 0.0,
        }
    }
}

/// Decoded texture pixels (RGBA8). `srgb` says whether the bytes are sRGB-encoded
/// (base colour, emissive) or linear data (metallic-roughness, normal, occlusion).
#[derive(Clone, Debug, PartialEq)]
pub struct TextureImage {
    /// File name or glTF image name, for messages.
    pub name: String,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels row by row from the top, four bytes (R, G, B, A) each: `width * height * 4`
    /// bytes.
    pub rgba8: Vec<u8>,
    /// Whether the colour bytes are sRGB-encoded (alpha is always linear).
    pub srgb: bool,
}

/// A glTF metallic-roughness material as imported; the material module maps it onto
/// its layered model.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceMaterial {
    /// Material name from the source file; scene files' `material_overrides` match it.
    pub name: String,
    /// Linear RGBA base colour factor (glTF `baseColorFactor`), multiplied with the texture.
    pub base_color: Vec4,
    /// Metalness factor, 0 (dielectric) to 1 (metal).
    pub metallic: f32,
    /// Perceptual roughness factor, 0 (mirror) to 1.
    pub roughness: f32,
    /// Linear emitted radiance factor (glTF `emissiveFactor` × `emissive_strength`).
    pub emissive: Vec3,
    /// Whether the surface is opaque, alpha-tested or blended.
    pub alpha_mode: AlphaMode,
    /// Whether back faces are lit and drawn (no back-face culling).
    pub double_sided: bool,
    /// Bit identifying the material type for light material masks (Leo demo).
    pub type_bit: u32,
    /// Base colour texture (sRGB), multiplied with `base_color`.
    pub base_color_texture: Option<std::sync::Arc<TextureImage>>,
    /// glTF layout: roughness in G, metallic in B.
    pub metallic_roughness_texture: Option<std::sync::Arc<TextureImage>>,
    /// Tangent-space normal map (linear).
    pub normal_texture: Option<std::sync::Arc<TextureImage>>,
    /// Scale of the normal map's x and y (glTF `normalTexture.scale`).
    pub normal_scale: f32,
    /// Emission texture (sRGB), multiplied with `emissive`.
    pub emissive_texture: Option<std::sync::Arc<TextureImage>>,
    /// Ambient occlusion texture (linear, R channel).
    pub occlusion_texture: Option<std::sync::Arc<TextureImage>>,
    /// How much the occlusion texture darkens ambient light, 0 (none) to 1 (full).
    pub occlusion_strength: f32,
    /// glTF `KHR_materials_unlit`: the base colour (× texture) shows as is, unlit.
    pub unlit: bool,
    /// The base colour and alpha are multiplied by the mesh's vertex colour (glTF
    /// `COLOR_0`): set on import where a primitive with vertex colours takes this
    /// material. Meshes without them read white.
    pub vertex_color: bool,
    /// Each texture slot's sampler and uv transform.
    pub sampling: SlotSampling,
}

/// The sampler and uv transform of each texture slot of a [`SurfaceMaterial`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SlotSampling {
    /// Sampler and uv transform of `base_color_texture`.
    pub base_color: TextureSampling,
    pub(crate) metallic_roughness: TextureSampling,
    /// Sampler and uv transform of `normal_texture`.
    pub normal: TextureSampling,
    /// Sampler and uv transform of `emissive_texture`.
    pub(crate) emissive: TextureSampling,
    pub(crate) occlusion: TextureSampling,
}

impl Default for SurfaceMaterial {
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_color: Vec4::ONE,
            metallic: 0.0,
            roughness: 1.0,
            emissive: Vec3::ZERO,
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
            type_bit: 1,
            base_color_texture: None,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            emissive_texture: None,
            occlusion_texture: None,
            occlusion_strength: 1.0,
            unlit: false,
            vertex_color: false,
            sampling: SlotSampling::default(),
        }
    }
}

/// The emission shape of a [`Light`]; both shapes fall off to zero at the light's range.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum LightShape {
    /// Emits equally in all directions.
    Point,
    /// Cone angles in radians from the axis; `inner <= outer <= pi/2`.
    Spot {
        /// Cone axis in world space (unit length).
        direction: Vec3,
        /// Angle from the axis where the falloff starts, radians.
        inner_angle: f32,
        /// Angle from the axis where the light reaches zero, radians.
        outer_angle: f32,
    },
}

/// Light flags (bit set).
pub mod light_flags {
    /// The light renders shadows (shadow maps or ray-cast shadows, as the graph has).
    pub const CASTS_SHADOW: u32 = 1;
    /// The light bounces once: its reflective shadow map spawns virtual point lights.
    pub const INDIRECT: u32 = 2;
    /// A virtual point light spawned on the GPU (`LIGHT_VPL` in lighting.wgsl).
    pub const VPL: u32 = 4;
}

/// A punctual light with a finite range (KHR_lights_punctual semantics: intensity in
/// candela, falloff window reaching exactly zero at `range`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Light {
    /// Position in world space, metres.
    pub position: Vec3,
    /// Distance in metres at which the light's falloff window reaches zero; culling uses it
    /// as the light's bounding sphere radius.
    pub range: f32,
    /// Linear RGB colour, multiplied with `intensity`.
    pub color: Vec3,
    /// Luminous intensity in candela.
    pub intensity: f32,
    /// Point or spot.
    pub shape: LightShape,
    /// Bit set of [`light_flags`] (`CASTS_SHADOW`, `INDIRECT`, `VPL`).
    #[serde(default)]
    pub flags: u32,
    /// Which material type bits this light lights.
    #[serde(default = "all_materials")]
    pub material_mask: u32,
}

fn all_materials() -> u32 {
    u32::MAX
}

impl Light {
    /// A point light with no flags that lights every material (`material_mask` all ones).
    pub fn point(position: Vec3, range: f32, color: Vec3, intensity: f32) -> Self {
        Self {
            position,
            range,
            color,
            intensity,
            shape: LightShape::Point,
            flags: 0,
            material_mask: u32::MAX,
        }
    }
}

/// A perspective camera.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Camera position in world space, metres.
    pub eye: Vec3,
    /// Point the camera looks at, world space.
    pub target: Vec3,
    /// World-space up direction (default +Y); need not be orthogonal to the view direction.
    #[serde(default = "default_up")]
    pub up: Vec3,
    /// Vertical field of view in radians.
    pub fov_y: f32,
    /// Near plane distance in metres (> 0).
    pub near: f32,
    /// Far plane distance in metres; `far / near` is at most [`MAX_FAR_OVER_NEAR`].
    pub far: f32,
}

fn default_up() -> Vec3 {
    Vec3::Y
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            eye: Vec3::new(0.0, 1.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y: 60f32.to_radians(),
            near: 0.1,
            far: 100.0,
        }
    }
}

/// Narrowest vertical field of view, degrees. At 1° a pixel of a 16,384-row frame still
/// subtends 1.07e-6 of its distance, about 9 f32 ulps (2^-23 relative): positions
/// reconstructed from depth through the inverse view-projection differ from pixel to pixel,
/// and the tile frustums the culling builds from neighbouring pixel rays are not degenerate.
/// Far narrower lenses collapse them (1e-6° rendered half or all black).
pub(crate) const MIN_FOV_Y_DEG: f32 = 1.0;
/// Largest far / near ratio, 2^24. The depth of the projection (standard Z, f32 depth) is
/// about 1 − near/z, and one ulp of values just under 1 is 2^-24: a surface at z keeps a
/// depth below the far plane's only while near·(1/z − 1/far) ≥ 2^-24. At the limit every
/// surface nearer than half the far plane does; past it depths round to the far plane, the
/// culling's depth bounds collapse and lights are lost (near 1e-8 with far 100 kept
/// nothing beyond 0.17 m).
pub const MAX_FAR_OVER_NEAR: f32 = 16_777_216.0;

impl Camera {
    /// Why a lens (vertical field of view in degrees, near and far planes in metres) is
    /// refused, naming the field; None when it is within the limits above.
    pub(crate) fn lens_error(fov_y_deg: f32, near: f32, far: f32) -> Option<String> {
        // A perspective projection ends below 180°.
        if !(MIN_FOV_Y_DEG..180.0).contains(&fov_y_deg) {
            return Some(format!(
                "fov_y_deg {fov_y_deg} must be at least {MIN_FOV_Y_DEG} (narrower lenses are beyond f32 position and culling precision) and below 180"
            ));
        }
        if !(near.is_finite() && near > 0.0) {
            return Some(format!("near {near} must be finite and > 0"));
        }
        if !(far.is_finite() && far > near) {
            return Some(format!("far {far} must be finite and > near {near}"));
        }
        if far / near > MAX_FAR_OVER_NEAR {
            return Some(format!(
                "far / near is {:e} (near {near}, far {far}), over the limit of 2^24 = {MAX_FAR_OVER_NEAR}: f32 depth cannot resolve the depth range (raise near)",
                far / near
            ));
        }
        None
    }

    /// World-to-view matrix (right-handed, looking down −Z).
    pub fn view(&self) -> Mat4 {
        Mat4::look_at_rh(self.eye, self.target, self.up)
    }
    /// Right-handed projection to wgpu's depth range 0 (near) .. 1 (far).
    pub fn projection(&self, aspect: f32) -> Mat4 {
        Mat4::perspective_rh(self.fov_y, aspect, self.near, self.far)
    }
}

/// What a scene contains, for the graph's `when:` conditions.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneFeatures {
    /// Some drawn material is alpha-blended (`AlphaMode::Blend`).
    pub has_transparent: bool,
    /// Some drawn material is alpha-tested (`AlphaMode::Mask`).
    pub has_alpha_mask: bool,
    /// Some light has `CASTS_SHADOW`.
    pub has_shadow_casters: bool,
    /// Some light has `INDIRECT` (spawns virtual point lights).
    pub has_indirect_lights: bool,
    /// Some light casts no shadow (shaded without a shadow test).
    pub has_unshadowed_lights: bool,
    /// Some light is a spot light.
    pub has_spot_lights: bool,
    /// The scene has at least one light.
    pub has_lights: bool,
    /// Some light is a point light.
    pub has_point_lights: bool,
    /// Some drawn material is double-sided (needs two-sided lighting / no back-face culling).
    pub has_double_sided: bool,
    /// Some drawn material emits light.
    pub has_emissive: bool,
    /// Some light is restricted to a subset of material types (`material_mask != u32::MAX`).
    pub has_material_masks: bool,
}

/// Everything needed to render a frame.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Scene name (file stem or built-in name), used in reports and benchmark rows.
    pub name: String,
    /// All meshes, in world space.
    pub meshes: Vec<Mesh>,
    /// Materials that [`Mesh::material`] indexes.
    pub materials: Vec<SurfaceMaterial>,
    /// The lights as placed (before any motion).
    pub lights: Vec<Light>,
    /// The scene's camera.
    pub camera: Camera,
    /// Preferred output size, if the scene names one.
    pub output_size: Option<(u32, u32)>,
    /// Constant ambient radiance added to every surface (0 for reference scenes).
    pub ambient: Vec3,
    /// Material overrides from a scene RON: (imported material name, material RON path as
    /// written in the scene file, e.g. `materials/brushed_metal.ron`). Loaded by the material
    /// module; names that match no material were reported as warnings at load.
    pub material_overrides: Vec<(String, std::path::PathBuf)>,
    /// The file this scene was loaded from (`None` for built-in scenes).
    pub source_path: Option<std::path::PathBuf>,
    /// How the ray-cast shadow BVH is built (scene files: `shadow_bvh: Medium`).
    pub shadow_bvh: BuildQuality,
    /// Art controls of indirect lights, by light index (lights marked indirect without
    /// an entry use [`super::VplControls::default`]).
    pub vpl_controls: std::collections::BTreeMap<u32, super::VplControls>,
    /// How lights move over time (scene files: `motion:` on a light or a light set);
    /// `lights` holds them as placed, before any motion.
    pub light_motion: Vec<super::motion::LightMotion>,
    /// Every light casts a shadow (scene files: `all_lights_cast_shadows: true`), the
    /// lights a benchmark sweep generates for the scene included.
    pub all_lights_cast_shadows: bool,
}

impl Scene {
    /// The VPL controls of light `i` (the defaults when the scene names none).
    pub fn vpl(&self, i: usize) -> super::VplControls {
        self.vpl_controls
            .get(&(i as u32))
            .copied()
            .unwrap_or_default()
    }

    /// What the scene contains, for the graph's `when:` conditions: passes whose condition
    /// is false are dropped at compile.
    pub fn features(&self) -> SceneFeatures {
        let uses = |f: &dyn Fn(&SurfaceMaterial) -> bool| {
            self.meshes
                .iter()
                .any(|m| self.materials.get(m.material).is_some_and(f))
        };
        SceneFeatures {
            has_transparent: uses(&|m| m.alpha_mode == AlphaMode::Blend),
            has_alpha_mask: uses(&|m| m.alpha_mode.is_masked()),
            has_shadow_casters: self
                .lights
                .iter()
                .any(|l| l.flags & light_flags::CASTS_SHADOW != 0),
            has_indirect_lights: self
                .lights
                .iter()
                .any(|l| l.flags & light_flags::INDIRECT != 0),
            has_unshadowed_lights: self
                .lights
                .iter()
                .any(|l| l.flags & light_flags::CASTS_SHADOW == 0),
            has_spot_lights: self
                .lights
                .iter()
                .any(|l| matches!(l.shape, LightShape::Spot { .. })),
            has_lights: !self.lights.is_empty(),
            has_point_lights: self
                .lights
                .iter()
                .any(|l| matches!(l.shape, LightShape::Point)),
            has_double_sided: uses(&|m| m.double_sided),
            has_emissive: uses(&|m| m.emissive != Vec3::ZERO || m.emissive_texture.is_some()),
            has_material_masks: self.lights.iter().any(|l| l.material_mask != u32::MAX),
        }
    }

    /// Whether any light moves or flickers.
    pub fn has_motion(&self) -> bool {
        !self.light_motion.is_empty()
    }

    /// The lights at `t` seconds into `out` (cleared first; no allocation once it has
    /// room): a pure function of the scene and `t`.
    pub fn lights_at(&self, t: f64, out: &mut Vec<Light>) {
        super::motion::animate_into(&self.lights, &self.light_motion, t, out);
    }

    /// Moves the lights to where they are at `t` seconds, for good: the motion is dropped
    /// (a still frame of a moving scene).
    pub fn place_lights_at(&mut self, t: f64) {
        if self.has_motion() {
            let mut lights = Vec::with_capacity(self.lights.len());
            self.lights_at(t, &mut lights);
            self.lights = lights;
            self.light_motion.clear();
        }
    }

    /// Whether `mesh` casts shadows (is in the shadow BVH and drawn into shadow maps):
    /// every mesh whose material is not blended, and blended ones that opt in.
    pub fn casts_shadow(&self, mesh: &Mesh) -> bool {
        mesh.blended_casts_shadow
            || self
                .materials
                .get(mesh.material)
                .is_none_or(|m| m.alpha_mode != AlphaMode::Blend)
    }

    /// Number of triangles over all meshes.
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.indices.len() / 3).sum()
    }

    /// Index of the material called `name`, if any.
    pub fn material_index(&self, name: &str) -> Option<usize> {
        self.materials.iter().position(|m| m.name == name)
    }

    /// Adds a `headlight` when the scene has no lights but has
    /// geometry; returns it so that the caller can say so (the library never prints).
    pub fn add_headlight_if_unlit(&mut self) -> Option<Light> {
        if !self.lights.is_empty() {
            return None;
        }
        let light = super::lights::headlight(&self.camera, self.bounds()?);
        self.lights.push(light);
        Some(light)
    }

    /// Axis-aligned bounds (min, max) of all geometry in world space, or `None` for an empty
    /// scene.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut it = self.meshes.iter().flat_map(|m| m.positions.iter().copied());
        let first = it.next()?;
        Some(it.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p))))
    }
}

/// How hard the shadow BVH's PLOC builder works for a cheaper tree (after obvhs's presets
/// of the same names). On an NVIDIA H200 the chairs scene's
/// 11.2 M shadow rays at 1280×720 cast in 2.99 ms (`Fastest`), 2.75 (`VeryFast`), 1.90
/// (`Fast`, the default) and 1.76 ms (`Medium`); one-core builds on a 2-core x86-64
/// machine take 58, 72, 104 and 117 ms (`benches/sweeps/bvh_quality.ron`, `benches/bvh_build.rs`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum BuildQuality {
    /// PLOC search distance 1, no reinsertion: the quickest rebuild.
    Fastest,
    /// PLOC search distance 1, reinsertion of 1 % of the nodes (about 10 % lower SAH
    /// cost than `Fastest` on the chairs scene, about 10 ms more).
    VeryFast,
    /// PLOC search distance 6 (1 below depth 2), reinsertion of 2 %: the default, the
    /// best casting time per build millisecond measured.
    #[default]
    Fast,
    /// PLOC search distance 14 (1 below depth 3), reinsertion of 5 %.
    Medium,
}
