//! Every opaque and alpha-masked mesh merged into two storage buffers, for passes that
//! fetch vertices themselves: the visibility buffer's shading (which rebuilds a pixel's
//! attributes from its triangle id) and the compute rasterizer. The blended meshes are
//! merged the same way apart ([`VisibilityGeometry::build_transparent`]), for the
//! compute rasterizer's transparent depth.
//!
//! A triangle's id is its index in `triangles`: the meshes in [`SceneGpu::opaque_draws`]
//! order (sorted by material), each mesh's triangles in its index order. So one
//! material's triangles form one range, and drawing mesh `m`'s triangle `t` has the id
//! `GpuMesh::first_triangle + t`. [`NO_TRIANGLE`] marks a pixel nothing covers.
//!
//! Layouts, as WGSL reads them:
//! - `vertices: array<f32>`: 18 floats per vertex (position xyz, normal xyz, uv, tangent
//!   xyzw, colour rgba, second uv: [`GpuVertex`]), world space.
//! - `triangles: array<u32>`: three vertex indices per triangle, already offset into the
//!   merged `vertices`.
//! - `material_triangles: array<vec2<u32>>`: per scene material, its triangles' range
//!   `[first, end)` (empty where it has none).

use super::scene_gpu::{gpu_vertices, storage_buffer, SceneGpu};
use crate::gpu::structs::GpuVertex;
use crate::scene::Scene;

/// The id of "no surface" in a visibility buffer.
pub const NO_TRIANGLE: u32 = u32::MAX;

/// Floats per vertex in the merged `vertices` buffer.
pub const VERTEX_FLOATS: u32 = (std::mem::size_of::<GpuVertex>() / 4) as u32;

/// The scene's opaque meshes merged into storage buffers, for passes that fetch vertices by
/// triangle id (visibility buffer shading, compute rasterization).
pub struct VisibilityGeometry {
    /// Every merged vertex, [`VERTEX_FLOATS`] floats each, in world space.
    pub vertices: wgpu::Buffer,
    /// Three vertex indices per triangle; a visibility id indexes it.
    pub triangles: wgpu::Buffer,
    /// Each material's `[first, end)` triangle ids, as u32 pairs.
    pub material_triangles: wgpu::Buffer,
    /// Triangles merged.
    pub triangle_count: u32,
    /// Vertices merged.
    pub vertex_count: u32,
    /// `[first, end)` triangle ids of each scene material, as in `material_triangles`.
    pub material_ranges: Vec<[u32; 2]>,
}

impl VisibilityGeometry {
    /// Merges `gpu`'s opaque meshes (uploaded from `scene`) in draw order. Refuses what
    /// the device cannot bind or a 32-bit id cannot name.
    pub fn build(device: &wgpu::Device, gpu: &SceneGpu, scene: &Scene) -> Result<Self, String> {
        Self::merge(device, gpu, scene, &gpu.opaque_draws(), "opaque", true)
    }

    /// Merges `gpu`'s blended meshes in scene order: triangle ids index these buffers
    /// alone (no visibility buffer holds them), and each blended material's range is
    /// its meshes' (adjacent only where its meshes are).
    pub fn build_transparent(
        device: &wgpu::Device,
        gpu: &SceneGpu,
        scene: &Scene,
    ) -> Result<Self, String> {
        Self::merge(
            device,
            gpu,
            scene,
            &gpu.transparent_draws(),
            "blended",
            false,
        )
    }

    /// `draws` merged in order; `numbered`: their ids must be the visibility ids the
    /// upload numbered (the opaque draws').
    fn merge(
        device: &wgpu::Device,
        gpu: &SceneGpu,
        scene: &Scene,
        draws: &[usize],
        what: &str,
        numbered: bool,
    ) -> Result<Self, String> {
        let mut vertices: Vec<GpuVertex> = Vec::new();
        let mut triangles: Vec<u32> = Vec::new();
        let mut material_ranges = vec![[0u32, 0u32]; gpu.materials.len()];
        for &mesh in draws {
            let gm = &gpu.meshes[mesh];
            let m = &scene.meshes[gm.scene_mesh];
            let first = (triangles.len() / 3) as u64;
            if numbered && first != u64::from(gm.first_triangle) {
                return Err(format!(
                    "mesh '{}' starts at triangle {first}, its draws say {}",
                    m.name, gm.first_triangle
                ));
            }
            let base = u32::try_from(vertices.len())
                .map_err(|_| "the scene has more than 2^32 vertices".to_string())?;
            vertices.extend(gpu_vertices(m));
            triangles.extend(m.indices.iter().map(|&i| base + i));
            let end = (triangles.len() / 3) as u64;
            if end >= u64::from(NO_TRIANGLE) {
                return Err(format!(
                    "the scene has {end} {what} triangles; a 32-bit visibility id names at most {}",
                    NO_TRIANGLE - 1
                ));
            }
            let r = &mut material_ranges[gm.material];
            if r[0] == r[1] {
                *r = [first as u32, end as u32];
            } else {
                // Draws are sorted by material, so a material's meshes are adjacent.
                r[1] = end as u32;
            }
        }
        let limit = device.limits().max_storage_buffer_binding_size;
        let vertex_bytes = std::mem::size_of_val(&vertices[..]) as u64;
        let triangle_bytes = std::mem::size_of_val(&triangles[..]) as u64;
        for (part, bytes) in [("vertices", vertex_bytes), ("triangles", triangle_bytes)] {
            if bytes > limit {
                return Err(format!(
                    "the scene's merged {what} {part} take {bytes} bytes; this device binds at most {limit} bytes of storage"
                ));
            }
        }
        let ranges: Vec<u32> = material_ranges.iter().flatten().copied().collect();
        let storage = |label: &str, bytes: &[u8]| {
            storage_buffer(device, label, bytes, wgpu::BufferUsages::empty())
        };
        Ok(Self {
            vertices: storage("merged vertices", bytemuck::cast_slice(&vertices)),
            triangles: storage("merged triangles", bytemuck::cast_slice(&triangles)),
            material_triangles: storage("material triangles", bytemuck::cast_slice(&ranges)),
            triangle_count: (triangles.len() / 3) as u32,
            vertex_count: vertices.len() as u32,
            material_ranges,
        })
    }

    /// Bytes on the GPU.
    pub fn bytes(&self) -> u64 {
        self.vertices.size() + self.triangles.size() + self.material_triangles.size()
    }
}
