// GPU structs. Each has a #[repr(C)] twin in src/gpu/structs.rs; a test compares the
// offsets naga computes here with Rust's.

struct Frame {
    view: mat4x4<f32>,
    proj: mat4x4<f32>,
    view_proj: mat4x4<f32>,
    inv_proj: mat4x4<f32>,
    camera_pos: vec4<f32>,
    // rgb: constant ambient radiance
    ambient: vec4<f32>,
    size: vec2<u32>,
    light_count: u32,
    // One past the highest index of a shadow-casting light (0 without): lists hold
    // lights in ascending index, so a walk over a list's casters stops there.
    caster_end: u32,
    near: f32,
    far: f32,
    _pad1: vec2<f32>,
};

// What culling reads: position, range and cone. Point lights have cos_outer = -1.
struct LightGeometry {
    position: vec3<f32>,
    range: f32,
    direction: vec3<f32>,
    cos_outer: f32,
};

// What shading reads besides geometry. `color` is colour times intensity (candela).
struct LightProperties {
    color: vec3<f32>,
    cos_inner: f32,
    flags: u32,
    material_mask: u32,
    _pad0: u32,
    // A VPL's disc radius squared (VplSpawn's `falloff: Disc`); 0 for any other light.
    disc_sq: f32,
};

// How a culling pass laid out its light lists (see ListLayout in src/graph/plan.rs).
struct ListParams {
    tiles_x: u32,
    tiles_y: u32,
    tile: u32,
    lists_per_tile: u32,
    // Fixed lists' capacity; 0 for compact lists.
    capacity: u32,
    // 0 Frustum, 1 HalfZ, 2 DepthMask, 3 Clustered
    variant: u32,
    // Words before the index pool, and light indices the pool holds.
    pool_offset: u32,
    pool_indices: u32,
};

// How a LightLinkedList pass laid out its links (see LinkLayout in
// src/kinds/light_linked_list/rules.rs).
struct LinkParams {
    // Output pixels per list-pixel side.
    scale: u32,
    // List pixels per side.
    width: u32,
    height: u32,
    // Words before the first link, and links the pool holds.
    pool_offset: u32,
    pool: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
};

// A mesh vertex's floats in the merged vertex array (src/gpu/structs.rs GpuVertex):
// position xyz, normal xyz, uv, tangent xyzw, colour rgba, second uv.
const VERTEX_FLOATS: u32 = 18u;

const LINK_HEADER_WORDS: u32 = 4u;
const LINK_WORDS: u32 = 3u;
const LINK_END: u32 = 0xffffffffu;

const VARIANT_FRUSTUM: u32 = 0u;
const VARIANT_HALF_Z: u32 = 1u;
const VARIANT_DEPTH_MASK: u32 = 2u;
const VARIANT_CLUSTERED: u32 = 3u;

const HEADER_WORDS: u32 = 4u;
const ENTRY_WORDS: u32 = 4u;
