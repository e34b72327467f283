//! What a writer publishes about a buffer it lays out, and what a reading slot needs.

use super::light_culling::ListLayout;
use super::{
    light_linked_list, light_sampling, reflective_shadow_maps, shadow_atlas, shadow_ray_jobs,
};

/// What a buffer slot's writer says about its contents, published on the planned
/// buffer so readers never search for the producer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BufferLayout {
    /// Tiled light lists of a `LightCulling` pass.
    LightLists(ListLayout),
    /// Per-pixel light linked lists: heads and the link pool.
    LightLinks(light_linked_list::LinkLayout),
    /// Ray-cast shadow jobs: a header, room for `capacity` jobs, and each pixel's surface.
    ShadowJobs {
        /// Jobs the buffer has room for.
        capacity: u64,
        /// Pixels whose surfaces follow the jobs.
        pixels: u64,
    },
    /// A 128-bit hit mask per pixel.
    ShadowMask {
        /// Pixels of the mask.
        pixels: u64,
    },
    /// A light array with room for `lights` entries of `stride` bytes (scene lights and
    /// virtual lights after them).
    Lights {
        /// Light entries.
        lights: u64,
        /// Bytes per entry.
        stride: u64,
    },
    /// A reflective shadow map's view table.
    RsmViews {
        /// Views the table holds.
        max_views: u64,
    },
    /// A shadow atlas's view table, and how shading filters the atlas.
    ShadowViews {
        /// Shadow-casting lights the table holds.
        lights: u32,
        /// Views the table holds.
        max_views: u64,
        /// How shading samples the atlas.
        filter: shadow_atlas::ShadowFilter,
        /// Who draws it, so its format: shading compares by hand in an R32Float atlas.
        raster: shadow_atlas::AtlasRaster,
    },
    /// A `VplVisibility` pass's bits, `words` a block of `block`×`block` pixels, then each
    /// block's point (`shaders/indirect/vpl_layout.wgsl`).
    VplVisibility {
        /// Pixels per side of a block.
        block: u32,
        /// Words of bits a block (32 VPLs a word).
        words: u32,
        /// Blocks of the frame.
        blocks: u64,
    },
    /// A `LightSampling` pass's exact lights and reservoirs, per pixel.
    LightSamples(light_sampling::SampleLayout),
}

/// What a laid-out buffer holds: a [`BufferLayout`] without its sizes, for contracts
/// between a buffer's writer and its readers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Contents {
    /// Tiled light lists of a `LightCulling` pass.
    LightLists,
    /// Per-pixel light linked lists of a `LightLinkedList` pass.
    LightLinks,
    /// Ray-cast shadow jobs of a `ShadowRayJobs` pass.
    ShadowJobs,
    /// The per-pixel hit mask of a `ShadowRayJobs` pass.
    ShadowMask,
    /// A light array a `VplSpawn` pass wrote.
    Lights,
    /// A `ReflectiveShadowMaps` pass's view table.
    RsmViews,
    /// A `ShadowAtlas` pass's view table.
    ShadowViews,
    /// A `VplVisibility` pass's visibility bits.
    VplVisibility,
    /// The exact lights and reservoirs of a `LightSampling` pass.
    LightSamples,
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
            Contents::VplVisibility => "VplVisibility",
            Contents::LightSamples => "LightSampling",
        }
    }
}

impl BufferLayout {
    /// What the buffer holds, without its sizes.
    pub fn contents(&self) -> Contents {
        match self {
            BufferLayout::LightLists(_) => Contents::LightLists,
            BufferLayout::LightLinks(_) => Contents::LightLinks,
            BufferLayout::ShadowJobs { .. } => Contents::ShadowJobs,
            BufferLayout::ShadowMask { .. } => Contents::ShadowMask,
            BufferLayout::Lights { .. } => Contents::Lights,
            BufferLayout::RsmViews { .. } => Contents::RsmViews,
            BufferLayout::ShadowViews { .. } => Contents::ShadowViews,
            BufferLayout::VplVisibility { .. } => Contents::VplVisibility,
            BufferLayout::LightSamples(_) => Contents::LightSamples,
        }
    }
    /// The buffer's size in bytes.
    pub fn bytes(&self) -> u64 {
        match self {
            BufferLayout::LightLists(l) => l.bytes(),
            BufferLayout::LightLinks(l) => l.bytes(),
            BufferLayout::ShadowJobs { capacity, pixels } => {
                shadow_ray_jobs::job_buffer_bytes(*capacity, *pixels)
            }
            BufferLayout::ShadowMask { pixels } => 4 * shadow_ray_jobs::MASK_WORDS * pixels,
            BufferLayout::Lights { lights, stride } => (*lights).max(1) * stride,
            BufferLayout::RsmViews { max_views } => {
                reflective_shadow_maps::view_table_bytes(*max_views)
            }
            BufferLayout::ShadowViews {
                lights, max_views, ..
            } => shadow_atlas::view_table_bytes(*lights, *max_views),
            // Each block's bits, then its point (position and packed normal: 16 bytes).
            BufferLayout::VplVisibility { words, blocks, .. } => {
                (4 * u64::from(*words) + 16) * blocks
            }
            BufferLayout::LightSamples(l) => l.bytes(),
        }
    }
    /// What would bring the buffer under `max` bytes, where a pass parameter sizes it:
    /// said with the error that refuses it.
    pub fn fit_hint(&self, max: u64) -> Option<String> {
        match *self {
            BufferLayout::ShadowJobs { pixels, .. } => Some(
                match shadow_ray_jobs::jobs_per_pixel_within(pixels, max) {
                    Some(x) => format!("ShadowRayJobs' jobs_per_pixel {x} or less fits (jobs past the buffer are lit unshadowed and counted)"),
                    None => format!(
                        "the pixels' surfaces alone take {} bytes: render a smaller frame",
                        shadow_ray_jobs::job_buffer_bytes(0, pixels)
                    ),
                },
            ),
            _ => None,
        }
    }
}
