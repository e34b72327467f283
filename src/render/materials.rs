//! Materials as the renderer sees them: WGSL that fulfils the material contract of
//! `shaders/forward/forward.wgsl` (material_setup / material_eval / material_emission /
//! material_alpha / MATERIAL_TYPE_BIT), plus what the pipelines need to know.

use crate::scene::{AlphaMode, SurfaceMaterial};

#[derive(Clone, Debug)]
pub struct MaterialProgram {
    pub name: String,
    /// Generated WGSL, included as `<material>`.
    pub wgsl: String,
    pub alpha_mode: AlphaMode,
    pub double_sided: bool,
}

/// A constant Lambertian material (with emission): the reference material of the
/// culling tests and the fallback when no layered material is given.
pub fn lambert(name: &str, albedo: [f32; 3], emissive: [f32; 3], type_bit: u32) -> String {
    let _ = name;
    format!(
        "struct MaterialSample {{ n: vec3<f32>, }};
const MATERIAL_TYPE_BIT: u32 = {type_bit}u;
const MATERIAL_ALBEDO: vec3<f32> = vec3<f32>({:?}, {:?}, {:?});
const MATERIAL_EMISSIVE: vec3<f32> = vec3<f32>({:?}, {:?}, {:?});
fn material_setup(p: ShadingPoint) -> MaterialSample {{ return MaterialSample(p.normal); }}
fn material_eval(m: MaterialSample, l: vec3<f32>) -> vec3<f32> {{
    return MATERIAL_ALBEDO * (0.31830988618379067 * max(dot(m.n, l), 0.0));
}}
fn material_emission(m: MaterialSample) -> vec3<f32> {{ return MATERIAL_EMISSIVE; }}
fn material_alpha(m: MaterialSample) -> f32 {{ return 1.0; }}
",
        albedo[0], albedo[1], albedo[2], emissive[0], emissive[1], emissive[2]
    )
}

impl MaterialProgram {
    /// The scene's material as a program (constant factors, Lambertian).
    pub fn from_surface(m: &SurfaceMaterial) -> Self {
        let c = m.base_color;
        Self {
            name: m.name.clone(),
            wgsl: lambert(&m.name, [c.x, c.y, c.z], m.emissive.into(), m.type_bit),
            alpha_mode: m.alpha_mode,
            double_sided: m.double_sided,
        }
    }
}
