//! Artists may push values past physical ranges: allowed, but reported. Values that could
//! produce NaN or Inf (non-finite numbers, negative colours, IOR below 1, roughness outside
//! [0, 1], huge weights) are clamped, and reported too.

use super::model::{Color, ColorExpr, Lobe, MaterialDesc, Scalar, ScalarExpr};

/// Largest weight or colour component kept (past it values are clamped).
pub(crate) const MAX_GAIN: f32 = 64.0;
const MAX_BIG: f32 = 1e6;

#[derive(Clone, Copy)]
struct Range {
    lo: f32,
    phys_hi: f32,
    hi: f32,
}

const UNIT: Range = Range {
    lo: 0.0,
    phys_hi: 1.0,
    hi: 1.0,
};
const GAIN: Range = Range {
    lo: 0.0,
    phys_hi: 1.0,
    hi: MAX_GAIN,
};
const SIGNED_UNIT: Range = Range {
    lo: -1.0,
    phys_hi: 1.0,
    hi: 1.0,
};
const POSITIVE: Range = Range {
    lo: 0.0,
    phys_hi: MAX_BIG,
    hi: MAX_BIG,
};
const IOR: Range = Range {
    lo: 1.0,
    phys_hi: 5.0,
    hi: 100.0,
};

struct Ctx {
    warnings: Vec<String>,
}

impl Ctx {
    fn fix(&mut self, x: &mut f32, r: Range, what: &str) {
        if x.is_nan() {
            self.warnings
                .push(format!("{what} is NaN, set to {}", r.lo));
            *x = r.lo;
        } else if *x < r.lo {
            self.warnings
                .push(format!("{what} = {x} is below {}, clamped", r.lo));
            *x = r.lo;
        } else if *x > r.hi {
            self.warnings
                .push(format!("{what} = {x} is above {}, clamped", r.hi));
            *x = r.hi;
        } else if *x > r.phys_hi {
            self.warnings.push(format!(
                "{what} = {x} is past the physical range (≤ {}), kept",
                r.phys_hi
            ));
        }
    }

    fn scalar(&mut self, s: &mut Scalar, r: Range, what: &str) {
        match s {
            Scalar::Val(x) => self.fix(x, r, what),
            Scalar::Expr(ScalarExpr::Tex { scale, .. }) => {
                self.fix(scale, r, &format!("{what} texture scale"))
            }
            Scalar::Expr(ScalarExpr::OneMinus(a)) => self.scalar(a, UNIT, what),
            Scalar::Expr(ScalarExpr::Mul(a, b)) => {
                self.scalar(a, r, what);
                self.scalar(b, r, what);
            }
            Scalar::Expr(ScalarExpr::VertexAlpha) => {}
        }
    }

    fn color(&mut self, c: &mut Color, r: Range, what: &str) {
        match c {
            Color::Rgb(a, b, c) => {
                for x in [a, b, c] {
                    self.fix(x, r, what);
                }
            }
            Color::Expr(ColorExpr::Tex { scale, .. }) => {
                let what = format!("{what} texture scale");
                for x in [&mut scale.0, &mut scale.1, &mut scale.2] {
                    self.fix(x, r, &what);
                }
            }
            Color::Expr(ColorExpr::Mix { a, b, t }) => {
                self.color(a, r, what);
                self.color(b, r, what);
                self.scalar(t, UNIT, &format!("{what} mix factor"));
            }
            Color::Expr(ColorExpr::Scale(c, s)) => {
                self.color(c, r, what);
                self.scalar(s, GAIN, &format!("{what} scale"));
            }
            Color::Expr(ColorExpr::Mul(a, b)) => {
                self.color(a, r, what);
                self.color(b, r, what);
            }
            Color::Expr(ColorExpr::Vertex) => {}
        }
    }
}

/// Clamps what must be clamped, returns one message per questionable value.
pub(crate) fn sanitize(desc: &mut MaterialDesc) -> Vec<String> {
    let mut cx = Ctx {
        warnings: Vec::new(),
    };
    cx.scalar(&mut desc.alpha, UNIT, "alpha");
    if let Some(e) = &mut desc.emissive {
        cx.color(e, POSITIVE, "emissive");
    }
    if let Some(nm) = &mut desc.normal_map {
        cx.fix(
            &mut nm.scale,
            Range {
                lo: -MAX_GAIN,
                phys_hi: MAX_GAIN,
                hi: MAX_GAIN,
            },
            "normal map scale",
        );
    }
    if let Some(o) = &mut desc.occlusion {
        cx.fix(&mut o.strength, UNIT, "occlusion strength");
    }
    for (i, layer) in desc.layers.iter_mut().enumerate() {
        let ln = format!("layer {i}");
        if let Some(ior) = &mut layer.ior {
            cx.fix(ior, IOR, &format!("{ln} ior"));
        }
        cx.fix(&mut layer.weight, GAIN, &format!("{ln} weight"));
        cx.fix(&mut layer.transmission, GAIN, &format!("{ln} transmission"));
        cx.fix(&mut layer.thickness, POSITIVE, &format!("{ln} thickness"));
        let a = &mut layer.absorption;
        for x in [&mut a.0, &mut a.1, &mut a.2] {
            cx.fix(x, POSITIVE, &format!("{ln} absorption"));
        }
        let mut total = 0.0;
        for (j, lobe) in layer.lobes.iter_mut().enumerate() {
            let what = format!("{ln} lobe {j} ({})", lobe.kind());
            match lobe {
                Lobe::Lambert { weight, color } => {
                    cx.fix(weight, GAIN, &format!("{what} weight"));
                    cx.color(color, GAIN, &format!("{what} color"));
                }
                Lobe::OrenNayar {
                    weight,
                    color,
                    roughness,
                }
                | Lobe::Sheen {
                    weight,
                    color,
                    roughness,
                } => {
                    cx.fix(weight, GAIN, &format!("{what} weight"));
                    cx.color(color, GAIN, &format!("{what} color"));
                    cx.scalar(roughness, UNIT, &format!("{what} roughness"));
                }
                Lobe::Ggx {
                    weight,
                    roughness,
                    f0,
                    ior,
                } => {
                    cx.fix(weight, GAIN, &format!("{what} weight"));
                    cx.scalar(roughness, UNIT, &format!("{what} roughness"));
                    if let Some(f0) = f0 {
                        cx.color(f0, GAIN, &format!("{what} f0"));
                    }
                    if let Some(ior) = ior {
                        cx.fix(ior, IOR, &format!("{what} ior"));
                    }
                }
                Lobe::AnisoGgx {
                    weight,
                    roughness,
                    anisotropy,
                    f0,
                    ior,
                } => {
                    cx.fix(weight, GAIN, &format!("{what} weight"));
                    cx.scalar(roughness, UNIT, &format!("{what} roughness"));
                    cx.scalar(anisotropy, SIGNED_UNIT, &format!("{what} anisotropy"));
                    if let Some(f0) = f0 {
                        cx.color(f0, GAIN, &format!("{what} f0"));
                    }
                    if let Some(ior) = ior {
                        cx.fix(ior, IOR, &format!("{what} ior"));
                    }
                }
                Lobe::Clearcoat {
                    weight,
                    roughness,
                    ior,
                } => {
                    cx.fix(weight, GAIN, &format!("{what} weight"));
                    cx.scalar(roughness, UNIT, &format!("{what} roughness"));
                    if let Some(ior) = ior {
                        cx.fix(ior, IOR, &format!("{what} ior"));
                    }
                }
            }
            total += lobe.weight();
        }
        if total > 1.0 + 1e-6 {
            cx.warnings.push(format!(
                "{ln} lobe weights sum to {total} (> 1): may reflect more light than it receives"
            ));
        }
    }
    cx.warnings
}
