// Material classification for visibility shading: which shading groups (materials that
// share their code, shaded by one dispatch) each tile holds, so each group's dispatch runs
// over its own tiles only. A tile is one shading workgroup's SHADING_GROUP × SHADING_GROUP
// pixels.
//
// `classify`, one workgroup per tile: every invocation finds its pixel's group (the
// binary search below) and sets its bit; then each group present appends the tile to
// its list (`material_tiles[slot * TILES + n]`, n from `material_tile_counts[slot]`).
// Pixels nothing covers are cleared to black here. `dispatch_args`, one invocation per
// group: turns each count into indirect dispatch arguments, folded into y past the
// 65,535 workgroups a dimension takes (the shading shader flattens them back).
// Defines: SHADING_GROUP, SLOTS (groups shaded), MEMBERS (materials shaded), TILES (tiles
// in the frame).

#include "common/types.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(5) var visibility: texture_2d<u32>;
@group(0) @binding(9) var hdr: texture_storage_2d<rgba32float, write>;
// Per material shaded, ascending by first triangle: (first triangle id, end, its group,
// unused).
@group(0) @binding(10) var<storage, read> slot_triangles: array<vec4<u32>>;
@group(0) @binding(11) var<storage, read_write> material_tiles: array<u32>;
@group(0) @binding(12) var<storage, read_write> material_tile_counts: array<atomic<u32>>;
@group(0) @binding(13) var<storage, read_write> material_dispatch: array<u32>;

const NO_TRIANGLE: u32 = 0xffffffffu;
const NO_SLOT: u32 = 0xffffffffu;
const MASK_WORDS: u32 = (SLOTS + 31u) / 32u;
const MAX_GROUPS: u32 = 65535u;

var<workgroup> present: array<atomic<u32>, MASK_WORDS>;

// The group whose triangles hold `tri`: that of the last material starting at or before
// it, if it ends after it (triangles of blended materials are in no material's range).
fn slot_of(tri: u32) -> u32 {
    var lo = 0u;
    var hi = MEMBERS;
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (slot_triangles[mid].x <= tri) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let r = slot_triangles[lo];
    return select(NO_SLOT, r.z, tri >= r.x && tri < r.y);
}

@compute @workgroup_size(SHADING_GROUP, SHADING_GROUP, 1)
fn classify(
    @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let id = group.xy * SHADING_GROUP + local.xy;
    if (all(id < frame.size)) {
        let tri = textureLoad(visibility, id, 0).x;
        if (tri == NO_TRIANGLE) {
            textureStore(hdr, id, vec4<f32>(0.0));
        } else {
            let slot = slot_of(tri);
            if (slot != NO_SLOT) {
                atomicOr(&present[slot / 32u], 1u << (slot % 32u));
            }
        }
    }
    workgroupBarrier();
    let tile = group.y * groups.x + group.x;
    for (var w = lane; w < MASK_WORDS; w += SHADING_GROUP * SHADING_GROUP) {
        var bits = atomicLoad(&present[w]);
        while (bits != 0u) {
            let slot = w * 32u + firstTrailingBit(bits);
            bits &= bits - 1u;
            let n = atomicAdd(&material_tile_counts[slot], 1u);
            material_tiles[slot * TILES + n] = tile;
        }
    }
}

@compute @workgroup_size(64, 1, 1)
fn dispatch_args(@builtin(global_invocation_id) id: vec3<u32>) {
    let slot = id.x;
    if (slot >= SLOTS) {
        return;
    }
    let count = atomicLoad(&material_tile_counts[slot]);
    let rows = max(1u, (count + MAX_GROUPS - 1u) / MAX_GROUPS);
    material_dispatch[slot * 3u] = min(count, MAX_GROUPS);
    material_dispatch[slot * 3u + 1u] = rows;
    material_dispatch[slot * 3u + 2u] = 1u;
}
