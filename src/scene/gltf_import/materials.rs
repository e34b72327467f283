//! Materials: metallic-roughness PBR factors and texture slots, one scene material each.

use super::{named, Importer};
use crate::scene::error::SceneError;
use crate::scene::types::{AlphaMode, SurfaceMaterial};
use glam::{Vec3, Vec4};

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
        let tex = |this: &mut Self, info: Option<(gltf::Texture, u32)>, slot: &str, srgb: bool| {
            let (t, set) = info?;
            if set != 0 {
                this.warn(format!(
                    "{element} {slot}: TEXCOORD_{set} is not supported; TEXCOORD_0 used"
                ));
            }
            this.texture(t.source().index(), srgb, &format!("{element} {slot}"))
        };
        let base_color_texture = tex(
            self,
            pbr.base_color_texture()
                .map(|i| (i.texture(), i.tex_coord())),
            "baseColorTexture",
            true,
        );
        let metallic_roughness_texture = tex(
            self,
            pbr.metallic_roughness_texture()
                .map(|i| (i.texture(), i.tex_coord())),
            "metallicRoughnessTexture",
            false,
        );
        let normal = m.normal_texture();
        let normal_scale = normal.as_ref().map(|n| n.scale()).unwrap_or(1.0);
        let normal_texture = tex(
            self,
            normal.map(|i| (i.texture(), i.tex_coord())),
            "normalTexture",
            false,
        );
        let occ = m.occlusion_texture();
        let occlusion_strength = occ.as_ref().map(|o| o.strength()).unwrap_or(1.0);
        let occlusion_texture = tex(
            self,
            occ.map(|i| (i.texture(), i.tex_coord())),
            "occlusionTexture",
            false,
        );
        let emissive_texture = tex(
            self,
            m.emissive_texture().map(|i| (i.texture(), i.tex_coord())),
            "emissiveTexture",
            true,
        );
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
        };
        let idx = self.scene.materials.len();
        self.scene.materials.push(sm);
        self.materials.insert(m.index(), idx);
        Ok(idx)
    }
}
