//! A flat test mesh: a grid of quads, and a .glb of one (for benchmarks).

use super::desc::{MaterialDesc, NodeDesc};
use super::GltfWriter;
use glam::{Vec2, Vec3};
use std::io;
use std::path::Path;

/// A `cells × cells` grid of quads (2 triangles each) in the XZ plane, size `size`, with
/// normals and UVs: (positions, normals, uvs, indices).
pub fn grid(cells: u32, size: f32) -> (Vec<Vec3>, Vec<Vec3>, Vec<Vec2>, Vec<u32>) {
    let n = cells + 1;
    let mut p = Vec::with_capacity((n * n) as usize);
    let mut uv = Vec::with_capacity((n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (i as f32 / cells as f32, j as f32 / cells as f32);
            p.push(Vec3::new((u - 0.5) * size, 0.0, (v - 0.5) * size));
            uv.push(Vec2::new(u, v));
        }
    }
    let normals = vec![Vec3::Y; p.len()];
    let mut idx = Vec::with_capacity((cells * cells * 6) as usize);
    for j in 0..cells {
        for i in 0..cells {
            let a = j * n + i;
            let (b, c, d) = (a + 1, a + n + 1, a + n);
            idx.extend_from_slice(&[a, d, c, a, c, b]);
        }
    }
    (p, normals, uv, idx)
}

/// Writes a .glb of one grid mesh of at least `triangles` triangles (for benchmarks).
pub fn write_grid_glb(path: &Path, triangles: u32) -> io::Result<()> {
    let cells = ((triangles as f64 / 2.0).sqrt().ceil() as u32).max(1);
    let (p, n, uv, idx) = grid(cells, 100.0);
    let mut w = GltfWriter::new();
    let m = w.add_material(&MaterialDesc::default());
    let mesh = w.add_simple_mesh("grid", &p, Some(&n), Some(&uv), Some(&idx), Some(m));
    let node = w.add_node(&NodeDesc {
        mesh: Some(mesh),
        ..Default::default()
    });
    w.add_root(node);
    w.write_glb(path)
}
