//! Triangle chunks for culling per shadow view: a mesh's triangles reordered along a
//! Morton curve of their centroids and cut into runs of at most `CHUNK_TRIANGLES`, each
//! with its bounds. A light's view then draws the runs its frustum touches instead of the
//! whole mesh (a small light in a large room touches a few).

use glam::Vec3;

pub(crate) const CHUNK_TRIANGLES: usize = 128;

/// A run of `count` indices from `first` in the reordered index buffer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chunk {
    /// Index of the chunk's first index in the reordered index buffer.
    pub first: u32,
    /// Number of indices (three per triangle, at most 3 × 128).
    pub count: u32,
    /// Low corner of the bounds of the chunk's triangles, world space.
    pub(crate) min: Vec3,
    /// High corner of the bounds of the chunk's triangles, world space.
    pub(crate) max: Vec3,
}

/// The mesh's indices reordered into chunks, and the chunks. Triangles with an index
/// past `positions` are left out (the draw would read garbage).
pub(crate) fn chunk_triangles(positions: &[Vec3], indices: &[u32]) -> (Vec<u32>, Vec<Chunk>) {
    let (out, chunks, _) = chunk_triangles_with_sources(positions, indices);
    (out, chunks)
}

/// [`chunk_triangles`], and for each reordered triangle its index in `indices` (what a
/// pass that names triangles by their place in the mesh, as visibility ids do, needs).
pub(crate) fn chunk_triangles_with_sources(
    positions: &[Vec3],
    indices: &[u32],
) -> (Vec<u32>, Vec<Chunk>, Vec<u32>) {
    let tris: Vec<(u32, [u32; 3])> = indices
        .chunks_exact(3)
        .enumerate()
        .map(|(n, t)| (n as u32, [t[0], t[1], t[2]]))
        .filter(|(_, t)| t.iter().all(|&i| (i as usize) < positions.len()))
        .collect();
    let corner = |t: &[u32; 3], f: fn(Vec3, Vec3) -> Vec3| {
        t.iter()
            .map(|&i| positions[i as usize])
            .reduce(f)
            .unwrap_or_default()
    };
    let (lo, hi) = tris
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (_, t)| {
            (lo.min(corner(t, Vec3::min)), hi.max(corner(t, Vec3::max)))
        });
    let extent = (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
    let mut keyed: Vec<(u64, u32, [u32; 3])> = tris
        .into_iter()
        .map(|(n, t)| {
            let c = t.iter().map(|&i| positions[i as usize]).sum::<Vec3>() / 3.0;
            let q = ((c - lo) / extent * 1023.0).clamp(Vec3::ZERO, Vec3::splat(1023.0));
            (morton3(q.x as u32, q.y as u32, q.z as u32), n, t)
        })
        .collect();
    keyed.sort_by_key(|(k, _, _)| *k);
    let mut out = Vec::with_capacity(keyed.len() * 3);
    let mut chunks = Vec::new();
    let sources = keyed.iter().map(|(_, n, _)| *n).collect();
    for run in keyed.chunks(CHUNK_TRIANGLES) {
        let first = out.len() as u32;
        let (mut min, mut max) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for (_, _, t) in run {
            for &i in t {
                let p = positions[i as usize];
                min = min.min(p);
                max = max.max(p);
            }
            out.extend_from_slice(t);
        }
        chunks.push(Chunk {
            first,
            count: out.len() as u32 - first,
            min,
            max,
        });
    }
    (out, chunks, sources)
}

/// Interleaves the low 10 bits of x, y, z.
fn morton3(x: u32, y: u32, z: u32) -> u64 {
    fn spread(v: u32) -> u64 {
        let mut v = (v & 0x3ff) as u64;
        v = (v | (v << 16)) & 0x0300_00ff;
        v = (v | (v << 8)) & 0x0300_f00f;
        v = (v | (v << 4)) & 0x030c_30c3;
        v = (v | (v << 2)) & 0x0924_9249;
        v
    }
    spread(x) | (spread(y) << 1) | (spread(z) << 2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_keep_every_triangle_and_bound_it() {
        // A 40×40 grid of quads: 3,200 triangles.
        let n = 40;
        let positions: Vec<Vec3> = (0..=n)
            .flat_map(|z| (0..=n).map(move |x| Vec3::new(x as f32, 0.0, z as f32)))
            .collect();
        let mut indices = Vec::new();
        for z in 0..n {
            for x in 0..n {
                let i = z * (n + 1) + x;
                indices.extend([i, i + 1, i + n + 1, i + 1, i + n + 2, i + n + 1]);
            }
        }
        indices.extend([0, 1, 100_000]); // an index past the vertices is left out
        let (out, chunks, sources) = chunk_triangles_with_sources(&positions, &indices);
        assert_eq!(
            (out.clone(), chunks.clone()),
            chunk_triangles(&positions, &indices)
        );
        assert_eq!(out.len(), indices.len() - 3);
        // Each reordered triangle names its place in `indices`.
        assert_eq!(sources.len() * 3, out.len());
        for (t, &n) in sources.iter().enumerate() {
            let n = n as usize;
            assert_eq!(out[3 * t..3 * t + 3], indices[3 * n..3 * n + 3]);
        }
        let mut sorted_in: Vec<[u32; 3]> = indices[..indices.len() - 3]
            .chunks(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        let mut sorted_out: Vec<[u32; 3]> = out.chunks(3).map(|t| [t[0], t[1], t[2]]).collect();
        sorted_in.sort();
        sorted_out.sort();
        assert_eq!(sorted_in, sorted_out);
        assert_eq!(chunks.len(), 3200usize.div_ceil(CHUNK_TRIANGLES));
        let mut next = 0;
        for c in &chunks {
            assert_eq!(c.first, next);
            next += c.count;
            for &i in &out[c.first as usize..(c.first + c.count) as usize] {
                let p = positions[i as usize];
                assert!(p.cmpge(c.min).all() && p.cmple(c.max).all());
            }
            // Morton order keeps runs compact: a chunk's box covers a small part of the grid.
            let span = c.max - c.min;
            assert!(span.x * span.z <= 400.0, "{c:?}");
        }
        // The boxes tile the 40×40 grid with little overlap (1× would be a perfect tiling).
        let covered: f32 = chunks
            .iter()
            .map(|c| (c.max - c.min).x * (c.max - c.min).z)
            .sum();
        assert!(covered <= 3.0 * 1600.0, "boxes cover {covered}");
    }
}
