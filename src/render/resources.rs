//! Physical textures and buffers for one plan.

use crate::graph::plan::{PhysicalDesc, ResourcePlan};

pub enum Physical {
    Texture {
        texture: wgpu::Texture,
        view: wgpu::TextureView,
    },
    Buffer(wgpu::Buffer),
}

pub struct FrameResources {
    pub physical: Vec<Physical>,
}

impl FrameResources {
    pub fn create(device: &wgpu::Device, plan: &ResourcePlan) -> Self {
        let physical = plan
            .physical
            .iter()
            .enumerate()
            .map(|(i, p)| match &p.desc {
                PhysicalDesc::Texture {
                    format,
                    width,
                    height,
                    samples,
                } => {
                    let texture = device.create_texture(&wgpu::TextureDescriptor {
                        label: Some(&format!("physical #{i} ({})", p.serves.join(", "))),
                        size: wgpu::Extent3d {
                            width: *width,
                            height: *height,
                            depth_or_array_layers: 1,
                        },
                        mip_level_count: 1,
                        sample_count: *samples,
                        dimension: wgpu::TextureDimension::D2,
                        format: format.to_wgpu(),
                        usage: p.texture_usage,
                        view_formats: &[],
                    });
                    let view = texture.create_view(&Default::default());
                    Physical::Texture { texture, view }
                }
                PhysicalDesc::Buffer { bytes } => {
                    Physical::Buffer(device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some(&format!("physical #{i} ({})", p.serves.join(", "))),
                        size: *bytes,
                        usage: p.buffer_usage,
                        mapped_at_creation: false,
                    }))
                }
            })
            .collect();
        Self { physical }
    }

    pub fn view(&self, plan: &ResourcePlan, name: &str) -> Option<&wgpu::TextureView> {
        match &self.physical[plan.get(name)?.physical] {
            Physical::Texture { view, .. } => Some(view),
            Physical::Buffer(_) => None,
        }
    }
    pub fn texture(&self, plan: &ResourcePlan, name: &str) -> Option<&wgpu::Texture> {
        match &self.physical[plan.get(name)?.physical] {
            Physical::Texture { texture, .. } => Some(texture),
            Physical::Buffer(_) => None,
        }
    }
    pub fn buffer(&self, plan: &ResourcePlan, name: &str) -> Option<&wgpu::Buffer> {
        match &self.physical[plan.get(name)?.physical] {
            Physical::Buffer(b) => Some(b),
            Physical::Texture { .. } => None,
        }
    }
}
