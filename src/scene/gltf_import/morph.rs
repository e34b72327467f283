//! Morph targets: the static pose a viewer shows without animation, the base attributes
//! plus each target's displacement times its default weight (the node's `weights`, else
//! the mesh's, else zero: the base mesh). Animations are not played; TANGENT displacements
//! are not applied (the file's tangents, or ones computed from the morphed normals, are used).

use super::Importer;
use crate::scene::error::SceneError;
use gltf::accessor::DataType;

/// Which attribute a displacement applies to.
#[derive(Clone, Copy)]
pub(super) enum MorphAttribute {
    Position,
    Normal,
}

impl Importer {
    /// Adds every target's `attribute` displacement, scaled by its weight, to `values`.
    pub(super) fn apply_morph(
        &self,
        prim: &gltf::Primitive,
        weights: Option<&[f32]>,
        attribute: MorphAttribute,
        values: &mut [[f32; 3]],
        element: &str,
    ) -> Result<(), SceneError> {
        let targets = prim.morph_targets().len();
        if let Some(w) = weights {
            if w.len() != targets {
                return Err(self.err(
                    element,
                    format!("{} morph weights for {targets} morph targets", w.len()),
                ));
            }
        }
        for (t, target) in prim.morph_targets().enumerate() {
            let weight = weights.map_or(0.0, |w| w[t]);
            if !weight.is_finite() {
                return Err(self.err(element, format!("morph weight {t} is {weight}")));
            }
            let (acc, name) = match attribute {
                MorphAttribute::Position => (target.positions(), "POSITION"),
                MorphAttribute::Normal => (target.normals(), "NORMAL"),
            };
            let Some(acc) = acc.filter(|_| weight != 0.0) else {
                continue;
            };
            let te = format!("{element} morph target {t} {name} accessor {}", acc.index());
            if acc.count() != values.len() {
                return Err(self.err(
                    te,
                    format!(
                        "has {} elements, the base has {}",
                        acc.count(),
                        values.len()
                    ),
                ));
            }
            let deltas: Vec<[f32; 3]> = self.read_f32(&acc, &te, &[DataType::F32])?;
            for (v, d) in values.iter_mut().zip(&deltas) {
                for c in 0..3 {
                    v[c] += weight * d[c];
                }
            }
        }
        Ok(())
    }
}
