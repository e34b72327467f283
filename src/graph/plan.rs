//! Step 5: resource lifetimes and reuse. wgpu has no placed resources, so aliasing means
//! one physical texture or buffer serving several graph resources with the same
//! descriptor whose lifetimes (first to last use in the schedule) do not overlap.

use super::deps::PassIds;
use super::kinds::light_culling::ListLayout;
use super::kinds::{self, BufferLayout, Usage};
use super::model::{BufferSize, GraphDesc, Name, ResourceDesc, TextureFormat, TextureSize};
use super::roles::PassRoles;
use crate::shader::BindingKind;
use rustc_hash::FxHashMap;
use std::sync::Arc;

/// What a physical resource is; two graph resources may share one only if these are equal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PhysicalDesc {
    /// A texture of this format, size and sample count.
    Texture {
        /// Its texel format.
        format: TextureFormat,
        /// Width in texels.
        width: u32,
        /// Height in texels.
        height: u32,
        /// MSAA sample count.
        samples: u32,
    },
    /// A buffer of this size.
    Buffer {
        /// Its size in bytes.
        bytes: u64,
    },
}

/// One texture or buffer the frame allocates, serving one or more graph resources in turn.
#[derive(Clone, Debug, PartialEq)]
pub struct PhysicalResource {
    /// What is allocated.
    pub desc: PhysicalDesc,
    /// Every usage the resources it serves need (empty for buffers).
    pub texture_usage: wgpu::TextureUsages,
    pub(crate) buffer_usage: wgpu::BufferUsages,
    /// Graph resources this one serves, in order of use.
    pub serves: Vec<Name>,
    /// Last schedule position of any resource it serves.
    pub last_use: usize,
}

/// Where a graph resource lives in the frame and when it is used.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedResource {
    /// The graph resource's name.
    pub name: Name,
    /// Index into [`ResourcePlan::physical`].
    pub physical: usize,
    /// First and last schedule position that uses it (inclusive).
    pub first: usize,
    /// The last schedule position that uses it (inclusive).
    pub last: usize,
    /// No running pass writes it (its writers were culled): cleared to zero each frame.
    pub absent: bool,
    /// What the built-in pass declared to write it says about its contents (light-list
    /// layout), even if that pass was culled.
    pub layout: Option<BufferLayout>,
}

/// Where every graph resource of a compiled graph lives: the plan's allocations and which
/// resources share them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ResourcePlan {
    /// One entry per graph resource the compiled graph uses.
    pub resources: Vec<PlannedResource>,
    /// The textures and buffers to allocate, indexed by `PlannedResource::physical`;
    /// several resources may share one.
    pub physical: Vec<PhysicalResource>,
}

impl ResourcePlan {
    /// The planned resource named `name`.
    pub fn get(&self, name: &str) -> Option<&PlannedResource> {
        self.resources.iter().find(|r| r.name == name)
    }
    /// The light-list layout of a planned buffer a culling pass writes.
    pub(crate) fn list_layout(&self, name: &str) -> Option<ListLayout> {
        match self.get(name)?.layout? {
            BufferLayout::LightLists(l) => Some(l),
            _ => None,
        }
    }
    /// The linked-list layout of a planned buffer a LightLinkedList pass writes.
    pub(crate) fn link_layout(
        &self,
        name: &str,
    ) -> Option<crate::graph::kinds::light_linked_list::LinkLayout> {
        match self.get(name)?.layout? {
            BufferLayout::LightLinks(l) => Some(l),
            _ => None,
        }
    }
}

/// Sizes the plan needs from outside the graph.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameSize {
    /// Output width in pixels.
    pub width: u32,
    /// Output height in pixels.
    pub height: u32,
    /// Lights the scene's light buffers hold (VPL room included): sizes per-light buffers
    /// and light lists.
    pub lights: u32,
}

fn texture_extent(size: TextureSize, frame: FrameSize) -> (u32, u32) {
    match size {
        TextureSize::Output => (frame.width, frame.height),
        TextureSize::Scaled(s) => (
            ((frame.width as f32 * s).ceil() as u32).max(1),
            ((frame.height as f32 * s).ceil() as u32).max(1),
        ),
        TextureSize::Fixed(w, h) => (w.max(1), h.max(1)),
    }
}

/// Per written resource, the layout the built-in pass declared to write it gives it:
/// the first pass in declaration order that writes it into a slot whose kind gives one.
/// Indexed by declared resource.
fn buffer_layouts(
    desc: &GraphDesc,
    roles: &[Arc<PassRoles>],
    ids: &PassIds,
    frame: FrameSize,
) -> Vec<Option<BufferLayout>> {
    let mut layouts = vec![None; desc.resources.len()];
    for (p, (pass, r)) in desc.passes.iter().zip(roles).enumerate() {
        for (name, &id) in pass.writes.iter().zip(ids.writes(p)) {
            if layouts[id].is_some() {
                continue;
            }
            let Some(slot) = r.slot_of(name) else {
                continue;
            };
            layouts[id] = kinds::buffer_layout(&pass.kind, slot, frame);
        }
    }
    layouts
}

fn buffer_bytes(size: BufferSize, layout: Option<BufferLayout>, frame: FrameSize) -> u64 {
    let bytes = match size {
        BufferSize::Bytes(b) => b,
        BufferSize::PerTile { tile, bytes } => {
            let t = tile.max(1);
            (frame.width.div_ceil(t) as u64 * frame.height.div_ceil(t) as u64).saturating_mul(bytes)
        }
        // Saturating: an absurd size is refused against the device's limit, never wrapped.
        BufferSize::PerPixel(b) => (frame.width as u64 * frame.height as u64).saturating_mul(b),
        BufferSize::PerLight(b) => (frame.lights.max(1) as u64).saturating_mul(b),
        BufferSize::Auto => layout.map_or(16, |l| l.bytes()),
    };
    // Storage bindings need a multiple of 4 and at least one element.
    bytes.clamp(16, u64::MAX - 3).next_multiple_of(4)
}

/// Plans physical resources for the passes in `schedule` (pass indices, in order) of
/// a validated graph; `ids` are its passes' resource indices.
pub(crate) fn plan(
    desc: &GraphDesc,
    roles: &[Arc<PassRoles>],
    ids: &PassIds,
    schedule: &[usize],
    frame: FrameSize,
) -> ResourcePlan {
    let mut plan = ResourcePlan::default();
    // Schedule positions that use each resource, from one walk over the schedule, as
    // one array: `positions[start[i]..start[i + 1]]` are resource i's, ascending.
    let mut uses_at: Vec<(usize, usize)> = Vec::new();
    let mut last_pos = vec![usize::MAX; desc.resources.len()];
    let mut start = vec![0usize; desc.resources.len() + 1];
    for (pos, &p) in schedule.iter().enumerate() {
        for &i in ids.reads(p).iter().chain(ids.writes(p)) {
            if last_pos[i] != pos {
                last_pos[i] = pos;
                uses_at.push((i, pos));
                start[i + 1] += 1;
            }
        }
    }
    for i in 0..desc.resources.len() {
        start[i + 1] += start[i];
    }
    let mut positions = vec![0usize; uses_at.len()];
    let mut fill = start.clone();
    for &(i, pos) in &uses_at {
        positions[fill[i]] = pos;
        fill[i] += 1;
    }
    let used_at = |i: usize| -> &[usize] { &positions[start[i]..start[i + 1]] };
    // Transients in order of first use.
    let mut uses: Vec<(usize, usize, usize)> = Vec::new();
    for (i, r) in desc.resources.iter().enumerate() {
        if matches!(r, ResourceDesc::Import { .. }) {
            continue;
        }
        let used_at = used_at(i);
        if used_at.is_empty() {
            continue;
        }
        let (first, last) = (used_at[0], *used_at.last().unwrap());
        // The output lives to the end of the frame (it is read back).
        let last = if r.name() == desc.output {
            schedule.len()
        } else {
            last
        };
        uses.push((first, last, i));
    }
    uses.sort_by_key(|u| u.0);
    let layouts = buffer_layouts(desc, roles, ids, frame);
    // Physical resources by descriptor, in index order: reuse takes the first free one.
    let mut by_desc: FxHashMap<PhysicalDesc, Vec<usize>> = FxHashMap::default();
    let mut users: Vec<usize> = Vec::new();
    for (first, last, i) in uses {
        let r = &desc.resources[i];
        users.clear();
        users.extend(used_at(i).iter().map(|&pos| schedule[pos]));
        let layout = match r {
            ResourceDesc::Buffer { .. } => layouts[i],
            _ => None,
        };
        let (pdesc, tex_usage, buf_usage) = describe(r, desc, roles, &users, frame, layout);
        let absent = !users.iter().any(|&p| ids.writes(p).contains(&i));
        let same = by_desc.entry(pdesc).or_default();
        let reuse = same
            .iter()
            .copied()
            .find(|&i| plan.physical[i].last_use < first);
        let physical = match reuse {
            Some(i) => i,
            None => {
                same.push(plan.physical.len());
                plan.physical.push(PhysicalResource {
                    desc: pdesc,
                    texture_usage: wgpu::TextureUsages::empty(),
                    buffer_usage: wgpu::BufferUsages::empty(),
                    serves: Vec::new(),
                    last_use: 0,
                });
                plan.physical.len() - 1
            }
        };
        let ph = &mut plan.physical[physical];
        ph.texture_usage |= tex_usage;
        ph.buffer_usage |= buf_usage;
        ph.serves.push(r.shared_name().clone());
        ph.last_use = ph.last_use.max(last);
        plan.resources.push(PlannedResource {
            name: r.shared_name().clone(),
            physical,
            first,
            last,
            absent,
            layout,
        });
    }
    plan
}

fn describe(
    r: &ResourceDesc,
    desc: &GraphDesc,
    roles: &[Arc<PassRoles>],
    users: &[usize],
    frame: FrameSize,
    layout: Option<BufferLayout>,
) -> (PhysicalDesc, wgpu::TextureUsages, wgpu::BufferUsages) {
    use wgpu::{BufferUsages as B, TextureUsages as T};
    match r {
        ResourceDesc::Texture {
            name,
            format,
            size,
            samples,
        } => {
            let (width, height) = texture_extent(*size, frame);
            // Copies: readback of the output and of any texture a test inspects. Depth
            // is also sampled by the statistics pass.
            let mut usage = T::COPY_SRC;
            // The viewer samples the output to draw it into its window.
            if format.is_depth() || *name == desc.output {
                usage |= T::TEXTURE_BINDING;
            }
            // A depth texture whose writer was culled is cleared by a render pass.
            if format.is_depth() {
                usage |= T::RENDER_ATTACHMENT;
            }
            for &p in users {
                let role = &roles[p];
                let slot = role.slot_of(name).and_then(|slot| {
                    kinds::slots(&desc.passes[p].kind)?
                        .iter()
                        .find(|s| s.name == slot)
                });
                if let Some(spec) = slot {
                    usage |= match spec.usage {
                        Usage::Attachment => T::RENDER_ATTACHMENT,
                        Usage::Sampled => T::TEXTURE_BINDING,
                        Usage::Storage => T::STORAGE_BINDING,
                        Usage::AttachmentOrStorage if format.is_depth() => T::RENDER_ATTACHMENT,
                        Usage::AttachmentOrStorage if *format == TextureFormat::R32Float => {
                            T::STORAGE_BINDING
                        }
                        Usage::AttachmentOrStorage => T::RENDER_ATTACHMENT | T::STORAGE_BINDING,
                        Usage::AttachmentOrSampled if format.is_depth() => T::RENDER_ATTACHMENT,
                        Usage::AttachmentOrSampled => T::TEXTURE_BINDING,
                        Usage::Bound => T::empty(),
                    };
                }
                if role.target.as_deref() == Some(name) {
                    usage |= T::RENDER_ATTACHMENT;
                }
                for (b, n) in &role.bindings {
                    if n == name {
                        usage |= match b.kind {
                            BindingKind::StorageTexture { .. } => T::STORAGE_BINDING,
                            _ => T::TEXTURE_BINDING,
                        };
                    }
                }
            }
            (
                PhysicalDesc::Texture {
                    format: *format,
                    width,
                    height,
                    samples: *samples,
                },
                usage,
                B::empty(),
            )
        }
        ResourceDesc::Buffer { size, .. } => (
            PhysicalDesc::Buffer {
                bytes: buffer_bytes(*size, layout, frame),
            },
            T::empty(),
            // INDIRECT: ray-cast shadow jobs carry their casting pass's dispatch.
            B::STORAGE | B::COPY_SRC | B::COPY_DST | B::UNIFORM | B::INDIRECT,
        ),
        ResourceDesc::Import { .. } => unreachable!("imports are not planned"),
    }
}
