//! glTF metallic-roughness onto the layered model, exactly (glTF 2.0 Appendix B):
//!
//! `mix(fresnel_mix(1.5, diffuse(c), spec), conductor_fresnel(c, spec), m)`
//! `= F_schlick(mix(0.04, c, m)) · D·V + (1 − F_schlick(0.04)) · (1 − m) c / π`
//!
//! because Schlick's F is linear in F0. So: a top layer of IOR 1.5 holding one GGX lobe
//! with F0 = mix(0.04, c, m), over a Lambert layer of colour c (1 − m).
//! c = base colour factor × texture (sRGB) × vertex colour (COLOR_0), metallic = factor × texture B, roughness =
//! factor × texture G, alpha = base alpha × texture alpha × vertex alpha, emissive = factor × texture,
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
    let sampling = &s.sampling;
    for (name, img, how) in [
        (BASE, &s.base_color_texture, sampling.base_color),
        (
            MR,
            &s.metallic_roughness_texture,
            sampling.metallic_roughness,
        ),
        (NORMAL, &s.normal_texture, sampling.normal),
        (EMISSIVE, &s.emissive_texture, sampling.emissive),
        (OCCLUSION, &s.occlusion_texture, sampling.occlusion),
    ] {
        // Unlit: the base colour alone (KHR_materials_unlit ignores every other input).
        if s.unlit && name != BASE {
            continue;
        }
        if let Some(img) = img {
            textures.insert(name.to_string(), (img.clone(), how));
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
    // glTF 3.9.2: the base colour (and its alpha) times the vertex colour, where the
    // primitives that take this material have COLOR_0 (white where others have none).
    let base = if s.vertex_color {
        Color::Expr(ColorExpr::Mul(
            Box::new(base),
            Box::new(Color::Expr(ColorExpr::Vertex)),
        ))
    } else {
        base
    };
    let base_unlit = base.clone();
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
    let alpha = if s.vertex_color {
        Scalar::Expr(ScalarExpr::Mul(
            Box::new(alpha),
            Box::new(Scalar::Expr(ScalarExpr::VertexAlpha)),
        ))
    } else {
        alpha
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
    // Unlit: no lobes, and the base colour emitted, so every shading path that takes
    // the layered model shows it as is (ambient and lights add nothing).
    let (emissive, layers) = if s.unlit {
        (base_unlit, Vec::new())
    } else {
        (emissive, vec![spec, diffuse])
    };
    let desc = MaterialDesc {
        name: s.name.clone(),
        type_bit: s.type_bit,
        alpha_mode: s.alpha_mode,
        double_sided: s.double_sided,
        textures: textures
            .iter()
            .map(|(k, (img, how))| {
                (
                    k.clone(),
                    TextureDesc {
                        file: img.name.clone(),
                        srgb: img.srgb,
                        sampler: how.sampler,
                        tex_coord: how.tex_coord,
                        transform: how.transform,
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
        layers,
    };
    let slots = textures
        .into_iter()
        .enumerate()
        .map(|(i, (name, (img, how)))| TextureSlot {
            binding: i as u32 + 1,
            name,
            source: TextureSource::Image(img),
            sampler: how.sampler,
            tex_coord: how.tex_coord,
            transform: how.transform,
        })
        .collect();
    (desc, slots)
}
