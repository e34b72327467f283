//! What a writer publishes about a buffer it lays out, and what a reading slot needs.

use super::light_culling::ListLayout;
use super::{light_linked_list, reflective_shadow_maps, shadow_atlas, shadow_ray_jobs};

/// What a buffer slot's writer says about its contents, published on the planned
/// buffer so readers never search for the producer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BufferLayout {
    LightLists(ListLayout),
    /// Per-pixel light linked lists: heads and the link pool.
    LightLinks(light_linked_list::LinkLayout),
    /// Ray-cast shadow jobs: a header and room for `capacity` jobs.
    ShadowJobs {
        capacity: u64,
    },
    /// A 128-bit hit mask per pixel.
    ShadowMask {
        pixels: u64,
    },
    /// A light array with room for `lights` entries of `stride` bytes (scene lights and
    /// virtual lights after them).
    Lights {
        lights: u64,
        stride: u64,
    },
    /// A reflective shadow map's view table.
    RsmViews {
        max_views: u64,
    },
    /// A shadow atlas's view table, and how shading filters the atlas.
    ShadowViews {
        lights: u32,
        max_views: u64,
        filter: shadow_atlas::ShadowFilter,
    },
}

/// What a laid-out buffer holds: a [`BufferLayout`] without its sizes, for contracts
/// between a buffer's writer and its readers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Contents {
    LightLists,
    LightLinks,
    ShadowJobs,
    ShadowMask,
    Lights,
    RsmViews,
    ShadowViews,
}

impl Contents {
    /// The kind whose pass lays such a buffer out, for messages.
    pub fn producer(self) -> &'static str {
        match self {
            Contents::LightLists => "LightCulling",
            Contents::LightLinks => "LightLinkedList",
            Contents::ShadowJobs | Contents::ShadowMask => "ShadowRayJobs",
            Contents::Lights => "VplSpawn",
            Contents::RsmViews => "ReflectiveShadowMaps",
            Contents::ShadowViews => "ShadowAtlas",
        }
    }
}

impl BufferLayout {
    pub fn contents(&self) -> Contents {
        match self {
            BufferLayout::LightLists(_) => Contents::LightLists,
            BufferLayout::LightLinks(_) => Contents::LightLinks,
            BufferLayout::ShadowJobs { .. } => Contents::ShadowJobs,
            BufferLayout::ShadowMask { .. } => Contents::ShadowMask,
            BufferLayout::Lights { .. } => Contents::Lights,
            BufferLayout::RsmViews { .. } => Contents::RsmViews,
            BufferLayout::ShadowViews { .. } => Contents::ShadowViews,
        }
    }
    pub fn bytes(&self) -> u64 {
        match self {
            BufferLayout::LightLists(l) => l.bytes(),
            BufferLayout::LightLinks(l) => l.bytes(),
            BufferLayout::ShadowJobs { capacity } => shadow_ray_jobs::job_buffer_bytes(*capacity),
            BufferLayout::ShadowMask { pixels } => 4 * shadow_ray_jobs::MASK_WORDS * pixels,
            BufferLayout::Lights { lights, stride } => (*lights).max(1) * stride,
            BufferLayout::RsmViews { max_views } => {
                reflective_shadow_maps::view_table_bytes(*max_views)
            }
            BufferLayout::ShadowViews {
                lights, max_views, ..
            } => shadow_atlas::view_table_bytes(*lights, *max_views),
        }
    }
}
