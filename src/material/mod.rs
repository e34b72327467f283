//! Layered BRDF materials (RON model, WGSL generation, f64 reference).
//!
//! A material file (`materials/*.ron`, see [`model::MaterialDesc`]) is parsed and validated
//! (`parse`), its out-of-range values are clamped or flagged (`sanitize`), and it
//! compiles to WGSL ([`wgsl`]) that plugs into the forward light loop through
//! `material_setup` / `material_eval` / `material_emission` / `material_alpha`.
//! [`reference`](mod@reference) is the f64 CPU implementation the tests compare the GPU against.
//!
//! # Accuracy (f32 WGSL against the f64 reference)
//!
//! The hard places are cancellations: n·l and n·v at grazing angles, |n × h| at the GGX peak
//! and at h ≈ n for sheen, v·h where l ≈ −v, and 1 − F at grazing. The lobe library
//! (`shaders/material/lobes.wgsl`) therefore
//! - computes dot and cross products of unit vectors as plain f32 where the result is at
//!   least 1/16 (accurate there), and below that with a split into a 2^-11 grid part,
//!   whose products are done exactly in i32, and a small remainder (`lg_dot`, `lg_cross`;
//!   sheen always takes the split |n × h|²):
//!   FMA-based error-free transformations are not portable (lavapipe does not fuse `fma`,
//!   and Mesa's NIR algebraic passes fold TwoSum away and factor `a·b + a·c`);
//! - takes |n × h|² from the accurate cross product with l + v scaled by a power of two
//!   (exact), instead of 1 − (n·h)²; v·h as |l + v| / 2 (symmetric, no cancellation);
//! - writes 1 − w·F(c) as (1 − w) + w (1 − F0) c (1 + m + m² + m³ + m⁴), m = 1 − c;
//! - writes the refracted cosine as sqrt((η − 1)(η + 1) + c²) / η;
//! - clamps α ≥ 0.002 (perceptual roughness 0.045, as Filament), cosines ≥ 1e-4 inside lobes.
//!
//! Measured on lavapipe over 65,536 random samples a lobe (roughness 0 and 1, grazing angles,
//! specular peaks), error |gpu − ref| / max(|ref|, 1e-3): every lobe ≤ 7.3e-5, layered
//! materials ≤ 4.9e-5 (see `tests/material_gpu.rs`).

pub(crate) mod error;
mod gltf_map;
pub mod model;
pub(crate) mod parse;
pub mod reference;
pub(crate) mod sanitize;
pub mod wgsl;

pub use error::{Location, MaterialError};
pub use model::MaterialDesc;
pub use wgsl::WgslOptions;

use crate::scene::TextureImage;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Where a texture slot's pixels come from.
#[derive(Clone, Debug, PartialEq)]
pub enum TextureSource {
    /// A file named in the RON (resolved against the material file's folder).
    File {
        /// The image file (PNG or JPEG).
        path: PathBuf,
        /// Whether the texels are sRGB-encoded colour rather than linear data.
        srgb: bool,
    },
    /// An image already decoded (glTF import).
    Image(Arc<TextureImage>),
}

impl TextureSource {
    /// Whether the bytes are sRGB-encoded (create the texture as `Rgba8UnormSrgb`).
    pub fn srgb(&self) -> bool {
        match self {
            TextureSource::File { srgb, .. } => *srgb,
            TextureSource::Image(img) => img.srgb,
        }
    }

    /// Decodes the texture to RGBA8.
    pub fn load(&self) -> Result<Arc<TextureImage>, MaterialError> {
        match self {
            TextureSource::Image(img) => Ok(img.clone()),
            TextureSource::File { path, srgb } => {
                let err = |message: String| MaterialError::TextureDecode {
                    name: path.display().to_string(),
                    path: path.clone(),
                    message,
                };
                let bytes = crate::files::read_bytes(path, crate::files::caps::IMAGE)
                    .map_err(|e| err(e.to_string()))?;
                let img = image::ImageReader::new(std::io::Cursor::new(bytes))
                    .with_guessed_format()
                    .map_err(|e| err(e.to_string()))?
                    .decode()
                    .map_err(|e| err(e.to_string()))?;
                let rgba = img.to_rgba8();
                Ok(Arc::new(TextureImage {
                    name: path.display().to_string(),
                    width: rgba.width(),
                    height: rgba.height(),
                    rgba8: rgba.into_raw(),
                    srgb: *srgb,
                }))
            }
        }
    }
}

/// One `texture_2d<f32>` of the material's bind group (`@group(2)`; binding 0 is the
/// first sampler `material_sampler`, further distinct samplers follow the textures), with
/// how it is sampled.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureSlot {
    /// The texture's binding in `@group(2)` (1 and up; 0 is the first sampler).
    pub binding: u32,
    /// The texture's name in the material file (and in the generated WGSL).
    pub name: String,
    /// Where the pixels come from.
    pub source: TextureSource,
    /// Wrap and filter modes of the sampler the slot reads through.
    pub sampler: model::SamplerDesc,
    /// The uv set sampled: 0 (`TEXCOORD_0`) or 1 (`TEXCOORD_1`).
    pub tex_coord: u32,
    /// The uv transform applied before sampling, if any.
    pub transform: Option<model::UvTransform>,
}

/// The WGSL name of the material's `k`-th distinct sampler: `material_sampler` (binding
/// 0) for the first, then `material_sampler{k}` at bindings after the textures.
pub(crate) fn sampler_wgsl_name(k: usize) -> String {
    if k == 0 {
        "material_sampler".into()
    } else {
        format!("material_sampler{k}")
    }
}

/// A validated, sanitised material.
#[derive(Clone, Debug)]
pub struct Material {
    desc: MaterialDesc,
    path: PathBuf,
    slots: Vec<TextureSlot>,
    warnings: Vec<String>,
}

impl Material {
    /// Reads and validates a material file.
    pub fn load(path: impl AsRef<Path>) -> Result<Material, MaterialError> {
        let path = path.as_ref();
        let src = crate::files::read_text(path, crate::files::caps::RON).map_err(|e| {
            MaterialError::Io {
                file: path.to_path_buf(),
                message: e.to_string(),
            }
        })?;
        Self::parse(&src, path)
    }

    /// Parses and validates material source; `path` names it in messages and anchors
    /// relative texture paths.
    pub fn parse(src: &str, path: impl AsRef<Path>) -> Result<Material, MaterialError> {
        let path = path.as_ref();
        let desc = parse::parse_desc(src, path)?;
        let slots = parse::file_slots(&desc, src, path)?;
        Ok(Self::finish(desc, path.to_path_buf(), slots))
    }

    /// The exact glTF metallic-roughness mapping (see `gltf_map.rs`).
    pub fn from_surface(surface: &crate::scene::SurfaceMaterial) -> Material {
        let (desc, slots) = gltf_map::map(surface);
        Self::finish(desc, PathBuf::from(format!("gltf:{}", surface.name)), slots)
    }

    fn finish(mut desc: MaterialDesc, path: PathBuf, slots: Vec<TextureSlot>) -> Material {
        let warnings = sanitize::sanitize(&mut desc);
        if !warnings.is_empty() {
            log::warn!(
                "material `{}` ({}): {}",
                desc.name,
                path.display(),
                warnings.join("; ")
            );
        }
        Material {
            desc,
            path,
            slots,
            warnings,
        }
    }

    /// The sanitised model (what the WGSL and the reference evaluate).
    pub fn desc(&self) -> &MaterialDesc {
        &self.desc
    }
    /// The material's name (`name:` in the file, or the glTF material's name).
    pub fn name(&self) -> &str {
        &self.desc.name
    }
    /// The material file, or `gltf:NAME` for a material mapped from glTF.
    pub fn path(&self) -> &Path {
        &self.path
    }
    /// Whether shading it reads more of the surface than a position and a normal: the
    /// uv (its textures) or the tangent (an anisotropic lobe). A deferred G-buffer keeps
    /// those for such materials only.
    pub fn reads_uv_or_tangent(&self) -> bool {
        !self.slots.is_empty()
            || self
                .desc
                .layers
                .iter()
                .flat_map(|l| &l.lobes)
                .any(|l| matches!(l, model::Lobe::AnisoGgx { .. }))
    }
    /// Whether a texture samples the second uv set (`TEXCOORD_1`).
    pub fn reads_uv1(&self) -> bool {
        self.slots.iter().any(|s| s.tex_coord == 1)
    }
    /// The bit this material answers to in a light's material mask.
    pub fn type_bit(&self) -> u32 {
        self.desc.type_bit
    }
    /// Texture slots in binding order (bindings 1..; 0 is the first sampler). Empty: the
    /// generated WGSL declares nothing in `@group(2)`.
    pub fn texture_slots(&self) -> &[TextureSlot] {
        &self.slots
    }
    /// The distinct samplers of the texture slots in first-use order, and for each slot
    /// the index of its sampler (see `sampler_wgsl_name`).
    pub fn samplers(&self) -> (Vec<model::SamplerDesc>, Vec<usize>) {
        let mut distinct: Vec<model::SamplerDesc> = Vec::new();
        let of_slot = self
            .slots
            .iter()
            .map(|s| match distinct.iter().position(|d| *d == s.sampler) {
                Some(k) => k,
                None => {
                    distinct.push(s.sampler);
                    distinct.len() - 1
                }
            })
            .collect();
        (distinct, of_slot)
    }
    /// Values past physical ranges (allowed, or clamped where they would produce NaN/Inf);
    /// logged once when the material was created.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }
    /// The material's WGSL for the forward shader (naga-validated).
    pub fn wgsl(&self) -> Result<String, MaterialError> {
        self.wgsl_with(&WgslOptions::default())
    }
    /// With `include_library` the code is validated with the built-in lobe library in
    /// place of its `#include` (the renderer's composer resolves the include, from the
    /// root first).
    pub fn wgsl_with(&self, options: &WgslOptions) -> Result<String, MaterialError> {
        Ok(self.wgsl_with_constants(options)?.0)
    }
    /// [`Self::wgsl_with`] and the constants the code reads from its buffer (empty
    /// without `WgslOptions::constants_binding`).
    pub fn wgsl_with_constants(
        &self,
        options: &WgslOptions,
    ) -> Result<(String, Vec<f32>), MaterialError> {
        let (code, constants) = wgsl::generate_with_constants(self, options);
        if options.include_library {
            let standalone = code.replacen(wgsl::LOBE_LIBRARY_INCLUDE, wgsl::LOBE_LIBRARY, 1);
            wgsl::validate(&standalone, self.name())?;
        } else {
            wgsl::validate(&code, self.name())?;
        }
        Ok((code, constants))
    }
    /// The material's code as the renderer composes it: the lobe library by `#include`.
    pub(crate) fn renderer_wgsl(&self, options: &WgslOptions) -> Result<String, MaterialError> {
        Ok(self.renderer_wgsl_with_constants(options)?.0)
    }
    /// [`Self::renderer_wgsl`] and the constants its buffer holds.
    pub(crate) fn renderer_wgsl_with_constants(
        &self,
        options: &WgslOptions,
    ) -> Result<(String, Vec<f32>), MaterialError> {
        self.wgsl_with_constants(&WgslOptions {
            include_library: true,
            ..options.clone()
        })
    }
}
