//! Mesh primitives: triangles (strips and fans unrolled) with normals, UVs and tangents,
//! transformed to world space.

use super::morph::MorphAttribute;
use super::{named, Importer};
use crate::scene::error::SceneError;
use crate::scene::geometry::{compute_normals, compute_tangents};
use crate::scene::types::Mesh;
use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use gltf::accessor::DataType;

impl Importer {
    pub(super) fn import_mesh(
        &mut self,
        mesh: &gltf::Mesh,
        world: &Mat4,
        node_weights: Option<&[f32]>,
    ) -> Result<(), SceneError> {
        let weights = node_weights.or(mesh.weights());
        let mesh_el = named("mesh", mesh.index(), mesh.name());
        let prim_count = mesh.primitives().len();
        for prim in mesh.primitives() {
            let pel = format!("{mesh_el} primitive {}", prim.index());
            use gltf::mesh::Mode;
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                self.warn(format!(
                    "{pel}: {mode:?} primitives are not triangles; skipped"
                ));
                continue;
            }
            let Some(pos_acc) = prim.get(&gltf::Semantic::Positions) else {
                self.warn(format!("{pel}: no POSITION attribute; skipped"));
                continue;
            };
            let el =
                |sem: &str, acc: &gltf::Accessor| format!("{pel} {sem} accessor {}", acc.index());
            let pe = el("POSITION", &pos_acc);
            let mut local: Vec<[f32; 3]> = self.read_f32(&pos_acc, &pe, &[DataType::F32])?;
            self.apply_morph(&prim, weights, MorphAttribute::Position, &mut local, &pel)?;
            let n = local.len();
            if let Some(i) = local.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
                return Err(self.err(
                    pe,
                    format!(
                        "vertex {i} position {:?} is not finite (NaN or Inf)",
                        local[i]
                    ),
                ));
            }
            let mut indices = match prim.indices() {
                Some(acc) => {
                    let ie = el("indices", &acc);
                    let idx = self.read_indices(&acc, &ie)?;
                    if let Some(k) = idx.iter().position(|&i| i as usize >= n) {
                        return Err(self.err(
                            ie,
                            format!("index {k} is {}, past the vertex count {n}", idx[k]),
                        ));
                    }
                    idx
                }
                None => (0..n as u32).collect(),
            };
            indices = match mode {
                Mode::TriangleStrip => (2..indices.len())
                    .flat_map(|i| {
                        let (a, b, c) = (indices[i - 2], indices[i - 1], indices[i]);
                        if i % 2 == 0 {
                            [a, b, c]
                        } else {
                            [a, c, b]
                        }
                    })
                    .collect(),
                Mode::TriangleFan => (2..indices.len())
                    .flat_map(|i| [indices[i - 1], indices[i], indices[0]])
                    .collect(),
                _ => indices,
            };
            if indices.len() % 3 != 0 {
                self.warn(format!(
                    "{pel}: {} indices is not a multiple of 3; the last {} ignored",
                    indices.len(),
                    indices.len() % 3
                ));
                indices.truncate(indices.len() / 3 * 3);
            }
            self.triangles += indices.len() as u64 / 3;
            self.limit(
                &pel,
                "scene triangle count",
                self.triangles,
                self.limits.max_triangles,
            )?;

            let read_attr = |this: &Self,
                             sem: gltf::Semantic,
                             name: &str|
             -> Result<Option<(gltf::Accessor, String)>, SceneError> {
                match prim.get(&sem) {
                    Some(acc) => {
                        let e = el(name, &acc);
                        if acc.count() != n {
                            return Err(this.err(
                                e,
                                format!("has {} elements but POSITION has {n}", acc.count()),
                            ));
                        }
                        Ok(Some((acc, e)))
                    }
                    None => Ok(None),
                }
            };
            let normals_local: Option<Vec<[f32; 3]>> =
                match read_attr(self, gltf::Semantic::Normals, "NORMAL")? {
                    Some((acc, e)) => {
                        let mut v = self.read_f32(&acc, &e, &[DataType::F32])?;
                        self.apply_morph(&prim, weights, MorphAttribute::Normal, &mut v, &pel)?;
                        if v.iter().any(|p| !p.iter().all(|c| c.is_finite())) {
                            self.warn(format!("{e}: non-finite normals; normals regenerated"));
                            None
                        } else {
                            Some(v)
                        }
                    }
                    None => None,
                };
            let read_uvs = |this: &mut Self, set: u32| -> Result<Vec<Vec2>, SceneError> {
                let name = format!("TEXCOORD_{set}");
                Ok(
                    match read_attr(this, gltf::Semantic::TexCoords(set), &name)? {
                        Some((acc, e)) => this
                            .read_f32::<2>(&acc, &e, &[DataType::F32, DataType::U8, DataType::U16])?
                            .into_iter()
                            .map(|[u, v]| {
                                if u.is_finite() && v.is_finite() {
                                    Vec2::new(u, v)
                                } else {
                                    Vec2::ZERO
                                }
                            })
                            .collect(),
                        None => Vec::new(),
                    },
                )
            };
            let uvs = read_uvs(self, 0)?;
            let uvs1 = read_uvs(self, 1)?;
            // Vertex colours multiply the base colour and alpha (glTF 2.0, 3.7.2.1).
            let colors = match read_attr(self, gltf::Semantic::Colors(0), "COLOR_0")? {
                Some((acc, e)) => self.vertex_colors(&acc, &e)?,
                None => Vec::new(),
            };
            let tangents_local: Option<Vec<[f32; 4]>> =
                match read_attr(self, gltf::Semantic::Tangents, "TANGENT")? {
                    Some((acc, e)) => {
                        let v = self.read_f32(&acc, &e, &[DataType::F32])?;
                        if v.iter().any(|p| !p.iter().all(|c| c.is_finite())) {
                            self.warn(format!("{e}: non-finite tangents; tangents regenerated"));
                            None
                        } else {
                            Some(v)
                        }
                    }
                    None => None,
                };

            // To world space.
            let m3 = Mat3::from_mat4(*world);
            let det = m3.determinant();
            let normal_m = if det.abs() > 1e-30 {
                m3.inverse().transpose()
            } else {
                m3
            };
            let positions: Vec<Vec3> = local
                .iter()
                .map(|p| world.transform_point3(Vec3::from(*p)))
                .collect();
            if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
                return Err(self.err(
                    pe,
                    format!("vertex {i} is not finite after the node transforms"),
                ));
            }
            if det < 0.0 {
                // Mirroring transform: keep counter-clockwise front faces.
                for t in indices.chunks_exact_mut(3) {
                    t.swap(1, 2);
                }
            }
            let normals = match &normals_local {
                Some(v) => self.world_normals(&pel, v, normal_m, &positions, &indices),
                None => compute_normals(&positions, &indices),
            };
            let material = self.material(prim.material())?;
            // glTF: a normal-mapped primitive without tangents gets MikkTSpace's (below).
            // (The file's tangents count only with the file's normals, as glTF says.)
            let file_tangents = tangents_local.is_some() && normals_local.is_some();
            if !colors.is_empty() {
                self.scene.materials[material].vertex_color = true;
            }
            let mikktspace = !file_tangents
                && uvs.len() == n
                && self.scene.materials[material].normal_texture.is_some();
            let tangents = match &tangents_local {
                Some(v) if normals_local.is_some() => v
                    .iter()
                    .zip(&normals)
                    .map(|(t, n)| {
                        let t3 = (m3 * Vec3::new(t[0], t[1], t[2]))
                            .try_normalize()
                            .unwrap_or_else(|| crate::scene::geometry::any_perpendicular(*n));
                        let w = if t[3] < 0.0 { -1.0 } else { 1.0 } * det.signum();
                        t3.extend(w)
                    })
                    .collect::<Vec<Vec4>>(),
                _ if mikktspace => Vec::new(),
                _ => compute_tangents(&positions, &normals, &uvs, &indices),
            };
            let name = match (mesh.name(), prim_count) {
                (Some(nm), 1) => nm.to_string(),
                (Some(nm), _) => format!("{nm}/{}", prim.index()),
                (None, 1) => format!("mesh{}", mesh.index()),
                (None, _) => format!("mesh{}/{}", mesh.index(), prim.index()),
            };
            let mut mesh = Mesh {
                name,
                positions,
                normals,
                uvs,
                uvs1,
                tangents,
                colors,
                indices,
                material,
                blended_casts_shadow: false,
            };
            if mikktspace {
                crate::scene::tangent_space::mikktspace_tangents(&mut mesh);
            }
            self.scene.meshes.push(mesh);
        }
        Ok(())
    }
}

impl Importer {
    /// COLOR_0 as linear RGBA (VEC3 reads alpha 1): float or normalized unsigned bytes
    /// or shorts, as glTF allows. Values outside 0..=1 (or not finite) are clamped into
    /// it, with a warning: glTF allows none, and a negative colour would subtract light.
    fn vertex_colors(&mut self, acc: &gltf::Accessor, e: &str) -> Result<Vec<Vec4>, SceneError> {
        let allowed = [DataType::F32, DataType::U8, DataType::U16];
        let raw: Vec<Vec4> = if acc.dimensions() == gltf::accessor::Dimensions::Vec3 {
            self.read_f32::<3>(acc, e, &allowed)?
                .into_iter()
                .map(|c| Vec3::from(c).extend(1.0))
                .collect()
        } else {
            self.read_f32::<4>(acc, e, &allowed)?
                .into_iter()
                .map(Vec4::from)
                .collect()
        };
        let bad = raw
            .iter()
            .filter(|c| !(c.cmpge(Vec4::ZERO).all() && c.cmple(Vec4::ONE).all()))
            .count();
        if bad > 0 {
            self.warn(format!(
                "{e}: {bad} vertex colours outside 0..=1 (or not finite), clamped into it"
            ));
        }
        Ok(raw
            .into_iter()
            .map(|c| {
                let c = Vec4::select(c.is_nan_mask(), Vec4::ZERO, c);
                c.clamp(Vec4::ZERO, Vec4::ONE)
            })
            .collect())
    }

    /// The file's normals in world space. Zero-length ones (exporters write them for
    /// unused or degenerate vertices) take the normal computed from the triangles, with a
    /// warning: a made-up direction would light them wrongly without a word.
    fn world_normals(
        &mut self,
        pel: &str,
        local: &[[f32; 3]],
        normal_m: Mat3,
        positions: &[Vec3],
        indices: &[u32],
    ) -> Vec<Vec3> {
        let mut normals: Vec<Option<Vec3>> = local
            .iter()
            .map(|n| (normal_m * Vec3::from(*n)).try_normalize())
            .collect();
        let zero = normals.iter().filter(|n| n.is_none()).count();
        if zero > 0 {
            let first = normals.iter().position(Option::is_none).unwrap_or(0);
            self.warn(format!(
                "{pel}: {zero} zero-length normals (the first at vertex {first}); replaced by normals computed from the triangles"
            ));
            let computed = compute_normals(positions, indices);
            for (n, c) in normals.iter_mut().zip(computed) {
                n.get_or_insert(c);
            }
        }
        normals.into_iter().map(|n| n.unwrap_or(Vec3::Y)).collect()
    }
}
