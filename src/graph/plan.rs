//! Step 5: resource lifetimes and reuse. wgpu has no placed resources, so aliasing means
//! one physical texture or buffer serving several graph resources with the same
//! descriptor whose lifetimes (first to last use in the schedule) do not overlap.

use super::deps::PassIds;
use super::fxmap::FxHashMap;
use super::kinds::{self, BufferLayout, Usage};
use super::model::{
    BufferSize, CullVariant, GraphDesc, Name, ResourceDesc, TextureFormat, TextureSize,
};
use super::roles::PassRoles;
use crate::shader::BindingKind;
use std::sync::Arc;

/// What a physical resource is; two graph resources may share one only if these are equal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PhysicalDesc {
    Texture {
        format: TextureFormat,
        width: u32,
        height: u32,
        samples: u32,
    },
    Buffer {
        bytes: u64,
    },
}

#[derive(Clone, Debug, PartialEq)]
pub struct PhysicalResource {
    pub desc: PhysicalDesc,
    pub texture_usage: wgpu::TextureUsages,
    pub buffer_usage: wgpu::BufferUsages,
    /// Graph resources this one serves, in order of use.
    pub serves: Vec<Name>,
    /// Last schedule position of any resource it serves.
    pub last_use: usize,
}

#[derive(Clone, Debug, PartialEq)]
pub struct PlannedResource {
    pub name: Name,
    /// Index into [`ResourcePlan::physical`].
    pub physical: usize,
    /// First and last schedule position that uses it (inclusive).
    pub first: usize,
    pub last: usize,
    /// No running pass writes it (its writers were culled): cleared to zero each frame.
    pub absent: bool,
    /// What the built-in pass declared to write it says about its contents (light-list
    /// layout), even if that pass was culled.
    pub layout: Option<BufferLayout>,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct ResourcePlan {
    pub resources: Vec<PlannedResource>,
    pub physical: Vec<PhysicalResource>,
}

impl ResourcePlan {
    pub fn get(&self, name: &str) -> Option<&PlannedResource> {
        self.resources.iter().find(|r| r.name == name)
    }
    /// The light-list layout of a planned buffer a culling pass writes.
    pub fn list_layout(&self, name: &str) -> Option<ListLayout> {
        match self.get(name)?.layout? {
            BufferLayout::LightLists(l) => Some(l),
            _ => None,
        }
    }
    /// The linked-list layout of a planned buffer a LightLinkedList pass writes.
    pub fn link_layout(
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
    pub width: u32,
    pub height: u32,
    pub lights: u32,
}

/// Layout of a culling pass's light-list buffer, shared with `shaders/cull/*.wgsl` and
/// every reader through `shaders/common/light_lists.wgsl`: a header of 4 u32, then
/// (offset, count, z_min, z_max) per list, then the index pool. A list's lights are
/// `pool[offset .. offset + count]`, in ascending light order, in both storages.
/// `Compact` pools start with a scratch slot of [`Self::scratch_per_list`] indices per
/// list, in list order: a list of 1 to that many lights lies in its own slot, every other
/// list after all slots, back to back in list order.
///
/// Header, `Fixed`: pool cursor, lists cut at the capacity, longest list wanted, unused.
/// Header, `Compact`: indices the lists past their slot wanted (all lists without
/// scratch; saturating at u32::MAX), lists cut at the bound, longest list wanted, lists
/// whose fill found other lights than their count (0 unless the two dispatches disagree;
/// counted so it is never silent).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ListLayout {
    /// Pixels per tile side.
    pub tile: u32,
    pub variant: CullVariant,
    pub tiles_x: u32,
    pub tiles_y: u32,
    pub lists_per_tile: u32,
    pub storage: ListStorage,
}

/// How a culling pass stores its lists: room for `capacity` lights in every list, or
/// one flat array of at most `max_indices` for all lists together, filled by count →
/// prefix sum → fill, with slots of `scratch` indices per list (as the graph asks; see
/// [`ListLayout::scratch_per_list`]) for the lists that need no fill.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ListStorage {
    Fixed { capacity: u32 },
    Compact { max_indices: u32, scratch: u32 },
}

impl ListLayout {
    pub const HEADER_WORDS: u32 = 4;
    /// Words per list entry: offset, count, and the view-depth range it covers (f32 bits).
    pub const ENTRY_WORDS: u32 = 4;
    /// Lists per workgroup of the compact layout's scan (256 invocations × 4 lists).
    pub const SCAN_BLOCK: u32 = 1024;
    pub fn new(
        tile: u32,
        variant: CullVariant,
        storage: ListStorage,
        width: u32,
        height: u32,
    ) -> Self {
        Self {
            tile,
            variant,
            tiles_x: width.div_ceil(tile),
            tiles_y: height.div_ceil(tile),
            lists_per_tile: match variant {
                CullVariant::HalfZ => 2,
                CullVariant::Clustered { slices } => slices,
                CullVariant::Frustum | CullVariant::DepthMask => 1,
            },
            storage,
        }
    }
    pub fn lists(&self) -> u32 {
        self.tiles_x * self.tiles_y * self.lists_per_tile
    }
    pub fn pool_offset_words(&self) -> u32 {
        Self::HEADER_WORDS + Self::ENTRY_WORDS * self.lists()
    }
    /// Light indices the pool holds: every list at full capacity (so only a list longer
    /// than the capacity can overflow), or the compact bound for all lists together.
    pub fn pool_indices(&self) -> u64 {
        match self.storage {
            ListStorage::Fixed { capacity } => self.lists() as u64 * capacity as u64,
            ListStorage::Compact { max_indices, .. } => max_indices as u64,
        }
    }
    /// Compact lists: each list's scratch slot, in light indices. The graph's `scratch`,
    /// lowered where the slots would take more than half of `max_indices` (to
    /// ⌊max_indices / 2L⌋ for L lists), so the pool keeps at least half; 0 for fixed lists.
    pub fn scratch_per_list(&self) -> u32 {
        match self.storage {
            ListStorage::Fixed { .. } => 0,
            ListStorage::Compact {
                max_indices,
                scratch,
            } => {
                let half_per_list = max_indices as u64 / (2 * self.lists().max(1) as u64);
                scratch.min(half_per_list as u32)
            }
        }
    }
    /// Compact lists: the indices all scratch slots take at the start of the pool.
    pub fn scratch_indices(&self) -> u64 {
        self.scratch_per_list() as u64 * self.lists() as u64
    }
    /// Scan blocks of the compact layout (0 for fixed lists).
    pub fn scan_blocks(&self) -> u32 {
        match self.storage {
            ListStorage::Fixed { .. } => 0,
            ListStorage::Compact { .. } => self.lists().div_ceil(Self::SCAN_BLOCK),
        }
    }
    /// The whole buffer: header, entries and pool. Overflow of any list is counted,
    /// never silent.
    pub fn bytes(&self) -> u64 {
        4 * (self.pool_offset_words() as u64 + self.pool_indices())
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn list_layout_counts_partial_tiles() {
        let fixed = |capacity| ListStorage::Fixed { capacity };
        let l = ListLayout::new(16, CullVariant::Frustum, fixed(256), 333, 197);
        assert_eq!((l.tiles_x, l.tiles_y), (21, 13));
        assert_eq!(l.lists(), 273);
        let h = ListLayout::new(8, CullVariant::HalfZ, fixed(64), 16, 16);
        assert_eq!(h.lists(), 8);
        assert_eq!(h.bytes(), 4 * (4 + 32 + 8 * 64));
        assert_eq!(h.scan_blocks(), 0);
    }

    #[test]
    fn compact_lists_are_bounded_by_the_graph_alone() {
        let compact = ListStorage::Compact {
            max_indices: 5000,
            scratch: 256,
        };
        let c = ListLayout::new(8, CullVariant::Clustered { slices: 16 }, compact, 333, 197);
        assert_eq!(c.lists(), 42 * 25 * 16);
        // Header, one entry a list, then exactly the bound: scratch slots come out of it.
        assert_eq!(c.bytes(), 4 * (4 + 4 * 16_800 + 5000));
        assert_eq!(c.scan_blocks(), 17);
        // 16,800 slots of 256 would take 860 times the bound: none fit in half of it.
        assert_eq!(c.scratch_per_list(), 0);
    }

    #[test]
    fn scratch_slots_take_at_most_half_the_bound() {
        let compact = |max_indices, scratch| ListStorage::Compact {
            max_indices,
            scratch,
        };
        let frustum = |storage| ListLayout::new(16, CullVariant::Frustum, storage, 1920, 1080);
        // The shipped bound at 1920×1080: 8,160 slots of 256 (8 MiB of 64).
        let shipped = frustum(compact(16_777_216, 256));
        assert_eq!(shipped.scratch_per_list(), 256);
        assert_eq!(shipped.scratch_indices(), 8_160 * 256);
        assert_eq!(shipped.bytes(), 4 * (4 + 4 * 8_160 + 16_777_216));
        // 2 · 8,160 · 100 = 1,632,000 indices: 100 fits, 101 does not.
        assert_eq!(frustum(compact(1_632_000, 256)).scratch_per_list(), 100);
        assert_eq!(frustum(compact(1_631_999, 256)).scratch_per_list(), 99);
        assert_eq!(frustum(compact(16_777_216, 0)).scratch_per_list(), 0);
        let clustered = ListLayout::new(
            16,
            CullVariant::Clustered { slices: 16 },
            compact(16_777_216, 256),
            1920,
            1080,
        );
        assert_eq!(clustered.scratch_per_list(), 64);
        let fixed = frustum(ListStorage::Fixed { capacity: 256 });
        assert_eq!(fixed.scratch_per_list(), 0);
    }
}
