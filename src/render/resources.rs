//! Physical textures and buffers for one plan. A frame that replaces another (hot reload)
//! takes the old frame's resources whose descriptor and usage did not change instead of
//! creating them again.

use crate::graph::plan::{PhysicalDesc, PhysicalResource, ResourcePlan};

#[derive(Clone)]
pub enum Physical {
    Texture {
        texture: wgpu::Texture,
        view: wgpu::TextureView,
    },
    Buffer(wgpu::Buffer),
}

/// The physical textures and buffers of a prepared frame, one per entry of the plan's
/// `physical`, possibly taken over from the frame it replaces.
pub struct FrameResources {
    /// The allocated textures and buffers, indexed like `ResourcePlan::physical`.
    pub physical: Vec<Physical>,
    /// What each physical resource was created as (to match it against a later plan).
    descs: Vec<PhysicalResource>,
    /// How many of `physical` were taken from the previous frame rather than created.
    reused: usize,
}

/// Whether a resource created as `old` can serve as `new`.
fn same_descriptor(old: &PhysicalResource, new: &PhysicalResource) -> bool {
    old.desc == new.desc
        && old.texture_usage == new.texture_usage
        && old.buffer_usage == new.buffer_usage
}

type Fits = fn(&PhysicalResource, &PhysicalResource) -> bool;

/// For each physical resource of the plan, the index in `pool` to reuse, if any. One that
/// served the same graph resources is preferred, then any with the same descriptor; each
/// pooled resource is given out once.
fn match_pool(plan: &[PhysicalResource], pool: &[PhysicalResource]) -> Vec<Option<usize>> {
    let mut taken = vec![false; pool.len()];
    let mut out = vec![None; plan.len()];
    let same_role = |old: &PhysicalResource, new: &PhysicalResource| {
        same_descriptor(old, new) && old.serves == new.serves
    };
    for fits in [same_role as Fits, same_descriptor] {
        for (i, new) in plan.iter().enumerate() {
            if out[i].is_some() {
                continue;
            }
            if let Some(j) = (0..pool.len()).find(|&j| !taken[j] && fits(&pool[j], new)) {
                taken[j] = true;
                out[i] = Some(j);
            }
        }
    }
    out
}

impl FrameResources {
    /// Creates every resource of `plan`.
    pub fn create(device: &wgpu::Device, plan: &ResourcePlan) -> Self {
        Self::create_reusing(device, plan, None)
    }

    /// Like [`create`](Self::create), taking what fits from `pool` (the resources of a
    /// frame this one replaces; both may be alive at once, the handles are shared).
    pub(crate) fn create_reusing(
        device: &wgpu::Device,
        plan: &ResourcePlan,
        pool: Option<&FrameResources>,
    ) -> Self {
        let matches = match pool {
            Some(pool) => match_pool(&plan.physical, &pool.descs),
            None => vec![None; plan.physical.len()],
        };
        let physical: Vec<Physical> = plan
            .physical
            .iter()
            .zip(&matches)
            .map(|(p, m)| match (m, pool) {
                (Some(j), Some(pool)) => pool.physical[*j].clone(),
                _ => create_one(device, p),
            })
            .collect();
        Self {
            physical,
            descs: plan.physical.clone(),
            reused: matches.iter().filter(|m| m.is_some()).count(),
        }
    }

    /// Resources taken from the previous frame.
    pub fn reused(&self) -> usize {
        self.reused
    }

    /// Resources created for this frame.
    pub fn created(&self) -> usize {
        self.physical.len() - self.reused
    }

    /// The view of graph texture `name` (`None` for buffers or unknown names).
    pub fn view(&self, plan: &ResourcePlan, name: &str) -> Option<&wgpu::TextureView> {
        match &self.physical[plan.get(name)?.physical] {
            Physical::Texture { view, .. } => Some(view),
            Physical::Buffer(_) => None,
        }
    }
    /// The texture behind graph resource `name` (`None` for buffers or unknown names).
    pub fn texture(&self, plan: &ResourcePlan, name: &str) -> Option<&wgpu::Texture> {
        match &self.physical[plan.get(name)?.physical] {
            Physical::Texture { texture, .. } => Some(texture),
            Physical::Buffer(_) => None,
        }
    }
    /// The buffer behind graph resource `name` (`None` for textures or unknown names).
    pub fn buffer(&self, plan: &ResourcePlan, name: &str) -> Option<&wgpu::Buffer> {
        match &self.physical[plan.get(name)?.physical] {
            Physical::Buffer(b) => Some(b),
            Physical::Texture { .. } => None,
        }
    }
}

fn create_one(device: &wgpu::Device, p: &PhysicalResource) -> Physical {
    // wgpu's messages quote the label: name what the graph file names.
    let label = format!("graph resource '{}'", p.serves.join("', '"));
    match &p.desc {
        PhysicalDesc::Texture {
            format,
            width,
            height,
            samples,
        } => {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some(&label),
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
                label: Some(&label),
                size: *bytes,
                usage: p.buffer_usage,
                mapped_at_creation: false,
            }))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::TextureFormat;

    fn texture(w: u32, serves: &str) -> PhysicalResource {
        PhysicalResource {
            desc: PhysicalDesc::Texture {
                format: TextureFormat::Rgba32Float,
                width: w,
                height: 64,
                samples: 1,
            },
            texture_usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            buffer_usage: wgpu::BufferUsages::empty(),
            serves: vec![crate::graph::Name::from(serves)],
            last_use: 0,
        }
    }

    #[test]
    fn pool_prefers_the_same_role_then_any_same_descriptor() {
        let pool = [texture(96, "a"), texture(96, "b"), texture(128, "c")];
        // "b" gets its own; "x" takes the remaining 96-wide one; 200-wide is new; the
        // 128-wide one is given out once only.
        let plan = [
            texture(96, "x"),
            texture(96, "b"),
            texture(200, "c"),
            texture(128, "y"),
            texture(128, "z"),
        ];
        assert_eq!(
            match_pool(&plan, &pool),
            vec![Some(0), Some(1), None, Some(2), None]
        );
    }

    #[test]
    fn usage_is_part_of_the_descriptor() {
        let mut other = texture(96, "a");
        other.texture_usage |= wgpu::TextureUsages::STORAGE_BINDING;
        assert_eq!(match_pool(&[other], &[texture(96, "a")]), vec![None]);
    }
}
