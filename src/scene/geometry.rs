//! Mesh helpers: generated normals and tangents, and a builder for procedural scenes.

use super::types::Mesh;
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};

/// Area-weighted vertex normals of a triangle list. Vertices no triangle touches get +Y.
pub(crate) fn compute_normals(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
        let face = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
        n[a] += face;
        n[b] += face;
        n[c] += face;
    }
    n.iter_mut()
        .for_each(|v| *v = v.try_normalize().unwrap_or(Vec3::Y));
    n
}

/// Any unit vector perpendicular to `n`.
pub(crate) fn any_perpendicular(n: Vec3) -> Vec3 {
    let a = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    (a - n * n.dot(a)).try_normalize().unwrap_or(Vec3::X)
}

/// Tangents by per-triangle accumulation of the UV-space derivatives (MikkTSpace-like: tangent
/// and bitangent accumulated per vertex, Gram-Schmidt against the normal, handedness in w).
/// Without UVs (or with degenerate UVs) a tangent perpendicular to the normal is chosen.
pub(crate) fn compute_tangents(
    positions: &[Vec3],
    normals: &[Vec3],
    uvs: &[Vec2],
    indices: &[u32],
) -> Vec<Vec4> {
    let count = positions.len();
    let mut t = vec![Vec3::ZERO; count];
    let mut b = vec![Vec3::ZERO; count];
    if uvs.len() == count {
        for tri in indices.chunks_exact(3) {
            let [i0, i1, i2] = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
            let e1 = positions[i1] - positions[i0];
            let e2 = positions[i2] - positions[i0];
            let d1 = uvs[i1] - uvs[i0];
            let d2 = uvs[i2] - uvs[i0];
            let det = d1.x * d2.y - d2.x * d1.y;
            if det.abs() < 1e-20 || !det.is_finite() {
                continue;
            }
            let r = 1.0 / det;
            let sdir = (e1 * d2.y - e2 * d1.y) * r;
            let tdir = (e2 * d1.x - e1 * d2.x) * r;
            for i in [i0, i1, i2] {
                t[i] += sdir;
                b[i] += tdir;
            }
        }
    }
    (0..count)
        .map(|i| {
            let n = normals.get(i).copied().unwrap_or(Vec3::Y);
            let tan = (t[i] - n * n.dot(t[i]))
                .try_normalize()
                .unwrap_or_else(|| any_perpendicular(n));
            let w = if n.cross(tan).dot(b[i]) < 0.0 {
                -1.0
            } else {
                1.0
            };
            tan.extend(w)
        })
        .collect()
}

/// Builds one mesh out of boxes, cylinders and swept profiles (for the built-in scenes).
#[derive(Default)]
pub struct MeshBuilder {
    /// The mesh built so far; take it when done.
    pub mesh: Mesh,
}

impl MeshBuilder {
    /// An empty mesh called `name` using material index `material` of the scene.
    pub fn new(name: &str, material: usize) -> Self {
        MeshBuilder {
            mesh: Mesh {
                name: name.into(),
                material,
                ..Default::default()
            },
        }
    }

    fn vertex(&mut self, p: Vec3, n: Vec3, uv: Vec2) -> u32 {
        let m = &mut self.mesh;
        m.positions.push(p);
        m.normals.push(n);
        m.uvs.push(uv);
        (m.positions.len() - 1) as u32
    }

    /// The four inward-facing walls of a room centred on the origin, `2hx` × `2hz` and `h`
    /// high from y = 0; `uv_x` tiles the walls along x, `uv_z` those along z.
    pub(crate) fn inward_walls(
        &mut self,
        hx: f32,
        hz: f32,
        h: f32,
        uv_x: Vec2,
        uv_z: Vec2,
    ) -> &mut Self {
        self.quad(
            Vec3::new(-hx, 0.0, -hz),
            Vec3::X * 2.0 * hx,
            Vec3::Y * h,
            uv_x,
        )
        .quad(
            Vec3::new(hx, 0.0, hz),
            -Vec3::X * 2.0 * hx,
            Vec3::Y * h,
            uv_x,
        )
        .quad(
            Vec3::new(-hx, 0.0, hz),
            Vec3::Z * -2.0 * hz,
            Vec3::Y * h,
            uv_z,
        )
        .quad(
            Vec3::new(hx, 0.0, -hz),
            Vec3::Z * 2.0 * hz,
            Vec3::Y * h,
            uv_z,
        )
    }

    /// A quad `o, o+u, o+u+v, o+v`, counter-clockwise seen from `u × v`.
    pub fn quad(&mut self, o: Vec3, u: Vec3, v: Vec3, uv_scale: Vec2) -> &mut Self {
        let n = u.cross(v).normalize_or_zero();
        let a = self.vertex(o, n, Vec2::ZERO);
        let b = self.vertex(o + u, n, Vec2::new(uv_scale.x, 0.0));
        let c = self.vertex(o + u + v, n, uv_scale);
        let d = self.vertex(o + v, n, Vec2::new(0.0, uv_scale.y));
        self.mesh.indices.extend_from_slice(&[a, b, c, a, c, d]);
        self
    }

    /// An axis-aligned box with outward faces.
    pub fn cuboid(&mut self, min: Vec3, max: Vec3) -> &mut Self {
        let s = max - min;
        let (x, y, z) = (Vec3::X * s.x, Vec3::Y * s.y, Vec3::Z * s.z);
        let uv = |a: f32, b: f32| Vec2::new(a, b);
        self.quad(min, y, x, uv(s.y, s.x)) // -Z
            .quad(min + z, x, y, uv(s.x, s.y)) // +Z
            .quad(min, z, y, uv(s.z, s.y)) // -X
            .quad(min + x, y, z, uv(s.y, s.z)) // +X
            .quad(min, x, z, uv(s.x, s.z)) // -Y
            .quad(min + y, z, x, uv(s.z, s.x)) // +Y
    }

    /// A vertical cylinder (no caps) centred on `base`, `segments` around, `rings` high.
    pub fn cylinder(
        &mut self,
        base: Vec3,
        radius: f32,
        height: f32,
        segments: u32,
        rings: u32,
    ) -> &mut Self {
        let start = self.mesh.positions.len() as u32;
        for r in 0..=rings {
            let h = height * r as f32 / rings as f32;
            for s in 0..=segments {
                let a = std::f32::consts::TAU * s as f32 / segments as f32;
                let n = Vec3::new(a.cos(), 0.0, -a.sin());
                self.vertex(
                    base + n * radius + Vec3::Y * h,
                    n,
                    Vec2::new(s as f32 / segments as f32, h),
                );
            }
        }
        let row = segments + 1;
        for r in 0..rings {
            for s in 0..segments {
                let a = start + r * row + s;
                let (b, c, d) = (a + 1, a + row + 1, a + row);
                self.mesh.indices.extend_from_slice(&[a, b, c, a, c, d]);
            }
        }
        self
    }

    /// A semicircular arch in the plane spanned by `across` (unit, horizontal) and +Y, centred
    /// at `center` (the springing line), inner radius `r0`, outer `r1`, thickness `depth`
    /// along `across × Y`.
    pub(crate) fn arch(
        &mut self,
        center: Vec3,
        across: Vec3,
        r0: f32,
        r1: f32,
        depth: f32,
        segments: u32,
    ) -> &mut Self {
        let dz = across.cross(Vec3::Y).normalize() * (depth * 0.5);
        let point = |r: f32, t: f32| {
            let a = std::f32::consts::PI * t;
            center + across * (r * a.cos()) + Vec3::Y * (r * a.sin())
        };
        for i in 0..segments {
            let (t0, t1) = (i as f32 / segments as f32, (i + 1) as f32 / segments as f32);
            let (i0, i1, o0, o1) = (point(r0, t0), point(r0, t1), point(r1, t0), point(r1, t1));
            // front (+dz) and back (-dz) faces of the ring segment
            self.quad_pts([o0 + dz, o1 + dz, i1 + dz, i0 + dz]);
            self.quad_pts([i0 - dz, i1 - dz, o1 - dz, o0 - dz]);
            // intrados (faces the centre) and extrados
            self.quad_pts([i0 + dz, i1 + dz, i1 - dz, i0 - dz]);
            self.quad_pts([o0 - dz, o1 - dz, o1 + dz, o0 + dz]);
        }
        self
    }

    /// A planar quad from four points (counter-clockwise from the front).
    pub(crate) fn quad_pts(&mut self, p: [Vec3; 4]) -> &mut Self {
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        let base = self.mesh.positions.len() as u32;
        let uvs = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
        for (q, uv) in p.iter().zip(uvs) {
            self.vertex(*q, n, uv);
        }
        self.mesh
            .indices
            .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
        self
    }

    /// Applies a transform to everything added so far.
    pub(crate) fn transform(&mut self, rotation: Quat, translation: Vec3) -> &mut Self {
        let m = Mat4::from_rotation_translation(rotation, translation);
        self.mesh
            .positions
            .iter_mut()
            .for_each(|p| *p = m.transform_point3(*p));
        self.mesh
            .normals
            .iter_mut()
            .for_each(|n| *n = rotation * *n);
        self
    }

    /// Finishes the mesh (tangents generated from the UVs).
    pub fn build(mut self) -> Mesh {
        let m = &mut self.mesh;
        m.tangents = compute_tangents(&m.positions, &m.normals, &m.uvs, &m.indices);
        self.mesh
    }
}
