//! Bind groups by reflected WGSL binding name, for every pass: a pass offers named
//! resources (its declared slots, the frame uniform, buffers it owns), the shader's
//! reflected bindings pick from them, and the layout comes from the same reflection.
//! No binding number is typed anywhere in Rust.

use crate::shader::{BindingKind, ReflectedBinding};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// A resource a pass offers its shader under a name.
#[derive(Clone)]
pub(super) enum Bound {
    Buffer(wgpu::Buffer),
    View(wgpu::TextureView),
    Sampler(wgpu::Sampler),
}

/// The named resources a pass may bind. Binding names the shader declares but the set
/// lacks are an error naming the pass and binding; offered names the shader does not
/// use are left unbound.
#[derive(Clone, Default)]
pub(super) struct BindingSet {
    named: Vec<(String, Bound)>,
}

impl BindingSet {
    pub fn offer(&mut self, name: &str, resource: Bound) {
        self.named.retain(|(n, _)| n != name);
        self.named.push((name.to_string(), resource));
    }
    pub fn buffer(&mut self, name: &str, buffer: &wgpu::Buffer) {
        self.offer(name, Bound::Buffer(buffer.clone()));
    }
    /// The size in bytes of the buffer offered under `name`.
    pub fn buffer_size(&self, name: &str) -> Option<u64> {
        match self.get(name) {
            Some(Bound::Buffer(b)) => Some(b.size()),
            _ => None,
        }
    }
    /// Whether something is offered under `name`.
    pub fn has(&self, name: &str) -> bool {
        self.get(name).is_some()
    }
    fn get(&self, name: &str) -> Option<&Bound> {
        self.named.iter().find(|(n, _)| n == name).map(|(_, b)| b)
    }

    /// A bind group for `group` of `bindings` on `layout`.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        label: &str,
        layout: &wgpu::BindGroupLayout,
        bindings: &[ReflectedBinding],
        group: u32,
    ) -> Result<wgpu::BindGroup, String> {
        let mut entries = Vec::new();
        for b in bindings.iter().filter(|b| b.group == group) {
            let resource = match self.get(&b.name) {
                Some(Bound::Buffer(buf)) => buf.as_entire_binding(),
                Some(Bound::View(view)) => wgpu::BindingResource::TextureView(view),
                Some(Bound::Sampler(s)) => wgpu::BindingResource::Sampler(s),
                None => {
                    return Err(format!(
                        "the shader binds '{}' (group {group}, binding {}), which the pass does not declare",
                        b.name, b.binding
                    ))
                }
            };
            entries.push(wgpu::BindGroupEntry {
                binding: b.binding,
                resource,
            });
        }
        Ok(device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout,
            entries: &entries,
        }))
    }
}

/// Layout entries of `group` from reflection. Float textures are bound unfilterable
/// (Rgba32Float is not filterable without a feature; built-in shaders only load them).
pub(super) fn layout_entries(
    bindings: &[ReflectedBinding],
    group: u32,
    visibility: wgpu::ShaderStages,
) -> Vec<wgpu::BindGroupLayoutEntry> {
    layout_entries_filtering(bindings, group, visibility, false)
}

/// Like [`layout_entries`]; `filtering` binds float textures filterable and samplers
/// filtering (material textures, sampled with a linear sampler).
pub(super) fn layout_entries_filtering(
    bindings: &[ReflectedBinding],
    group: u32,
    visibility: wgpu::ShaderStages,
    filtering: bool,
) -> Vec<wgpu::BindGroupLayoutEntry> {
    use wgpu::{BindingType as T, TextureViewDimension as D};
    bindings
        .iter()
        .filter(|b| b.group == group)
        .map(|b| {
            let ty = match &b.kind {
                BindingKind::Uniform => T::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                BindingKind::Storage { writable } => T::Buffer {
                    ty: wgpu::BufferBindingType::Storage {
                        read_only: !writable,
                    },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                BindingKind::SampledTexture { multisampled, kind } => T::Texture {
                    sample_type: match kind {
                        naga::ScalarKind::Uint => wgpu::TextureSampleType::Uint,
                        naga::ScalarKind::Sint => wgpu::TextureSampleType::Sint,
                        _ => wgpu::TextureSampleType::Float {
                            filterable: filtering,
                        },
                    },
                    view_dimension: D::D2,
                    multisampled: *multisampled,
                },
                BindingKind::DepthTexture { multisampled } => T::Texture {
                    sample_type: wgpu::TextureSampleType::Depth,
                    view_dimension: D::D2,
                    multisampled: *multisampled,
                },
                BindingKind::StorageTexture {
                    format,
                    writable,
                    readable,
                } => T::StorageTexture {
                    access: match (*writable, *readable) {
                        (true, true) => wgpu::StorageTextureAccess::ReadWrite,
                        (true, false) => wgpu::StorageTextureAccess::WriteOnly,
                        (false, _) => wgpu::StorageTextureAccess::ReadOnly,
                    },
                    format: storage_format(*format),
                    view_dimension: D::D2,
                },
                BindingKind::Sampler { comparison } => T::Sampler(if *comparison {
                    wgpu::SamplerBindingType::Comparison
                } else if filtering {
                    wgpu::SamplerBindingType::Filtering
                } else {
                    wgpu::SamplerBindingType::NonFiltering
                }),
            };
            wgpu::BindGroupLayoutEntry {
                binding: b.binding,
                visibility,
                ty,
                count: None,
            }
        })
        .collect()
}

fn storage_format(f: naga::StorageFormat) -> wgpu::TextureFormat {
    use naga::StorageFormat as S;
    use wgpu::TextureFormat as W;
    match f {
        S::Rgba8Unorm => W::Rgba8Unorm,
        S::Rgba16Float => W::Rgba16Float,
        S::R32Float => W::R32Float,
        S::Rg32Float => W::Rg32Float,
        S::R32Uint => W::R32Uint,
        _ => W::Rgba32Float,
    }
}

/// Bind-group layouts by their entries: every pipeline made from the same reflected
/// bindings gets the same layout object, so one bind group serves them all.
#[derive(Default)]
pub struct LayoutCache {
    layouts: Mutex<HashMap<Vec<wgpu::BindGroupLayoutEntry>, Arc<wgpu::BindGroupLayout>>>,
}

impl LayoutCache {
    pub fn get(
        &self,
        device: &wgpu::Device,
        entries: Vec<wgpu::BindGroupLayoutEntry>,
    ) -> Arc<wgpu::BindGroupLayout> {
        let mut layouts = self.layouts.lock().unwrap_or_else(|e| e.into_inner());
        layouts
            .entry(entries)
            .or_insert_with_key(|entries| {
                Arc::new(
                    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                        label: None,
                        entries,
                    }),
                )
            })
            .clone()
    }
}
