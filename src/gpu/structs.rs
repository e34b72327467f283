//! GPU struct layouts shared with WGSL (`shaders/common/types.wgsl`). A test checks
//! every offset and size against naga's layout of the WGSL struct.

use crate::scene::{Camera, Light, LightShape};
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

/// Per-frame uniforms every pass reads (`Frame` in `shaders/common/types.wgsl`): camera
/// matrices, frame size and light count.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuFrame {
    /// World to view space, column-major.
    pub view: [[f32; 4]; 4],
    /// View to clip space, column-major.
    pub proj: [[f32; 4]; 4],
    /// World to clip space (`proj * view`).
    pub view_proj: [[f32; 4]; 4],
    /// Clip to view space, for reconstructing positions from depth.
    pub inv_proj: [[f32; 4]; 4],
    /// The camera's world position; `w` is 1.
    pub camera_pos: [f32; 4],
    /// Ambient light added to every lit surface; `w` is unused.
    pub ambient: [f32; 4],
    /// The frame's width and height in pixels.
    pub size: [u32; 2],
    /// Lights the passes loop over: the scene upload's count, or the last light update's.
    pub light_count: u32,
    /// One past the highest index of a light that casts a shadow (0 without casters).
    /// Light lists hold their lights in ascending index, so a walk over a list's
    /// casters (shadow-ray jobs) stops there.
    pub caster_end: u32,
    /// The camera's near plane distance (world units).
    pub near: f32,
    /// The camera's far plane distance (world units).
    pub far: f32,
    /// Padding to WGSL's alignment; always 0.
    pub _pad1: [f32; 2],
}

impl GpuFrame {
    /// The uniforms for `camera` at `width`×`height` pixels with `light_count` lights,
    /// the casters among the first `caster_end` ([`caster_end`]).
    pub fn new(
        camera: &Camera,
        ambient: Vec3,
        width: u32,
        height: u32,
        light_count: u32,
        caster_end: u32,
    ) -> Self {
        let view = camera.view();
        let proj = camera.projection(width as f32 / height as f32);
        Self {
            view: view.to_cols_array_2d(),
            proj: proj.to_cols_array_2d(),
            view_proj: (proj * view).to_cols_array_2d(),
            inv_proj: proj.inverse().to_cols_array_2d(),
            camera_pos: camera.eye.extend(1.0).into(),
            ambient: ambient.extend(0.0).into(),
            size: [width, height],
            light_count,
            caster_end,
            near: camera.near,
            far: camera.far,
            _pad1: [0.0; 2],
        }
    }
    /// The view matrix as a glam matrix.
    pub fn view_matrix(&self) -> Mat4 {
        Mat4::from_cols_array_2d(&self.view)
    }
}

/// One past the highest index of a light in `lights` that casts a shadow; 0 without one.
pub fn caster_end(lights: &[Light]) -> u32 {
    lights
        .iter()
        .rposition(|l| l.flags & crate::scene::light_flags::CASTS_SHADOW != 0)
        .map_or(0, |i| i as u32 + 1)
}

/// What culling reads. Point lights have `cos_outer = -1`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuLightGeometry {
    /// World position.
    pub position: [f32; 3],
    /// Distance (world units) at which the light's falloff reaches zero.
    pub range: f32,
    /// Spot direction (unit vector); zero for point lights.
    pub direction: [f32; 3],
    /// Cosine of the spot cone's outer half-angle; -1 for point lights.
    pub cos_outer: f32,
}

/// What shading reads besides geometry; `color` is colour × intensity.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuLightProperties {
    /// Linear colour times intensity.
    pub color: [f32; 3],
    /// Cosine of the spot cone's inner half-angle, where the falloff to the outer cone
    /// starts; -1 for point lights.
    pub cos_inner: f32,
    /// The light's flag bits (`Light::flags`), passed through to the shaders.
    pub flags: u32,
    /// Which material type bits the light lights (`Light::material_mask`).
    pub material_mask: u32,
    /// Padding to WGSL's alignment; always 0.
    pub _pad: [u32; 2],
}

/// Bytes of one light in either light array (`light_geometry`, `light_properties`): the
/// one definition every buffer size and stride of a light array takes.
pub const LIGHT_BYTES: u64 = std::mem::size_of::<GpuLightGeometry>() as u64;
// Both arrays are indexed alike, so their elements must be the same size.
const _: () = assert!(std::mem::size_of::<GpuLightProperties>() as u64 == LIGHT_BYTES);

/// How a culling pass laid out its lists; see [`crate::graph::ListLayout`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuListParams {
    /// Tiles across the frame.
    pub tiles_x: u32,
    /// Tiles down the frame.
    pub tiles_y: u32,
    /// The tile side in pixels.
    pub tile: u32,
    /// Lists per tile: 1, 2 for HalfZ, or the slice count for Clustered.
    pub lists_per_tile: u32,
    /// Fixed lists' capacity; 0 for compact lists.
    pub capacity: u32,
    /// The culling variant's code ([`crate::graph::CullVariant::code`]).
    pub variant: u32,
    /// Word offset of the index pool in the list buffer (after the header and entries).
    pub pool_offset: u32,
    /// Light indices the pool holds (saturating at u32::MAX).
    pub pool_indices: u32,
}

impl GpuListParams {
    /// The parameters of a culling pass's list `layout`.
    pub fn new(layout: &crate::graph::ListLayout) -> Self {
        Self {
            tiles_x: layout.tiles_x,
            tiles_y: layout.tiles_y,
            tile: layout.tile,
            lists_per_tile: layout.lists_per_tile,
            capacity: match layout.storage {
                crate::graph::ListStorage::Fixed { capacity } => capacity,
                crate::graph::ListStorage::Compact { .. } => 0,
            },
            variant: layout.variant.code(),
            pool_offset: layout.pool_offset_words(),
            pool_indices: layout.pool_indices().min(u32::MAX as u64) as u32,
        }
    }

    /// A uniform buffer holding these parameters.
    pub fn buffer(&self, device: &wgpu::Device) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("list params"),
            contents: bytemuck::bytes_of(self),
            usage: wgpu::BufferUsages::UNIFORM,
        })
    }
}

/// How a LightLinkedList pass laid out its links; see
/// [`crate::graph::kinds::light_linked_list::LinkLayout`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuLinkParams {
    /// Resolution divisor of the head grid against the frame (`scale` of the pass).
    pub scale: u32,
    /// Head grid width in pixels.
    pub width: u32,
    /// Head grid height in pixels.
    pub height: u32,
    /// Word offset of the link pool in the buffer.
    pub pool_offset: u32,
    /// Links the pool holds.
    pub pool: u32,
    /// Padding to WGSL's alignment; always 0.
    pub _pad0: u32,
    /// Padding to WGSL's alignment; always 0.
    pub _pad1: u32,
    /// Padding to WGSL's alignment; always 0.
    pub _pad2: u32,
}

impl GpuLinkParams {
    /// `None` where the pool is past what a u32 link index addresses.
    pub fn new(layout: &crate::graph::kinds::light_linked_list::LinkLayout) -> Option<Self> {
        let words = layout.pool_offset_words()
            + crate::graph::kinds::light_linked_list::LinkLayout::LINK_WORDS * layout.pool;
        // Link indices and word offsets are u32 in the shaders; LINK_END is u32::MAX.
        if words >= u32::MAX as u64 {
            return None;
        }
        Some(Self {
            scale: layout.scale,
            width: layout.width,
            height: layout.height,
            pool_offset: layout.pool_offset_words() as u32,
            pool: layout.pool as u32,
            _pad0: 0,
            _pad1: 0,
            _pad2: 0,
        })
    }

    /// A uniform buffer holding these parameters.
    pub fn buffer(&self, device: &wgpu::Device) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("link params"),
            contents: bytemuck::bytes_of(self),
            usage: wgpu::BufferUsages::UNIFORM,
        })
    }
}

/// One light as culling and shading read it: the one conversion from [`Light`], which
/// every upload and update of the light buffers writes out. Spot directions are taken as
/// they are: unit length, as `LightShape::Spot` says (the buffers' writer normalises
/// them, src/render/scene_gpu.rs).
pub fn gpu_light(l: &Light) -> (GpuLightGeometry, GpuLightProperties) {
    let (direction, cos_outer, cos_inner) = match l.shape {
        LightShape::Point => (Vec3::ZERO, -1.0, -1.0),
        LightShape::Spot {
            direction,
            inner_angle,
            outer_angle,
        } => (
            direction,
            outer_angle.cos(),
            inner_angle.min(outer_angle).cos(),
        ),
    };
    (
        GpuLightGeometry {
            position: l.position.into(),
            range: l.range,
            direction: direction.into(),
            cos_outer,
        },
        GpuLightProperties {
            color: (l.color * l.intensity).into(),
            cos_inner,
            flags: l.flags,
            material_mask: l.material_mask,
            _pad: [0; 2],
        },
    )
}

/// Vertex layout of every mesh: position, normal, uv, tangent, colour, second uv.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuVertex {
    /// World-space position (scene meshes are stored transformed).
    pub position: [f32; 3],
    /// World-space normal.
    pub normal: [f32; 3],
    /// Texture coordinates (glTF TEXCOORD_0).
    pub uv: [f32; 2],
    /// World-space tangent; `w` is the bitangent sign (glTF TANGENT).
    pub tangent: [f32; 4],
    /// Linear RGBA vertex colour (glTF COLOR_0; white where the mesh has none).
    pub color: [f32; 4],
    /// The second texture coordinates (glTF TEXCOORD_1; zero where the mesh has none).
    pub uv1: [f32; 2],
}

impl GpuVertex {
    pub(crate) const ATTRIBUTES: [wgpu::VertexAttribute; 6] = wgpu::vertex_attr_array![
        0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x4, 4 => Float32x4,
        5 => Float32x2
    ];
    /// The vertex buffer layout render pipelines draw meshes with (locations 0..=5).
    pub fn layout() -> wgpu::VertexBufferLayout<'static> {
        wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<GpuVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &Self::ATTRIBUTES,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::caster_end;
    use crate::scene::{light_flags, Light};
    use glam::Vec3;

    #[test]
    fn caster_end_is_one_past_the_last_casting_light() {
        let plain = Light::point(Vec3::ZERO, 1.0, Vec3::ONE, 1.0);
        let casting = Light {
            flags: light_flags::CASTS_SHADOW,
            ..plain
        };
        assert_eq!(caster_end(&[]), 0);
        assert_eq!(caster_end(&[plain, plain]), 0);
        assert_eq!(caster_end(&[casting, plain, plain]), 1);
        assert_eq!(caster_end(&[plain, casting, plain, casting, plain]), 4);
    }
}
