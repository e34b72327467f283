//! Materials: metallic-roughness PBR factors and texture slots, one scene material each.

use super::{named, Importer};
use crate::material::model::{
    Filter, MipmapFilter, SamplerDesc, TextureSampling, UvTransform, Wrap,
};
use crate::scene::error::SceneError;
use crate::scene::types::{AlphaMode, SlotSampling, SurfaceMaterial, TextureImage};
use glam::{Vec3, Vec4};
use gltf::texture::{MagFilter, MinFilter, WrappingMode};
use std::path::Path;
use std::sync::Arc;

const TEXTURE_TRANSFORM: &str = "KHR_texture_transform";

impl Importer {
    pub(super) fn material(&mut self, m: gltf::Material) -> Result<usize, SceneError> {
        if let Some(&i) = self.materials.get(&m.index()) {
            return Ok(i);
        }
        let element = match m.index() {
            Some(i) => named("material", i, m.name()),
            None => "default material".into(),
        };
        let pbr = m.pbr_metallic_roughness();
        let tex = |this: &mut Self,
                   info: Option<(gltf::Texture, u32, Option<TransformJson>)>,
                   slot: &str,
                   srgb: bool|
         -> Result<(Option<Arc<TextureImage>>, TextureSampling), SceneError> {
            let Some((t, set, transform)) = info else {
                return Ok((None, TextureSampling::default()));
            };
            let at = format!("{element} {slot}");
            let transform = transform.map(|j| j.read(&this.file, &at)).transpose()?;
            // KHR_texture_transform's texCoord replaces the textureInfo's.
            let mut set = transform.and_then(|t| t.1).unwrap_or(set);
            if set > 1 {
                this.warn(format!(
                    "{at}: TEXCOORD_{set} is not supported (sets 0 and 1 are); TEXCOORD_0 used"
                ));
                set = 0;
            }
            let sampling = TextureSampling {
                sampler: sampler_desc(&t.sampler()),
                transform: transform.map(|t| t.0),
                tex_coord: set,
            };
            Ok((this.texture(t.source().index(), srgb, &at), sampling))
        };
        let raw = |v: Option<&gltf::json::Value>| v.cloned().map(TransformJson::Raw);
        let (base_color_texture, base_color) = tex(
            self,
            pbr.base_color_texture().map(texture_info),
            "baseColorTexture",
            true,
        )?;
        let (metallic_roughness_texture, metallic_roughness) = tex(
            self,
            pbr.metallic_roughness_texture().map(texture_info),
            "metallicRoughnessTexture",
            false,
        )?;
        let normal = m.normal_texture();
        let normal_scale = normal.as_ref().map(|n| n.scale()).unwrap_or(1.0);
        let (normal_texture, normal) = tex(
            self,
            normal.map(|i| {
                let t = raw(i.extension_value(TEXTURE_TRANSFORM));
                (i.texture(), i.tex_coord(), t)
            }),
            "normalTexture",
            false,
        )?;
        let occ = m.occlusion_texture();
        let occlusion_strength = occ.as_ref().map(|o| o.strength()).unwrap_or(1.0);
        let (occlusion_texture, occlusion) = tex(
            self,
            occ.map(|i| {
                let t = raw(i.extension_value(TEXTURE_TRANSFORM));
                (i.texture(), i.tex_coord(), t)
            }),
            "occlusionTexture",
            false,
        )?;
        let (emissive_texture, emissive_sampling) = tex(
            self,
            m.emissive_texture().map(texture_info),
            "emissiveTexture",
            true,
        )?;
        let sampling = SlotSampling {
            base_color,
            metallic_roughness,
            normal,
            emissive: emissive_sampling,
            occlusion,
        };
        let base_color = Vec4::from(pbr.base_color_factor());
        let emissive = Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0);
        let (metallic, roughness) = (pbr.metallic_factor(), pbr.roughness_factor());
        let ok = base_color.is_finite()
            && emissive.is_finite()
            && metallic.is_finite()
            && roughness.is_finite();
        if !ok {
            return Err(self.err(element, "material factors are not finite"));
        }
        let alpha_mode = match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => {
                let cutoff = m.alpha_cutoff().unwrap_or(0.5);
                if let Some(rule) = crate::material::parse::alpha_cutoff_rule(cutoff) {
                    return Err(self.err(element, format!("alphaCutoff {cutoff} {rule}")));
                }
                AlphaMode::Mask(cutoff)
            }
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        };
        let sm = SurfaceMaterial {
            name: m
                .name()
                .map(str::to_string)
                .unwrap_or_else(|| match m.index() {
                    Some(i) => format!("material{i}"),
                    None => "default".into(),
                }),
            base_color,
            metallic: metallic.clamp(0.0, 1.0),
            roughness: roughness.clamp(0.0, 1.0),
            emissive,
            alpha_mode,
            double_sided: m.double_sided(),
            type_bit: 1,
            base_color_texture,
            metallic_roughness_texture,
            normal_texture,
            normal_scale,
            emissive_texture,
            occlusion_texture,
            occlusion_strength,
            unlit: m.unlit(),
            vertex_color: false,
            sampling,
        };
        let idx = self.scene.materials.len();
        self.scene.materials.push(sm);
        self.materials.insert(m.index(), idx);
        Ok(idx)
    }
}

/// A textureInfo's texture, set and transform (the latter parsed by the gltf crate).
fn texture_info(i: gltf::texture::Info<'_>) -> (gltf::Texture<'_>, u32, Option<TransformJson>) {
    let transform = i.texture_transform().map(|t| TransformJson::Parsed {
        offset: t.offset(),
        rotation: t.rotation(),
        scale: t.scale(),
        tex_coord: t.tex_coord(),
    });
    (i.texture(), i.tex_coord(), transform)
}

/// A glTF sampler as the material model's; undefined filters are linear (trilinear).
fn sampler_desc(s: &gltf::texture::Sampler) -> SamplerDesc {
    let wrap = |w: WrappingMode| match w {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
    };
    let mag_filter = match s.mag_filter() {
        Some(MagFilter::Nearest) => Filter::Nearest,
        Some(MagFilter::Linear) | None => Filter::Linear,
    };
    let (min_filter, mipmap_filter) = match s.min_filter() {
        Some(MinFilter::Nearest) => (Filter::Nearest, MipmapFilter::None),
        Some(MinFilter::Linear) => (Filter::Linear, MipmapFilter::None),
        Some(MinFilter::NearestMipmapNearest) => (Filter::Nearest, MipmapFilter::Nearest),
        Some(MinFilter::LinearMipmapNearest) => (Filter::Linear, MipmapFilter::Nearest),
        Some(MinFilter::NearestMipmapLinear) => (Filter::Nearest, MipmapFilter::Linear),
        Some(MinFilter::LinearMipmapLinear) | None => (Filter::Linear, MipmapFilter::Linear),
    };
    SamplerDesc {
        wrap_u: wrap(s.wrap_s()),
        wrap_v: wrap(s.wrap_t()),
        mag_filter,
        min_filter,
        mipmap_filter,
    }
}

/// A textureInfo's `KHR_texture_transform`: parsed by the gltf crate (textureInfo), or the
/// raw extension JSON (normal and occlusion textures, which gltf 1.4 leaves unparsed).
enum TransformJson {
    Parsed {
        offset: [f32; 2],
        rotation: f32,
        scale: [f32; 2],
        tex_coord: Option<u32>,
    },
    Raw(gltf::json::Value),
}

impl TransformJson {
    /// The transform and its texCoord override; an error names the texture when a value
    /// is malformed or not finite.
    fn read(self, file: &Path, at: &str) -> Result<(UvTransform, Option<u32>), SceneError> {
        let err = |m: &str| SceneError::invalid(file, at, format!("{TEXTURE_TRANSFORM}: {m}"));
        let (offset, rotation, scale, tex_coord) = match self {
            TransformJson::Parsed {
                offset,
                rotation,
                scale,
                tex_coord,
            } => (offset, rotation, scale, tex_coord),
            TransformJson::Raw(v) => {
                let pair = |key: &str, default: [f32; 2]| -> Result<[f32; 2], SceneError> {
                    match v.get(key) {
                        None => Ok(default),
                        Some(a) => match a.as_array().map(|a| a.as_slice()) {
                            Some([x, y]) => match (x.as_f64(), y.as_f64()) {
                                (Some(x), Some(y)) => Ok([x as f32, y as f32]),
                                _ => Err(err(&format!("{key} is not two numbers"))),
                            },
                            _ => Err(err(&format!("{key} is not two numbers"))),
                        },
                    }
                };
                let rotation = match v.get("rotation") {
                    None => 0.0,
                    Some(r) => r.as_f64().ok_or_else(|| err("rotation is not a number"))? as f32,
                };
                let tex_coord = match v.get("texCoord") {
                    None => None,
                    Some(t) => Some(
                        t.as_u64()
                            .and_then(|t| u32::try_from(t).ok())
                            .ok_or_else(|| err("texCoord is not a set index"))?,
                    ),
                };
                (
                    pair("offset", [0.0; 2])?,
                    rotation,
                    pair("scale", [1.0; 2])?,
                    tex_coord,
                )
            }
        };
        let all = [offset[0], offset[1], rotation, scale[0], scale[1]];
        if !all.iter().all(|x| x.is_finite()) {
            return Err(err(&format!(
                "offset {offset:?}, rotation {rotation}, scale {scale:?} are not all finite"
            )));
        }
        let t = UvTransform {
            offset: (offset[0], offset[1]),
            rotation,
            scale: (scale[0], scale[1]),
        };
        Ok((t, tex_coord))
    }
}
