//! A scene uploaded to the GPU: one vertex and index buffer per mesh, the two light
//! arrays, and one material program per scene material.

use super::materials::MaterialProgram;
use super::visibility_geometry::VisibilityGeometry;
use crate::gpu::structs::{gpu_light, GpuVertex};
use crate::scene::{AlphaMode, Light, Scene};
use wgpu::util::DeviceExt;

/// Bytes of one light in either light buffer.
const LIGHT_BYTES: usize = crate::gpu::structs::LIGHT_BYTES as usize;

/// One uploaded mesh: its vertex and index buffers, material and shadow-culling data.
#[derive(Clone)]
pub struct GpuMesh {
    /// Vertices ([`crate::gpu::structs::GpuVertex`]), world space.
    pub vertices: wgpu::Buffer,
    /// Triangle indices (u32) in the scene's order.
    pub indices: wgpu::Buffer,
    /// Indices to draw (three per triangle).
    pub index_count: u32,
    /// Index into [`SceneGpu::materials`].
    pub material: usize,
    /// World-space bounds (min, max) of the vertices: for culling per shadow view.
    pub bounds: [glam::Vec3; 2],
    /// The triangles reordered into spatial chunks (`shadow::chunks`), drawn by shadow
    /// views, which cull chunk by chunk.
    pub shadow_indices: wgpu::Buffer,
    /// The spatial chunks of `shadow_indices`, with their bounds.
    pub chunks: std::sync::Arc<[crate::shadow::chunks::Chunk]>,
    /// This mesh's index in `Scene::meshes` (empty meshes are not uploaded).
    pub scene_mesh: usize,
    /// The visibility id of its first triangle (see `visibility_geometry`); 0 for
    /// blended meshes, which no visibility buffer holds.
    pub first_triangle: u32,
    /// A blended mesh that still casts shadows (`Mesh::blended_casts_shadow`).
    pub blended_casts_shadow: bool,
}

/// Cheap to clone (the GPU objects are shared handles): hot reload builds a changed copy
/// beside the live one.
#[derive(Clone)]
pub struct SceneGpu {
    /// The uploaded meshes, in scene order.
    pub meshes: Vec<GpuMesh>,
    /// One compiled material per scene material, indexed by `GpuMesh::material`.
    pub materials: Vec<MaterialProgram>,
    /// The `light_geometry` storage buffer ([`crate::gpu::structs::GpuLightGeometry`] per
    /// light).
    pub light_geometry: wgpu::Buffer,
    /// The `light_properties` storage buffer ([`crate::gpu::structs::GpuLightProperties`]
    /// per light).
    pub light_properties: wgpu::Buffer,
    /// Lights the two light buffers hold room for (at least the scene's): the most a
    /// light update may write. The count passes read is the prepared frame's
    /// (`PreparedFrame::light_count`).
    pub light_capacity: u32,
    /// The shadow BVH, built the first time a pass binds it (see [`SceneGpu::bvh`]);
    /// shared by clones of this upload.
    bvh: std::sync::Arc<std::sync::OnceLock<Result<GpuBvh, String>>>,
    /// The opaque meshes merged for vertex fetching, built the first time a pass binds
    /// them (see [`SceneGpu::visibility_geometry`]).
    visibility: std::sync::Arc<std::sync::OnceLock<Result<VisibilityGeometry, String>>>,
    /// The blended meshes merged the same way, built the first time a pass rasterizes
    /// them in compute (see [`SceneGpu::transparent_geometry`]).
    transparent: std::sync::Arc<std::sync::OnceLock<Result<VisibilityGeometry, String>>>,
}

/// The shadow BVH's two storage buffers and what building it found.
#[derive(Clone)]
pub struct GpuBvh {
    /// The BVH nodes (`bvh_nodes` binding).
    pub nodes: wgpu::Buffer,
    /// The triangles in leaf order (`bvh_triangles` binding).
    pub triangles: wgpu::Buffer,
    /// What alpha-tested rays read (`bvh_alpha` binding); None when no caster is
    /// alpha-masked.
    pub alpha: Option<wgpu::Buffer>,
    /// Triangles of alpha-masked casters that rays alpha-test.
    pub alpha_triangles: u32,
    /// What the build found: triangles kept and skipped, and the tree's shape.
    pub stats: crate::shadow::BuildStats,
}

impl GpuBvh {
    /// Builds the BVH over every shadow-casting triangle of `scene` (or an empty one when
    /// `full` is false) and uploads it.
    pub fn build(
        device: &wgpu::Device,
        scene: &Scene,
        full: bool,
    ) -> Result<Self, crate::shadow::ShadowError> {
        let bvh = if full {
            let options = crate::shadow::BuildOptions {
                quality: scene.shadow_bvh,
                max_alpha_bytes: device.limits().max_storage_buffer_binding_size,
                ..Default::default()
            };
            crate::shadow::ShadowBvh::build_with(scene, &options)?
        } else {
            crate::shadow::ShadowBvh::from_triangles(&[], &Default::default())?
        };
        let (nodes, triangles) = bvh.gpu_bytes();
        let upload = |label: &str, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        for unsupported in &bvh.alpha.unsupported {
            log::warn!(
                "shadow rays do not alpha-test {unsupported}; cut-out parts block rays as opaque ones"
            );
        }
        Ok(Self {
            nodes: upload("bvh_nodes", nodes),
            triangles: upload("bvh_triangles", triangles),
            alpha: bvh.alpha_bytes().map(|b| upload("bvh_alpha", b)),
            alpha_triangles: bvh.alpha.records(),
            stats: bvh.stats,
        })
    }

    /// Bytes on the GPU (nodes, triangles and alpha data).
    pub fn bytes(&self) -> u64 {
        self.nodes.size() + self.triangles.size() + self.alpha.as_ref().map_or(0, |a| a.size())
    }
}

impl SceneGpu {
    /// Uploads geometry, lights and the scene's materials (generated WGSL, textures).
    pub fn upload(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
    ) -> Result<Self, crate::material::MaterialError> {
        Self::upload_with_light_capacity(device, queue, scene, 0)
    }

    /// Like [`upload`](Self::upload) with light buffers holding room for `capacity` lights
    /// (or the scene's, if more), so that [`write_lights`](Self::write_lights) may later
    /// write up to that many. Compile the graph with `FrameSize::lights` = the capacity.
    pub fn upload_with_light_capacity(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        capacity: u32,
    ) -> Result<Self, crate::material::MaterialError> {
        let materials = MaterialProgram::for_scene(device, queue, scene)?;
        Ok(Self::upload_with_capacity(
            device, scene, materials, capacity,
        ))
    }

    /// Writes `lights` over the light buffers: one queue write per buffer, no allocation.
    /// The frames that render them need their count and light-dependent state updated too:
    /// call `PreparedFrame::update_lights`, which calls this.
    pub fn write_lights(
        &self,
        queue: &wgpu::Queue,
        lights: &[Light],
    ) -> Result<(), super::LightUpdateError> {
        if lights.len() > self.light_capacity as usize {
            return Err(super::LightUpdateError::OverCapacity {
                count: lights.len(),
                capacity: self.light_capacity,
            });
        }
        for (index, l) in lights.iter().enumerate() {
            crate::scene::lights::check_light(l)
                .map_err(|problem| super::LightUpdateError::BadLight { index, problem })?;
        }
        let Some(bytes) = std::num::NonZeroU64::new(lights.len() as u64 * LIGHT_BYTES as u64)
        else {
            return Ok(());
        };
        if let (Some(mut g), Some(mut p)) = (
            queue.write_buffer_with(&self.light_geometry, 0, bytes),
            queue.write_buffer_with(&self.light_properties, 0, bytes),
        ) {
            // The caller's lights are checked (above); write_light_bytes normalises them
            // as it does at upload.
            write_light_bytes(lights.iter().copied(), g.slice(..), p.slice(..));
        }
        Ok(())
    }

    /// The scene's BVH buffers, or why there are none: built on first use, so graphs
    /// that import no BVH (or scenes without casters, which get an empty one) never pay
    /// for it. `scene` must be the scene this was uploaded from.
    pub fn bvh(&self, device: &wgpu::Device, scene: &Scene) -> Result<&GpuBvh, String> {
        self.bvh
            .get_or_init(|| {
                // VPL visibility (VplVisibility) traces against it too.
                let f = scene.features();
                GpuBvh::build(device, scene, f.has_shadow_casters || f.has_indirect_lights)
                    .map_err(|e| format!("the scene's shadow BVH could not be built: {e}"))
            })
            .as_ref()
            .map_err(Clone::clone)
    }

    /// The opaque meshes merged into storage buffers, or why they cannot be: built on
    /// first use. `scene` must be the scene this was uploaded from.
    pub fn visibility_geometry(
        &self,
        device: &wgpu::Device,
        scene: &Scene,
    ) -> Result<&VisibilityGeometry, String> {
        self.visibility
            .get_or_init(|| VisibilityGeometry::build(device, self, scene))
            .as_ref()
            .map_err(Clone::clone)
    }

    /// The blended meshes merged into storage buffers (their own triangle ids), or why
    /// they cannot be: built on first use. `scene` must be the scene this was uploaded
    /// from.
    pub fn transparent_geometry(
        &self,
        device: &wgpu::Device,
        scene: &Scene,
    ) -> Result<&VisibilityGeometry, String> {
        self.transparent
            .get_or_init(|| VisibilityGeometry::build_transparent(device, self, scene))
            .as_ref()
            .map_err(Clone::clone)
    }

    /// The merged geometry, if a pass has built it.
    pub fn built_visibility_geometry(&self) -> Option<&VisibilityGeometry> {
        self.visibility.get().and_then(|b| b.as_ref().ok())
    }

    /// The BVH, if a pass has built it.
    pub fn built_bvh(&self) -> Option<&GpuBvh> {
        self.bvh.get().and_then(|b| b.as_ref().ok())
    }

    /// Uploads geometry and lights with materials already compiled (hot reload reuses the
    /// live ones).
    pub fn upload_with(
        device: &wgpu::Device,
        scene: &Scene,
        materials: Vec<MaterialProgram>,
    ) -> Self {
        Self::upload_with_capacity(device, scene, materials, 0)
    }

    /// [`upload_with`](Self::upload_with) with room for `capacity` lights (at least the
    /// scene's).
    pub fn upload_with_capacity(
        device: &wgpu::Device,
        scene: &Scene,
        materials: Vec<MaterialProgram>,
        capacity: u32,
    ) -> Self {
        let meshes: Vec<GpuMesh> = scene
            .meshes
            .iter()
            .enumerate()
            .filter(|(_, m)| !m.indices.is_empty())
            .map(|(scene_mesh, m)| upload_mesh(device, m, scene_mesh, materials.len()))
            .collect();
        let light_capacity = capacity.max(scene.lights.len() as u32);
        // Room for the lights an update may add: zeroed entries past the count are never
        // read (every pass loops to the frame's light count). Written by light updates,
        // read back by whoever checks what they hold.
        let [light_geometry, light_properties] = light_storage(
            device,
            ["light geometry", "light properties"],
            &scene.lights,
            light_capacity,
            wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );
        let mut gpu = Self {
            meshes,
            materials,
            light_geometry,
            light_properties,
            light_capacity,
            // A new upload (hot reload of geometry) builds its own when first bound.
            bvh: Default::default(),
            visibility: Default::default(),
            transparent: Default::default(),
        };
        gpu.number_triangles();
        gpu
    }

    /// Visibility ids: opaque triangles numbered in draw order.
    fn number_triangles(&mut self) {
        for m in &mut self.meshes {
            m.first_triangle = 0;
        }
        let mut next = 0u32;
        for mesh in self.opaque_draws() {
            let m = &mut self.meshes[mesh];
            m.first_triangle = next;
            next = next.saturating_add(m.index_count / 3);
        }
    }

    /// Uploads `scene.meshes[index]`, a mesh just added to the scene this was uploaded
    /// from (meshes after it in the scene shift up by one): its buffers alone are
    /// created; the visibility ids are numbered again and the shadow BVH and the merged
    /// visibility geometry are dropped, to be built for the new geometry when a pass
    /// next binds them. Prepared frames need their passes bound again:
    /// [`Renderer::add_mesh`](super::Renderer::add_mesh) does both.
    pub fn add_mesh(&mut self, device: &wgpu::Device, scene: &Scene, index: usize) {
        for m in &mut self.meshes {
            if m.scene_mesh >= index {
                m.scene_mesh += 1;
            }
        }
        let mesh = &scene.meshes[index];
        if !mesh.indices.is_empty() {
            let at = self.meshes.partition_point(|m| m.scene_mesh < index);
            let uploaded = upload_mesh(device, mesh, index, self.materials.len());
            self.meshes.insert(at, uploaded);
        }
        self.geometry_changed();
    }

    /// Forgets the upload of scene mesh `index`, about to be removed from the scene
    /// (meshes after it shift down by one); as [`add_mesh`](Self::add_mesh), the ids, the
    /// BVH and the merged geometry follow.
    pub fn remove_mesh(&mut self, index: usize) {
        self.meshes.retain(|m| m.scene_mesh != index);
        for m in &mut self.meshes {
            if m.scene_mesh > index {
                m.scene_mesh -= 1;
            }
        }
        self.geometry_changed();
    }

    /// Replaces material `index` (a hot-reloaded material). Where it alpha-tests, before
    /// or now, the BVH is dropped, so the next pass that binds it builds it again with the
    /// material's alpha (rays read it, `bvh_alpha`); clones of this upload keep theirs.
    pub fn set_material(&mut self, index: usize, program: MaterialProgram) {
        let masked = |m: &MaterialProgram| m.alpha_mode.is_masked();
        let was_masked = self.materials.get(index).is_some_and(masked);
        if was_masked || masked(&program) {
            self.bvh = Default::default();
        }
        if let Some(m) = self.materials.get_mut(index) {
            *m = program;
        }
    }

    /// The meshes changed: number the ids again and drop what was built from the old
    /// geometry (clones of this upload keep theirs).
    fn geometry_changed(&mut self) {
        self.number_triangles();
        self.bvh = Default::default();
        self.visibility = Default::default();
        self.transparent = Default::default();
    }

    /// Mesh indices to draw for opaque and alpha-masked geometry, sorted by material so
    /// pipeline changes are as few as possible.
    pub fn opaque_draws(&self) -> Vec<usize> {
        let mut draws: Vec<usize> = (0..self.meshes.len())
            .filter(|&i| self.materials[self.meshes[i].material].alpha_mode != AlphaMode::Blend)
            .collect();
        draws.sort_by_key(|&i| self.meshes[i].material);
        draws
    }

    /// Mesh indices that cast shadows into shadow maps: the opaque draws, then the
    /// blended meshes that opt in (`Scene::casts_shadow`, the BVH's rule).
    pub fn shadow_caster_draws(&self) -> Vec<usize> {
        let mut draws = self.opaque_draws();
        draws.extend(
            self.transparent_draws()
                .into_iter()
                .filter(|&i| self.meshes[i].blended_casts_shadow),
        );
        draws
    }

    /// Mesh indices of blended (glTF `alphaMode: BLEND`) geometry, in scene order: the
    /// transparency passes draw these, sorted per frame by view depth.
    pub(crate) fn transparent_draws(&self) -> Vec<usize> {
        (0..self.meshes.len())
            .filter(|&i| self.materials[self.meshes[i].material].alpha_mode == AlphaMode::Blend)
            .collect()
    }

    /// Positive view-space depth of a mesh's bounds centre: the key transparent meshes are
    /// sorted by, back to front.
    pub fn view_depth(&self, mesh: usize, view: &glam::Mat4) -> f32 {
        let [lo, hi] = self.meshes[mesh].bounds;
        -view.transform_point3((lo + hi) * 0.5).z
    }
}

/// One mesh's vertex, index and chunked shadow index buffers.
fn upload_mesh(
    device: &wgpu::Device,
    m: &crate::scene::Mesh,
    scene_mesh: usize,
    materials: usize,
) -> GpuMesh {
    let (shadow_indices, chunks) = crate::shadow::chunks::chunk_triangles(&m.positions, &m.indices);
    let vertices = gpu_vertices(m);
    GpuMesh {
        vertices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(&m.name),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        }),
        indices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(&m.name),
            contents: bytemuck::cast_slice(&m.indices),
            usage: wgpu::BufferUsages::INDEX,
        }),
        index_count: m.indices.len() as u32,
        material: m.material.min(materials - 1),
        bounds: m.positions.iter().fold(
            [glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY],
            |[lo, hi], &p| [lo.min(p), hi.max(p)],
        ),
        shadow_indices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(&m.name),
            // Never empty: a mesh of only bad triangles binds one unused entry.
            contents: bytemuck::cast_slice(if shadow_indices.is_empty() {
                &[0u32; 3][..]
            } else {
                &shadow_indices[..]
            }),
            usage: wgpu::BufferUsages::INDEX,
        }),
        chunks: chunks.into(),
        scene_mesh,
        first_triangle: 0,
        blended_casts_shadow: m.blended_casts_shadow,
    }
}

/// A mesh's vertices as the GPU reads them (missing normals point up, missing uvs and
/// tangents are zero, missing colours white).
pub(super) fn gpu_vertices(m: &crate::scene::Mesh) -> Vec<GpuVertex> {
    (0..m.positions.len())
        .map(|i| GpuVertex {
            position: m.positions[i].into(),
            normal: m.normals.get(i).copied().unwrap_or(glam::Vec3::Y).into(),
            uv: m.uvs.get(i).copied().unwrap_or_default().into(),
            tangent: m.tangents.get(i).copied().unwrap_or_default().into(),
            color: m.colors.get(i).copied().unwrap_or(glam::Vec4::ONE).into(),
            uv1: m.uvs1.get(i).copied().unwrap_or_default().into(),
        })
        .collect()
}

/// The two light storage buffers (geometry, properties) with room for `capacity` lights
/// (one when 0: storage bindings may not be empty), holding `lights` and zeros after.
pub(super) fn light_storage(
    device: &wgpu::Device,
    labels: [&str; 2],
    lights: &[Light],
    capacity: u32,
    extra: wgpu::BufferUsages,
) -> [wgpu::Buffer; 2] {
    let size = capacity.max(lights.len() as u32).max(1) as u64 * LIGHT_BYTES as u64;
    let [g, p] = labels.map(|label| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::STORAGE | extra,
            // Mapped memory starts zeroed.
            mapped_at_creation: true,
        })
    });
    {
        // Mapped whole at creation: mapping the whole range again cannot fail.
        let mapped = |b: &wgpu::Buffer| b.get_mapped_range_mut(..).expect("mapped at creation");
        let (mut gv, mut pv) = (mapped(&g), mapped(&p));
        write_light_bytes(lights.iter().copied(), gv.slice(..), pv.slice(..));
    }
    g.unmap();
    p.unmap();
    [g, p]
}

/// The one place lights are written out as the bytes culling and shading read: each
/// light's [`gpu_light`] (32 bytes into each array), in order from the start, its spot
/// direction normalised here, so an upload and an update of the same lights write the
/// same bytes (normalising a unit vector again can move its last bit).
fn write_light_bytes(
    lights: impl Iterator<Item = Light>,
    geometry: wgpu::WriteOnly<[u8]>,
    properties: wgpu::WriteOnly<[u8]>,
) {
    let (geometry, _) = geometry.into_chunks::<LIGHT_BYTES>();
    let (properties, _) = properties.into_chunks::<LIGHT_BYTES>();
    for ((mut l, g), p) in lights.zip(geometry).zip(properties) {
        if let crate::scene::LightShape::Spot { direction, .. } = &mut l.shape {
            *direction = direction.normalize();
        }
        let (lg, lp) = gpu_light(&l);
        g.write(bytemuck::cast(lg));
        p.write(bytemuck::cast(lp));
    }
}

/// A storage buffer holding `bytes`, padded to 32 bytes when empty: storage bindings may
/// not be empty.
pub(super) fn storage_buffer(
    device: &wgpu::Device,
    label: &str,
    bytes: &[u8],
    extra: wgpu::BufferUsages,
) -> wgpu::Buffer {
    let padded;
    let contents = if bytes.is_empty() {
        padded = vec![0u8; 32];
        &padded[..]
    } else {
        bytes
    };
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents,
        usage: wgpu::BufferUsages::STORAGE | extra,
    })
}
