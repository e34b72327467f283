//! The RON model of a layered material, as artists write it (see `materials/*.ron`).
//!
//! A material is a stack of layers, top first. Each layer holds weighted lobes and an
//! interface (IOR, weight, transmission, absorption over a thickness). Light reaching
//! layer `i + 1` is scaled by what layer `i` lets through (see [`super::reference`]).

use crate::scene::AlphaMode;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A material file (`materials/*.ron`) as written: a stack of layers over shared textures,
/// alpha and emission. Parse one with [`Material::load`](super::Material::load);
/// docs/format.md describes every field.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    /// The material's name in messages (default empty).
    #[serde(default)]
    pub name: String,
    /// The material's type bit for light material masks (Leo demo). Default 1.
    #[serde(default = "one_u32")]
    pub(crate) type_bit: u32,
    /// How the surface lets light through (default `Opaque`).
    #[serde(default)]
    pub(crate) alpha_mode: AlphaMode,
    /// Back faces are drawn and shaded too (default `false`).
    #[serde(default)]
    pub(crate) double_sided: bool,
    /// Texture slots by name; bindings follow the name order (BTreeMap).
    #[serde(default)]
    pub(crate) textures: BTreeMap<String, TextureDesc>,
    /// Coverage (glTF: base colour alpha × texture alpha). Default 1.
    #[serde(default = "one_scalar")]
    pub(crate) alpha: Scalar,
    /// Emitted radiance. Default black.
    #[serde(default)]
    pub(crate) emissive: Option<Color>,
    #[serde(default)]
    pub(crate) normal_map: Option<NormalMap>,
    #[serde(default)]
    pub(crate) occlusion: Option<Occlusion>,
    /// Top layer first.
    pub layers: Vec<Layer>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct TextureDesc {
    /// Path relative to the material file.
    pub(crate) file: String,
    /// sRGB-encoded colour data (base colour, emissive) rather than linear data.
    #[serde(default)]
    pub(crate) srgb: bool,
    /// Wrap and filter modes (a glTF sampler). Default: repeat, trilinear.
    #[serde(default)]
    pub(crate) sampler: SamplerDesc,
    /// A transform of the uv before sampling (glTF `KHR_texture_transform`).
    #[serde(default)]
    pub(crate) transform: Option<UvTransform>,
    /// The uv set sampled: 0 (`TEXCOORD_0`, default) or 1 (`TEXCOORD_1`).
    #[serde(default)]
    pub(crate) tex_coord: u32,
}

/// How a texture is sampled: glTF's sampler (wrapS/wrapT, magFilter, minFilter).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SamplerDesc {
    /// Along u (glTF `wrapS`).
    #[serde(default)]
    pub wrap_u: Wrap,
    /// Along v (glTF `wrapT`).
    #[serde(default)]
    pub wrap_v: Wrap,
    /// Filter where the texture is magnified (default `Linear`).
    #[serde(default)]
    pub mag_filter: Filter,
    /// Filter within a mip level where it is minified (default `Linear`).
    #[serde(default)]
    pub min_filter: Filter,
    /// Between mip levels; `None` samples level 0 only (glTF minFilter NEAREST or LINEAR).
    #[serde(default)]
    pub mipmap_filter: MipmapFilter,
}

/// What a uv outside [0, 1] reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Wrap {
    /// The texture tiles (glTF REPEAT, the default).
    #[default]
    Repeat,
    /// The edge texel (glTF CLAMP_TO_EDGE).
    ClampToEdge,
    /// The texture tiles, every other copy mirrored (glTF MIRRORED_REPEAT).
    MirroredRepeat,
}

/// Within one mip level.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Filter {
    /// The nearest texel.
    Nearest,
    /// Bilinear between the four nearest texels.
    #[default]
    Linear,
}

/// Between mip levels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum MipmapFilter {
    /// Level 0 only, however small the footprint.
    None,
    /// The nearest level.
    Nearest,
    /// Blends the two nearest levels (trilinear with linear `min_filter`).
    #[default]
    Linear,
}

/// glTF `KHR_texture_transform`: uv' = T(offset) R(rotation) S(scale) uv.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UvTransform {
    /// Added last (default `(0, 0)`).
    #[serde(default)]
    pub offset: (f32, f32),
    /// Radians, counter-clockwise in uv space (clockwise as the image shows it).
    #[serde(default)]
    pub rotation: f32,
    /// Multiplies u and v first (default `(1, 1)`).
    #[serde(default = "ones2")]
    pub scale: (f32, f32),
}

impl Default for UvTransform {
    fn default() -> Self {
        UvTransform {
            offset: (0.0, 0.0),
            rotation: 0.0,
            scale: (1.0, 1.0),
        }
    }
}

impl UvTransform {
    /// The rows of the 2×3 matrix T R S of the glTF extension.
    pub(crate) fn matrix(&self) -> [[f32; 3]; 2] {
        let (s, c) = self.rotation.sin_cos();
        let (sx, sy) = self.scale;
        [
            [c * sx, s * sy, self.offset.0],
            [-s * sx, c * sy, self.offset.1],
        ]
    }

    /// The transformed uv.
    pub fn apply(&self, uv: [f32; 2]) -> [f32; 2] {
        let m = self.matrix();
        [
            m[0][0] * uv[0] + m[0][1] * uv[1] + m[0][2],
            m[1][0] * uv[0] + m[1][1] * uv[1] + m[1][2],
        ]
    }
}

/// How one texture slot of a glTF material is sampled (its sampler and transform).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TextureSampling {
    /// The slot's wrap and filter modes.
    pub sampler: SamplerDesc,
    /// The slot's uv transform, if any (`KHR_texture_transform`).
    pub transform: Option<UvTransform>,
    /// The uv set the slot samples: 0 (`TEXCOORD_0`) or 1 (`TEXCOORD_1`).
    pub tex_coord: u32,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct NormalMap {
    pub(crate) texture: String,
    #[serde(default = "one_f32")]
    pub scale: f32,
}

/// Ambient occlusion (glTF semantics: `1 + strength * (tex.r - 1)`); exposed to the
/// renderer as `material_occlusion(m)`, it does not scale `material_eval` (direct light).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Occlusion {
    pub(crate) texture: String,
    #[serde(default)]
    pub(crate) channel: Channel,
    #[serde(default = "one_f32")]
    pub(crate) strength: f32,
}

/// One layer of a material: weighted lobes, summed, under an interface that passes light on
/// to the next layer.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Layer {
    /// The layer's name in messages (default empty).
    #[serde(default)]
    pub name: String,
    /// Index of refraction of the layer's interface; `None` (or 1) means no interface
    /// Fresnel. Also bends the path used for absorption.
    #[serde(default)]
    pub(crate) ior: Option<f32>,
    /// Scales the interface Fresnel in `1 - F * weight` (e.g. clearcoat amount).
    #[serde(default = "one_f32")]
    pub(crate) weight: f32,
    /// How the interface Fresnel scales what reaches the layers below.
    #[serde(default)]
    pub coupling: Coupling,
    /// Fraction of the non-reflected light that goes on to the next layer.
    #[serde(default = "one_f32")]
    pub(crate) transmission: f32,
    /// Thickness of the layer for Beer-Lambert absorption (same unit as `absorption`⁻¹).
    #[serde(default)]
    pub(crate) thickness: f32,
    /// Absorption coefficient per unit thickness, per channel.
    #[serde(default)]
    pub(crate) absorption: (f32, f32, f32),
    /// The layer's weighted lobes, summed.
    pub lobes: Vec<Lobe>,
}

/// How a layer's interface Fresnel scales the light reaching the layers below.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Coupling {
    /// Light crosses the interface on the way in and out: `(1 − w F(n·l)) (1 − w F(n·v))`.
    /// Reciprocal and energy-conserving.
    #[default]
    Interface,
    /// glTF's `fresnel_mix`: `1 − w F(v·h)`. Exact glTF, but not energy-conserving for
    /// smooth layers at grazing angles (the diffuse below is not dimmed where the mirror
    /// reflection is strong).
    HalfVector,
}

/// One weighted BRDF lobe. Roughness is perceptual (α = roughness²).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Lobe {
    /// ρ/π.
    Lambert {
        /// Scales the lobe (default 1).
        #[serde(default = "one_f32")]
        weight: f32,
        /// Albedo, linear RGB.
        color: Color,
    },
    /// Fujii's improved Oren-Nayar; `roughness` is σ in [0, 1].
    OrenNayar {
        /// Scales the lobe (default 1).
        #[serde(default = "one_f32")]
        weight: f32,
        /// Albedo, linear RGB.
        color: Color,
        /// σ in [0, 1].
        roughness: Scalar,
    },
    /// glTF Appendix B microfacet lobe: GGX D, height-correlated Smith V, Schlick F
    /// from `f0` or, when absent, from `ior` (default 1.5).
    Ggx {
        /// Scales the lobe (default 1).
        #[serde(default = "one_f32")]
        weight: f32,
        /// Perceptual roughness in [0, 1].
        roughness: Scalar,
        /// Reflectance at normal incidence; takes precedence over `ior`.
        #[serde(default)]
        f0: Option<Color>,
        /// IOR for the Fresnel term when `f0` is absent (default 1.5).
        #[serde(default)]
        ior: Option<f32>,
    },
    /// Anisotropic GGX (αt = α(1 + a), αb = α(1 − a)), along the tangent.
    AnisoGgx {
        /// Scales the lobe (default 1).
        #[serde(default = "one_f32")]
        weight: f32,
        /// Perceptual roughness in [0, 1].
        roughness: Scalar,
        /// Anisotropy a in [−1, 1]: positive stretches the highlight along the tangent.
        anisotropy: Scalar,
        /// Reflectance at normal incidence; takes precedence over `ior`.
        #[serde(default)]
        f0: Option<Color>,
        /// IOR for the Fresnel term when `f0` is absent (default 1.5).
        #[serde(default)]
        ior: Option<f32>,
    },
    /// A monochrome GGX on the geometric normal (not the normal map), F0 from `ior`
    /// (default 1.5).
    Clearcoat {
        /// Scales the lobe (default 1).
        #[serde(default = "one_f32")]
        weight: f32,
        /// Perceptual roughness in [0, 1].
        roughness: Scalar,
        /// IOR of the coat (default 1.5).
        #[serde(default)]
        ior: Option<f32>,
    },
    /// Charlie sheen (Estevez & Kulla's D and fitted Λ visibility with their terminator
    /// softening; see `shaders/material/lobes.wgsl`).
    Sheen {
        /// Scales the lobe (default 1).
        #[serde(default = "one_f32")]
        weight: f32,
        /// Sheen colour, linear RGB.
        color: Color,
        /// Perceptual roughness in [0, 1].
        roughness: Scalar,
    },
}

impl Lobe {
    /// The variant's name as written in RON (`"Ggx"`, ...), for messages.
    pub fn kind(&self) -> &'static str {
        match self {
            Lobe::Lambert { .. } => "Lambert",
            Lobe::OrenNayar { .. } => "OrenNayar",
            Lobe::Ggx { .. } => "Ggx",
            Lobe::AnisoGgx { .. } => "AnisoGgx",
            Lobe::Clearcoat { .. } => "Clearcoat",
            Lobe::Sheen { .. } => "Sheen",
        }
    }

    pub(crate) fn weight(&self) -> f32 {
        match *self {
            Lobe::Lambert { weight, .. }
            | Lobe::OrenNayar { weight, .. }
            | Lobe::Ggx { weight, .. }
            | Lobe::AnisoGgx { weight, .. }
            | Lobe::Clearcoat { weight, .. }
            | Lobe::Sheen { weight, .. } => weight,
        }
    }
}

/// A texture channel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Channel {
    /// Red.
    #[default]
    R,
    /// Green (glTF roughness).
    G,
    /// Blue (glTF metallic).
    B,
    /// Alpha.
    A,
}

impl Channel {
    /// The channel's index in an RGBA texel (R = 0 .. A = 3).
    pub fn index(self) -> usize {
        self as usize
    }
    pub(crate) fn swizzle(self) -> &'static str {
        ["x", "y", "z", "w"][self as usize]
    }
}

/// A scalar parameter: a number, or an expression over texture channels.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Scalar {
    /// A constant.
    Val(f32),
    /// An expression over texture channels.
    Expr(ScalarExpr),
}

/// A scalar expression over texture channels (written without the `Expr` wrapper).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ScalarExpr {
    /// `scale * texture.channel`.
    Tex {
        /// A slot name from `textures`.
        texture: String,
        /// The channel read (default `R`).
        #[serde(default)]
        channel: Channel,
        /// Multiplies the channel (default 1).
        #[serde(default = "one_f32")]
        scale: f32,
    },
    /// `1 − x`.
    OneMinus(Box<Scalar>),
    /// `a × b`.
    Mul(Box<Scalar>, Box<Scalar>),
    /// The mesh's vertex alpha (glTF `COLOR_0`'s a, interpolated); 1 where the mesh has
    /// no vertex colours.
    VertexAlpha,
}

/// A colour parameter: `(r, g, b)`, or an expression over textures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Color {
    /// A linear RGB constant, `(r, g, b)`.
    Rgb(f32, f32, f32),
    /// An expression over textures.
    Expr(ColorExpr),
}

/// A colour expression over textures (written without the `Expr` wrapper).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ColorExpr {
    /// `scale * texture.rgb`.
    Tex {
        /// A slot name from `textures`.
        texture: String,
        /// Multiplies the texel's rgb (default `(1, 1, 1)`).
        #[serde(default = "ones3")]
        scale: (f32, f32, f32),
    },
    /// `a * (1 - t) + b * t` (WGSL `mix`).
    Mix {
        /// The colour at t = 0.
        a: Box<Color>,
        /// The colour at t = 1.
        b: Box<Color>,
        /// The blend factor.
        t: Scalar,
    },
    /// `color * scalar`.
    Scale(Box<Color>, Scalar),
    /// `a * b`, channel by channel.
    Mul(Box<Color>, Box<Color>),
    /// The mesh's vertex colour (glTF `COLOR_0`'s rgb, linear, interpolated); white where
    /// the mesh has no vertex colours.
    Vertex,
}

fn one_u32() -> u32 {
    1
}
fn one_f32() -> f32 {
    1.0
}
fn ones2() -> (f32, f32) {
    (1.0, 1.0)
}
fn ones3() -> (f32, f32, f32) {
    (1.0, 1.0, 1.0)
}
fn one_scalar() -> Scalar {
    Scalar::Val(1.0)
}

/// What a parameter expression reads besides constants: a texture (its slot name) or the
/// mesh's vertex colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Source<'a> {
    Texture(&'a str),
    Vertex,
}

impl MaterialDesc {
    /// What the material reads besides constants, in order, repeats kept: its alpha and
    /// emission expressions, the normal map's and occlusion's textures, then every
    /// lobe's parameters.
    pub(crate) fn sources(&self) -> Vec<Source<'_>> {
        let mut out = Vec::new();
        self.alpha.sources(&mut out);
        if let Some(e) = &self.emissive {
            e.sources(&mut out);
        }
        if let Some(n) = &self.normal_map {
            out.push(Source::Texture(&n.texture));
        }
        if let Some(o) = &self.occlusion {
            out.push(Source::Texture(&o.texture));
        }
        for lobe in self.layers.iter().flat_map(|l| &l.lobes) {
            lobe.sources(&mut out);
        }
        out
    }

    /// Whether any parameter reads the mesh's vertex colour (`Vertex`, `VertexAlpha`).
    pub fn reads_vertex_color(&self) -> bool {
        self.sources().contains(&Source::Vertex)
    }
}

impl Lobe {
    /// What the lobe's parameters read, in order.
    pub(crate) fn sources<'a>(&'a self, out: &mut Vec<Source<'a>>) {
        match self {
            Lobe::Lambert { color, .. } => color.sources(out),
            Lobe::OrenNayar {
                color, roughness, ..
            }
            | Lobe::Sheen {
                color, roughness, ..
            } => {
                color.sources(out);
                roughness.sources(out);
            }
            Lobe::Ggx { roughness, f0, .. } => {
                roughness.sources(out);
                if let Some(f) = f0 {
                    f.sources(out);
                }
            }
            Lobe::AnisoGgx {
                roughness,
                anisotropy,
                f0,
                ..
            } => {
                roughness.sources(out);
                anisotropy.sources(out);
                if let Some(f) = f0 {
                    f.sources(out);
                }
            }
            Lobe::Clearcoat { roughness, .. } => roughness.sources(out),
        }
    }
}

impl Scalar {
    /// What this expression reads, in order.
    pub(crate) fn sources<'a>(&'a self, out: &mut Vec<Source<'a>>) {
        match self {
            Scalar::Val(_) => {}
            Scalar::Expr(ScalarExpr::Tex { texture, .. }) => out.push(Source::Texture(texture)),
            Scalar::Expr(ScalarExpr::OneMinus(a)) => a.sources(out),
            Scalar::Expr(ScalarExpr::Mul(a, b)) => {
                a.sources(out);
                b.sources(out);
            }
            Scalar::Expr(ScalarExpr::VertexAlpha) => out.push(Source::Vertex),
        }
    }
}

impl Color {
    /// What this expression reads, in order.
    pub(crate) fn sources<'a>(&'a self, out: &mut Vec<Source<'a>>) {
        match self {
            Color::Rgb(..) => {}
            Color::Expr(ColorExpr::Tex { texture, .. }) => out.push(Source::Texture(texture)),
            Color::Expr(ColorExpr::Mix { a, b, t }) => {
                a.sources(out);
                b.sources(out);
                t.sources(out);
            }
            Color::Expr(ColorExpr::Scale(c, s)) => {
                c.sources(out);
                s.sources(out);
            }
            Color::Expr(ColorExpr::Mul(a, b)) => {
                a.sources(out);
                b.sources(out);
            }
            Color::Expr(ColorExpr::Vertex) => out.push(Source::Vertex),
        }
    }
}
