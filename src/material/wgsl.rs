//! WGSL generation: the lobe library, the material's texture bindings, and
//! `material_setup` / `material_eval` / `material_emission` / `material_alpha` (plus
//! `material_occlusion`) specialised to the material's layers. Mirrors
//! [`super::reference::brdf_at`] operation for operation.

use super::model::{Color, ColorExpr, Lobe, Scalar, ScalarExpr};
use super::{Material, MaterialError};
use std::collections::BTreeMap;
use std::fmt::Write;

/// The lobe library (`shaders/material/lobes.wgsl`), included textually.
pub const LOBE_LIBRARY: &str = include_str!("../../shaders/material/lobes.wgsl");

/// The line that stands for the lobe library in code generated with
/// `WgslOptions::include_library`.
pub(crate) const LOBE_LIBRARY_INCLUDE: &str = "#include \"material/lobes.wgsl\"";

/// What every shading pass declares before including a material (the contract):
/// `shaders/common/shading_point.wgsl`, the shaders' one declaration of `ShadingPoint`.
pub const SHADING_POINT_WGSL: &str = include_str!("../../shaders/common/shading_point.wgsl");

/// How [`Material::wgsl_with`](super::Material::wgsl_with) generates a material's WGSL; the
/// default suits the forward and deferred fragment shaders.
#[derive(Clone, Debug, Default)]
pub struct WgslOptions {
    /// Sample textures with `textureSampleLevel(.., 0.0)` instead of `textureSample`, so the
    /// code also works outside fragment shaders (compute tests, ray-cast passes).
    pub sample_level_zero: bool,
    /// Sample with `textureSampleGrad(.., material_uv_ddx, material_uv_ddy)`: module-scope
    /// private variables (declared here) that the including shader sets before
    /// `material_setup` to the uv's screen derivatives (compute shading of a visibility
    /// buffer, where implicit derivatives do not exist). Takes precedence over
    /// `sample_level_zero`.
    pub sample_grad: bool,
    /// Include the lobe library with `#include "material/lobes.wgsl"` instead of its
    /// text: the renderer composes material code with its shaders, so the library is
    /// read from the root like any shader file and an edit to it reloads every
    /// material's pipelines. Standalone code (validation, `material --wgsl`, tests)
    /// leaves it off.
    pub include_library: bool,
    /// Read the material's per-pixel constants (colours, roughness, metalness, emission,
    /// alpha, texture and normal scales) from a storage buffer instead of writing them
    /// into the code: `Some(b)` declares
    /// `material_constants` (`array<f32>`) at `@group(0) @binding(b)` and a private
    /// `material_constant_base` the including shader sets to the material's first
    /// constant before `material_setup`. Materials that differ only in their constants
    /// then generate the same code, so one pipeline and one dispatch shade them all
    /// (visibility shading); `Material::wgsl_with_constants` returns the values. Such code
    /// declares neither `MATERIAL_ALPHA_CUTOFF` nor `MATERIAL_DOUBLE_SIDED` (only the
    /// rasterizing passes read them, with a material's own code), so materials that
    /// differ only in alpha cutoff or sidedness share it too. `material_eval`'s constants
    /// stay literals.
    pub constants_binding: Option<u32>,
}

fn lit(x: f32) -> String {
    let s = format!("{x:?}");
    if s.contains('.') || s.contains('e') || s.contains("inf") || s.contains("NaN") {
        s
    } else {
        format!("{s}.0")
    }
}

struct Gen<'a> {
    slot_of: BTreeMap<&'a str, usize>,
    /// The constants read from the buffer so far (`WgslOptions::constants_binding`);
    /// None writes them into the code.
    constants: Option<std::cell::RefCell<Vec<f32>>>,
}

impl Gen<'_> {
    /// A constant of the material: a literal, or the next entry of its constants.
    fn num(&self, x: f32) -> String {
        match &self.constants {
            None => lit(x),
            Some(c) => {
                let mut c = c.borrow_mut();
                c.push(x);
                format!(
                    "material_constants[material_constant_base + {}u]",
                    c.len() - 1
                )
            }
        }
    }
    /// A constant of `material_eval` or `material_diffuse` (lobe weights, the layers'
    /// IOR, weight, transmission and absorption): always written into the code. The
    /// light loop calls `material_eval` once a light, and with these as literals the
    /// compiler folds most of `lg_through` away (read from the buffer, harada's shading
    /// took 0.219 ms instead of 0.181 on an H100); materials that share them (every glTF
    /// metallic-roughness material without KHR_materials_ior) still share their code.
    fn eval_num(&self, x: f32) -> String {
        lit(x)
    }
    fn tex(&self, name: &str) -> String {
        format!("tx{}", self.slot_of[name])
    }
    fn scalar(&self, s: &Scalar) -> String {
        match s {
            Scalar::Val(x) => self.num(*x),
            Scalar::Expr(ScalarExpr::Tex {
                texture,
                channel,
                scale,
            }) => format!(
                "({}.{} * {})",
                self.tex(texture),
                channel.swizzle(),
                self.num(*scale)
            ),
            Scalar::Expr(ScalarExpr::OneMinus(a)) => format!("(1.0 - {})", self.scalar(a)),
            Scalar::Expr(ScalarExpr::Mul(a, b)) => {
                format!("({} * {})", self.scalar(a), self.scalar(b))
            }
            Scalar::Expr(ScalarExpr::VertexAlpha) => "p.color.w".to_string(),
        }
    }
    fn color(&self, c: &Color) -> String {
        match c {
            Color::Rgb(r, g, b) => format!(
                "vec3<f32>({}, {}, {})",
                self.num(*r),
                self.num(*g),
                self.num(*b)
            ),
            Color::Expr(ColorExpr::Tex { texture, scale: s }) => format!(
                "({}.xyz * vec3<f32>({}, {}, {}))",
                self.tex(texture),
                self.num(s.0),
                self.num(s.1),
                self.num(s.2)
            ),
            Color::Expr(ColorExpr::Mix { a, b, t }) => {
                // a (1 − t) + b t, as the reference computes it.
                let t = self.scalar(t);
                format!(
                    "({} * (1.0 - {t}) + {} * {t})",
                    self.color(a),
                    self.color(b)
                )
            }
            Color::Expr(ColorExpr::Scale(c, s)) => {
                format!("({} * {})", self.color(c), self.scalar(s))
            }
            Color::Expr(ColorExpr::Mul(a, b)) => {
                format!("({} * {})", self.color(a), self.color(b))
            }
            Color::Expr(ColorExpr::Vertex) => "p.color.xyz".to_string(),
        }
    }
    fn f0(&self, f0: &Option<Color>, ior: Option<f32>) -> String {
        match f0 {
            Some(c) => format!("max({}, vec3<f32>(0.0))", self.color(c)),
            None => format!("vec3<f32>(lg_ior_f0({}))", self.num(ior.unwrap_or(1.5))),
        }
    }
}

/// The material's WGSL (not validated; see [`Material::wgsl`]) and, with `WgslOptions::constants_binding`, the constants it reads
/// from the buffer (empty otherwise). With constants from a buffer the code names neither
/// the material nor its file, so two materials that differ only in their constants
/// generate the same text.
pub(crate) fn generate_with_constants(m: &Material, opts: &WgslOptions) -> (String, Vec<f32>) {
    let desc = m.desc();
    let slots = m.texture_slots();
    let g = Gen {
        slot_of: slots
            .iter()
            .enumerate()
            .map(|(i, s)| (s.name.as_str(), i))
            .collect(),
        constants: opts.constants_binding.map(|_| Default::default()),
    };
    let mut o = String::new();
    match opts.constants_binding {
        None => {
            let _ = writeln!(
                o,
                "// Generated by lightgraph from {}: material `{}`. Do not edit.\n",
                m.path().display(),
                desc.name
            );
        }
        Some(binding) => {
            let _ = writeln!(
                o,
                "// Generated by lightgraph: material code with its constants read from a \
                 buffer, shared by the materials that differ only in them. Do not edit.\n\n\
                 @group(0) @binding({binding}) var<storage, read> material_constants: array<f32>;\n\
                 // The material's first constant, set by the shader before material_setup.\n\
                 var<private> material_constant_base: u32;\n"
            );
        }
    }
    if opts.include_library {
        o.push_str(LOBE_LIBRARY_INCLUDE);
        o.push('\n');
    } else {
        o.push_str(LOBE_LIBRARY);
    }
    o.push_str("\n// ---- material ----\n\n");
    let (samplers, sampler_of) = m.samplers();
    if !slots.is_empty() {
        // The first sampler at binding 0, the textures after it, further samplers after
        // them: a material of one sampler keeps the layout it always had.
        let _ = writeln!(
            o,
            "@group(2) @binding(0) var {}: sampler;",
            super::sampler_wgsl_name(0)
        );
        for (i, s) in slots.iter().enumerate() {
            let _ = writeln!(
                o,
                "@group(2) @binding({}) var material_tex{i}: texture_2d<f32>; // {}",
                s.binding, s.name
            );
        }
        let after = slots.iter().map(|s| s.binding).max().unwrap_or(0);
        for (k, d) in samplers.iter().enumerate().skip(1) {
            let _ = writeln!(
                o,
                "@group(2) @binding({}) var {}: sampler; // {d:?}",
                after as usize + k,
                super::sampler_wgsl_name(k)
            );
        }
        if opts.sample_grad {
            o.push_str("// The uv's derivatives along x and y (TEXCOORD_0, and TEXCOORD_1's with uv1), set by the shader before material_setup.\nvar<private> material_uv_ddx: vec2<f32>;\nvar<private> material_uv_ddy: vec2<f32>;\nvar<private> material_uv1_ddx: vec2<f32>;\nvar<private> material_uv1_ddy: vec2<f32>;\n");
        }
        o.push('\n');
    }
    let _ = writeln!(o, "const MATERIAL_TYPE_BIT: u32 = {}u;", desc.type_bit);
    let cutoff = desc.alpha_mode.cutoff();
    // Shared code leaves out what only the rasterizing passes read (the alpha test's
    // cutoff, the faces drawn): visibility shading, which takes it, reads neither, so
    // materials that differ only in them share their code.
    if g.constants.is_none() {
        let _ = writeln!(o, "const MATERIAL_ALPHA_CUTOFF: f32 = {};", lit(cutoff));
        let _ = writeln!(
            o,
            "const MATERIAL_DOUBLE_SIDED: bool = {};",
            desc.double_sided
        );
    }
    o.push('\n');

    // MaterialSample: frame, view, and the resolved parameters of every lobe.
    o.push_str("struct MaterialSample {\n    n: vec3<f32>,\n    ng: vec3<f32>,\n    t: vec3<f32>,\n    b: vec3<f32>,\n    v: vec3<f32>,\n    emission: vec3<f32>,\n    alpha: f32,\n    occlusion: f32,\n");
    for (i, layer) in desc.layers.iter().enumerate() {
        for (j, lobe) in layer.lobes.iter().enumerate() {
            let _ = writeln!(o, "    c{i}_{j}: vec3<f32>,");
            match lobe {
                Lobe::Lambert { .. } => {}
                Lobe::AnisoGgx { .. } => {
                    let _ = writeln!(o, "    r{i}_{j}: f32,\n    a{i}_{j}: f32,");
                }
                _ => {
                    let _ = writeln!(o, "    r{i}_{j}: f32,");
                }
            }
        }
    }
    o.push_str("};\n\n");

    // material_setup
    o.push_str(
        "fn material_setup(p: ShadingPoint) -> MaterialSample {\n    var m: MaterialSample;\n",
    );
    for (i, slot) in slots.iter().enumerate() {
        let smp = super::sampler_wgsl_name(sampler_of[i]);
        // The slot's uv set (TEXCOORD_0 or TEXCOORD_1) and its derivatives.
        let set = if slot.tex_coord == 1 { "uv1" } else { "uv" };
        // KHR_texture_transform: uv' = M (uv, 1); the derivatives take M's linear part.
        let (uv, ddx, ddy) = match &slot.transform {
            Some(t) => {
                let [r0, r1] = t.matrix().map(|r| r.map(|x| g.num(x)));
                let _ = writeln!(
                    o,
                    "    let uv{i} = vec2<f32>({} * p.{set}.x + {} * p.{set}.y + {}, {} * p.{set}.x + {} * p.{set}.y + {});",
                    r0[0], r0[1], r0[2], r1[0], r1[1], r1[2]
                );
                if opts.sample_grad {
                    for d in ["ddx", "ddy"] {
                        let _ = writeln!(
                            o,
                            "    let {d}{i} = vec2<f32>({} * material_{set}_{d}.x + {} * material_{set}_{d}.y, {} * material_{set}_{d}.x + {} * material_{set}_{d}.y);",
                            r0[0], r0[1], r1[0], r1[1]
                        );
                    }
                }
                (format!("uv{i}"), format!("ddx{i}"), format!("ddy{i}"))
            }
            None => (
                format!("p.{set}"),
                format!("material_{set}_ddx"),
                format!("material_{set}_ddy"),
            ),
        };
        let sample = if opts.sample_grad {
            format!("textureSampleGrad(material_tex{i}, {smp}, {uv}, {ddx}, {ddy})")
        } else if opts.sample_level_zero {
            format!("textureSampleLevel(material_tex{i}, {smp}, {uv}, 0.0)")
        } else {
            format!("textureSample(material_tex{i}, {smp}, {uv})")
        };
        let _ = writeln!(o, "    let tx{i} = {sample};");
    }
    o.push_str("    m.ng = p.normal;\n    let t0 = lg_tangent(p.normal, p.tangent);\n    let b0 = lg_bitangent(p.normal, t0, p.tangent.w);\n");
    if let Some(nm) = &desc.normal_map {
        let s = g.num(nm.scale);
        let _ = writeln!(
            o,
            "    let nm = ({}.xyz * 2.0 - 1.0) * vec3<f32>({s}, {s}, 1.0);",
            g.tex(&nm.texture)
        );
        o.push_str("    let np = t0 * nm.x + b0 * nm.y + p.normal * nm.z;\n    let npl = dot(np, np);\n    if (npl > 1e-12) {\n        m.n = np / sqrt(npl);\n    } else {\n        m.n = p.normal;\n    }\n    m.t = lg_tangent(m.n, vec4<f32>(t0, 1.0));\n    m.b = lg_bitangent(m.n, m.t, p.tangent.w);\n");
    } else {
        o.push_str("    m.n = p.normal;\n    m.t = t0;\n    m.b = b0;\n");
    }
    o.push_str("    m.v = p.view;\n");
    let emissive = desc
        .emissive
        .as_ref()
        .map_or("vec3<f32>(0.0)".to_string(), |e| g.color(e));
    let _ = writeln!(o, "    m.emission = max({emissive}, vec3<f32>(0.0));");
    let _ = writeln!(
        o,
        "    m.alpha = clamp({}, 0.0, 1.0);",
        g.scalar(&desc.alpha)
    );
    match &desc.occlusion {
        Some(occ) => {
            let _ = writeln!(
                o,
                "    m.occlusion = 1.0 + {} * ({}.{} - 1.0);",
                g.num(occ.strength),
                g.tex(&occ.texture),
                occ.channel.swizzle()
            );
        }
        None => o.push_str("    m.occlusion = 1.0;\n"),
    }
    for (i, layer) in desc.layers.iter().enumerate() {
        for (j, lobe) in layer.lobes.iter().enumerate() {
            let (c, r) = match lobe {
                Lobe::Lambert { color, .. } => {
                    (format!("max({}, vec3<f32>(0.0))", g.color(color)), None)
                }
                Lobe::OrenNayar {
                    color, roughness, ..
                }
                | Lobe::Sheen {
                    color, roughness, ..
                } => (
                    format!("max({}, vec3<f32>(0.0))", g.color(color)),
                    Some(g.scalar(roughness)),
                ),
                Lobe::Ggx {
                    roughness, f0, ior, ..
                }
                | Lobe::AnisoGgx {
                    roughness, f0, ior, ..
                } => (
                    g.f0(f0, *ior),
                    Some(format!("lg_alpha({})", g.scalar(roughness))),
                ),
                Lobe::Clearcoat { roughness, ior, .. } => (
                    g.f0(&None, *ior),
                    Some(format!("lg_alpha({})", g.scalar(roughness))),
                ),
            };
            let _ = writeln!(o, "    m.c{i}_{j} = {c};");
            if let Some(r) = r {
                let _ = writeln!(o, "    m.r{i}_{j} = {r};");
            }
            if let Lobe::AnisoGgx { anisotropy, .. } = lobe {
                let _ = writeln!(o, "    m.a{i}_{j} = {};", g.scalar(anisotropy));
            }
        }
    }
    o.push_str("    return m;\n}\n\n");

    // material_eval
    let has_clearcoat = desc
        .layers
        .iter()
        .flat_map(|l| &l.lobes)
        .any(|l| matches!(l, Lobe::Clearcoat { .. }));
    // A sheen lobe's D magnifies the error of |n × h|² up to 50×: it needs the split
    // product there everywhere (lobes.wgsl, LG_S2_EXACT).
    let has_sheen = desc
        .layers
        .iter()
        .flat_map(|l| &l.lobes)
        .any(|l| matches!(l, Lobe::Sheen { .. }));
    let s2 = if has_sheen {
        "LG_S2_EXACT"
    } else {
        "LG_S2_GUARDED"
    };
    let _ = write!(
        o,
        "fn material_eval(m: MaterialSample, l: vec3<f32>) -> vec3<f32> {{\n    let cos_l = lg_dot_guarded(m.n, l);\n    if (!(cos_l > 0.0)) {{\n        return vec3<f32>(0.0);\n    }}\n    let d = lg_dirs(m.n, m.v, l, {s2});\n"
    );
    if has_clearcoat {
        if desc.normal_map.is_some() {
            let _ = write!(o, "    let dg = lg_dirs(m.ng, m.v, l, {s2});\n    let cc_on = select(0.0, 1.0, dot(m.ng, l) > 0.0);\n");
        } else {
            o.push_str("    let dg = d;\n    let cc_on = 1.0;\n");
        }
    }
    o.push_str("    var acc = vec3<f32>(0.0);\n");
    let n = desc.layers.len();
    for (i, layer) in desc.layers.iter().enumerate().rev() {
        // Named only where the code is the material's own.
        if g.constants.is_none() {
            let _ = writeln!(o, "    // layer {i} `{}`", layer.name);
        }
        let _ = writeln!(o, "    var s{i} = vec3<f32>(0.0);");
        for (j, lobe) in layer.lobes.iter().enumerate() {
            let w = g.eval_num(lobe.weight());
            let f = match lobe {
                Lobe::Lambert { .. } => format!("lg_lambert(m.c{i}_{j})"),
                Lobe::OrenNayar { .. } => format!("lg_oren_nayar(m.c{i}_{j}, m.r{i}_{j}, d)"),
                Lobe::Sheen { .. } => format!("lg_sheen(m.c{i}_{j}, m.r{i}_{j}, d)"),
                Lobe::Ggx { .. } => format!("lg_ggx(m.c{i}_{j}, m.r{i}_{j}, d)"),
                Lobe::AnisoGgx { .. } => {
                    format!("lg_ggx_aniso(m.c{i}_{j}, m.r{i}_{j}, m.a{i}_{j}, m.t, m.b, m.v, l, d)")
                }
                Lobe::Clearcoat { .. } => format!("cc_on * lg_ggx(m.c{i}_{j}, m.r{i}_{j}, dg)"),
            };
            let _ = writeln!(o, "    s{i} += {f} * {w};");
        }
        if i + 1 == n {
            let _ = writeln!(o, "    acc = s{i};");
        } else {
            let a = layer.absorption;
            let th = layer.thickness;
            let sigma_d = [a.0 * th, a.1 * th, a.2 * th];
            let common = format!(
                "{}, {}, {}",
                g.eval_num(layer.ior.unwrap_or(1.0)),
                g.eval_num(layer.weight),
                g.eval_num(layer.transmission),
            );
            let coupling = layer.coupling as u32;
            if sigma_d.iter().all(|&x| x == 0.0) {
                // No absorption: its factor is 1 for every path (lobes.wgsl).
                let _ = writeln!(
                    o,
                    "    acc = s{i} + lg_through_clear({common}, {coupling}u, d) * acc;"
                );
            } else {
                let _ = writeln!(
                    o,
                    "    acc = s{i} + lg_through({common}, vec3<f32>({}, {}, {}), {coupling}u, d) * acc;",
                    g.eval_num(sigma_d[0]),
                    g.eval_num(sigma_d[1]),
                    g.eval_num(sigma_d[2]),
                );
            }
        }
    }
    o.push_str("    return acc * min(cos_l, 1.0);\n}\n\n");
    // What a reflective shadow map bounces: the diffuse lobes' colour (specular lobes are
    // not bounced), summed over layers.
    o.push_str(
        "fn material_diffuse(m: MaterialSample) -> vec3<f32> {\n    var acc = vec3<f32>(0.0);\n",
    );
    for (i, layer) in desc.layers.iter().enumerate() {
        for (j, lobe) in layer.lobes.iter().enumerate() {
            if matches!(lobe, Lobe::Lambert { .. } | Lobe::OrenNayar { .. }) {
                let _ = writeln!(o, "    acc += m.c{i}_{j} * {};", g.eval_num(lobe.weight()));
            }
        }
    }
    o.push_str("    return acc;\n}\n\n");
    // A light seen as a disc of angular radius θ (a VPL standing for a patch of surface)
    // blurs a glossy reflection: each GGX lobe's α grows with θ (`spread` = θ², in
    // half-vector angle θ/2), so a receiver's lobe spreads the light as the patch would
    // rather than as a point (Hašan et al., "Virtual Spherical Lights for Many-Light
    // Rendering of Glossy Scenes").
    o.push_str(
        "fn material_widened(m: MaterialSample, alpha_sq: f32) -> MaterialSample {\n    var w = m;\n",
    );
    for (i, layer) in desc.layers.iter().enumerate() {
        for (j, lobe) in layer.lobes.iter().enumerate() {
            if matches!(
                lobe,
                Lobe::Ggx { .. } | Lobe::AnisoGgx { .. } | Lobe::Clearcoat { .. }
            ) {
                let _ = writeln!(
                    o,
                    "    w.r{i}_{j} = min(sqrt(m.r{i}_{j} * m.r{i}_{j} + alpha_sq), 1.0);"
                );
            }
        }
    }
    o.push_str("    return w;\n}\n\n");
    o.push_str("fn material_emission(m: MaterialSample) -> vec3<f32> {\n    return m.emission;\n}\n\nfn material_alpha(m: MaterialSample) -> f32 {\n    return m.alpha;\n}\n\n// Ambient occlusion for the renderer's ambient/indirect term; material_eval ignores it.\nfn material_occlusion(m: MaterialSample) -> f32 {\n    return m.occlusion;\n}\n");
    let constants = g.constants.map(|c| c.into_inner()).unwrap_or_default();
    (o, constants)
}

/// Parses and validates `code` (after the `ShadingPoint` declaration) with naga.
pub(crate) fn validate(code: &str, material: &str) -> Result<(), MaterialError> {
    let full = format!("{SHADING_POINT_WGSL}\n{code}");
    if let Some(line) = crate::shader::limits::longest_statement_over_limit(&full) {
        return Err(MaterialError::Wgsl {
            material: material.to_string(),
            message: format!(
                "generated line {line}: a statement over {} operators",
                crate::shader::limits::MAX_OPERATORS_PER_STATEMENT
            ),
        });
    }
    crate::shader::limits::on_naga_stack(|| validate_with_naga(&full, material))
}

fn validate_with_naga(full: &str, material: &str) -> Result<(), MaterialError> {
    let module = naga::front::wgsl::parse_str(full).map_err(|e| MaterialError::Wgsl {
        material: material.to_string(),
        message: e.emit_to_string(full),
    })?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .map_err(|e| MaterialError::Wgsl {
        material: material.to_string(),
        message: e.emit_to_string(full),
    })?;
    Ok(())
}
