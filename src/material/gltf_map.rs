//! glTF metallic-roughness onto the layered model, exactly (glTF 2.0 Appendix B):
//!
//! `mix(fresnel_mix(1.5, diffuse(c), spec), conductor_fresnel(c, spec), m)`
//! `= F_schlick(mix(0.04, c, m)) · D·V + (1 − F_schlick(0.04)) · (1 − m) c / π`
//!
//! because Schlick's F is linear in F0. So: a top layer of IOR 1.5 holding one GGX lobe
//! with F0 = mix(0.04, c, m), over a Lambert layer of colour c (1 − m).
//! c = base colour factor × texture (sRGB), metallic = factor × texture B, roughness =
//! factor × texture G, alpha = base alpha × texture alpha, emissive = factor × texture,
//! normal map with scale; occlusion (R, with strength) is exposed as `material_occlusion`
//! for the renderer's ambient term, and does not scale direct light.

use super::model::*;
use super::{TextureSlot, TextureSource};
use crate::scene::SurfaceMaterial;
use std::collections::BTreeMap;

const BASE: &str = "base_color";
const MR: &str = "metallic_roughness";
const NORMAL: &str = "normal";
const EMISSIVE: &str = "emissive";
const OCCLUSION: &str = "occlusion";

pub(super) fn map(s: &SurfaceMaterial) -> (MaterialDesc, Vec<TextureSlot>) {
    let mut textures = BTreeMap::new();
    for (name, img) in [
        (BASE, &s.base_color_texture),
        (MR, &s.metallic_roughness_texture),
        (NORMAL, &s.normal_texture),
        (EMISSIVE, &s.emissive_texture),
        (OCCLUSION, &s.occlusion_texture),
    ] {
        if let Some(img) = img {
            textures.insert(name.to_string(), img.clone());
        }
    }
    let has = |n: &str| textures.contains_key(n);
    let bc = s.base_color;
    let base = if has(BASE) {
        Color::Expr(ColorExpr::Tex {
            texture: BASE.into(),
            scale: (bc.x, bc.y, bc.z),
        })
    } else {
        Color::Rgb(bc.x, bc.y, bc.z)
    };
    let channel = |factor: f32, ch: Channel| {
        if has(MR) {
            Scalar::Expr(ScalarExpr::Tex {
                texture: MR.into(),
                channel: ch,
                scale: factor,
            })
        } else {
            Scalar::Val(factor)
        }
    };
    let metallic = channel(s.metallic, Channel::B);
    let roughness = channel(s.roughness, Channel::G);
    let alpha = if has(BASE) {
        Scalar::Expr(ScalarExpr::Tex {
            texture: BASE.into(),
            channel: Channel::A,
            scale: bc.w,
        })
    } else {
        Scalar::Val(bc.w)
    };
    let e = s.emissive;
    let emissive = if has(EMISSIVE) {
        Color::Expr(ColorExpr::Tex {
            texture: EMISSIVE.into(),
            scale: (e.x, e.y, e.z),
        })
    } else {
        Color::Rgb(e.x, e.y, e.z)
    };
    let spec = Layer {
        name: "specular".into(),
        ior: Some(1.5),
        weight: 1.0,
        coupling: Coupling::HalfVector,
        transmission: 1.0,
        thickness: 0.0,
        absorption: (0.0, 0.0, 0.0),
        lobes: vec![Lobe::Ggx {
            weight: 1.0,
            roughness,
            f0: Some(Color::Expr(ColorExpr::Mix {
                a: Box::new(Color::Rgb(0.04, 0.04, 0.04)),
                b: Box::new(base.clone()),
                t: metallic.clone(),
            })),
            ior: None,
        }],
    };
    let diffuse = Layer {
        name: "diffuse".into(),
        ior: None,
        weight: 1.0,
        coupling: Coupling::Interface,
        transmission: 1.0,
        thickness: 0.0,
        absorption: (0.0, 0.0, 0.0),
        lobes: vec![Lobe::Lambert {
            weight: 1.0,
            color: Color::Expr(ColorExpr::Mix {
                a: Box::new(base),
                b: Box::new(Color::Rgb(0.0, 0.0, 0.0)),
                t: metallic,
            }),
        }],
    };
    let desc = MaterialDesc {
        name: s.name.clone(),
        type_bit: s.type_bit,
        alpha_mode: s.alpha_mode,
        double_sided: s.double_sided,
        textures: textures
            .iter()
            .map(|(k, img)| {
                (
                    k.clone(),
                    TextureDesc {
                        file: img.name.clone(),
                        srgb: img.srgb,
                    },
                )
            })
            .collect(),
        alpha,
        emissive: Some(emissive),
        normal_map: has(NORMAL).then(|| NormalMap {
            texture: NORMAL.into(),
            scale: s.normal_scale,
        }),
        occlusion: has(OCCLUSION).then(|| Occlusion {
            texture: OCCLUSION.into(),
            channel: Channel::R,
            strength: s.occlusion_strength,
        }),
        layers: vec![spec, diffuse],
    };
    let slots = textures
        .into_iter()
        .enumerate()
        .map(|(i, (name, img))| TextureSlot {
            binding: i as u32 + 1,
            name,
            source: TextureSource::Image(img),
        })
        .collect();
    (desc, slots)
}
