//! MikkTSpace tangents (Mikkelsen's algorithm, as Blender and glTF exporters bake normal
//! maps with), through `bevy_mikktspace`: a safe Rust port, byte-identical to the
//! reference C code, without dependencies (the `mikktspace` crate pulls nalgebra or an
//! older glam by default).
//!
//! MikkTSpace gives each triangle corner its own tangent: a vertex shared by triangles
//! that disagree (a UV seam, a mirrored half) is split, so the mesh may grow.

use super::types::Mesh;
use bevy_mikktspace::{generate_tangents, Geometry, TangentSpace};
use glam::Vec4;
use std::collections::HashMap;

struct Corners<'a> {
    mesh: &'a Mesh,
    out: Vec<Vec4>,
}

impl Corners<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.mesh.indices[face * 3 + vert] as usize
    }
}

impl Geometry for Corners<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.indices.len() / 3
    }
    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }
    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.positions[self.vertex(face, vert)].to_array()
    }
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.normals[self.vertex(face, vert)].to_array()
    }
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        // glTF's v runs down the image; MikkTSpace's (Blender's) up. Flipped, the bitangent
        // sign is glTF's: bitangent = cross(normal, tangent) · w points to −v.
        let uv = self.mesh.uvs[self.vertex(face, vert)];
        [uv.x, 1.0 - uv.y]
    }
    fn set_tangent(&mut self, tangent: Option<TangentSpace>, face: usize, vert: usize) {
        // None: a degenerate triangle with no neighbour to borrow from; the shader builds
        // a frame from the normal alone for a zero tangent.
        self.out[face * 3 + vert] = tangent.map_or(Vec4::ZERO, |t| Vec4::from(t.tangent_encoded()));
    }
}

/// Replaces `mesh.tangents` with MikkTSpace tangents (w: glTF's bitangent sign), splitting
/// vertices whose corners got different tangents. Needs a uv and a normal per vertex; a
/// mesh without them is left as is and `false` returned.
pub fn mikktspace_tangents(mesh: &mut Mesh) -> bool {
    let n = mesh.positions.len();
    if mesh.uvs.len() != n || mesh.normals.len() != n || !mesh.indices.len().is_multiple_of(3) {
        return false;
    }
    let mut corners = Corners {
        mesh,
        out: vec![Vec4::ZERO; mesh.indices.len()],
    };
    // The crate's error type has no variants: generation cannot fail.
    let _ = generate_tangents(&mut corners);
    let tangents = corners.out;
    // Weld corners back: one vertex per (original vertex, tangent bits).
    let mut welded: HashMap<(u32, [u32; 4]), u32> = HashMap::with_capacity(n);
    let mut vertex_tangent: Vec<Option<Vec4>> = vec![None; n];
    let mut out = Mesh {
        name: std::mem::take(&mut mesh.name),
        material: mesh.material,
        ..Default::default()
    };
    out.positions = mesh.positions.clone();
    out.normals = mesh.normals.clone();
    out.uvs = mesh.uvs.clone();
    out.colors = mesh.colors.clone();
    out.uvs1 = mesh.uvs1.clone();
    out.tangents = vec![Vec4::ZERO; n];
    out.indices = Vec::with_capacity(mesh.indices.len());
    for (corner, &v) in mesh.indices.iter().enumerate() {
        let t = tangents[corner];
        let key = (v, t.to_array().map(f32::to_bits));
        let index = match vertex_tangent[v as usize] {
            // The vertex's first tangent keeps its index.
            None => {
                vertex_tangent[v as usize] = Some(t);
                out.tangents[v as usize] = t;
                welded.insert(key, v);
                v
            }
            Some(_) => *welded.entry(key).or_insert_with(|| {
                let i = out.positions.len() as u32;
                out.positions.push(mesh.positions[v as usize]);
                out.normals.push(mesh.normals[v as usize]);
                out.uvs.push(mesh.uvs[v as usize]);
                if let Some(&c) = mesh.colors.get(v as usize) {
                    out.colors.push(c);
                }
                if let Some(&uv) = mesh.uvs1.get(v as usize) {
                    out.uvs1.push(uv);
                }
                out.tangents.push(t);
                i
            }),
        };
        out.indices.push(index);
    }
    *mesh = out;
    true
}
