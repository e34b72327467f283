// The light loop's building block: which lights to visit for a pixel. Material shaders
// call `light_range` once, then `light_at` for k in 0..count, the same for every
// culling variant (and for all lights when LIGHT_LISTS is off).

struct LightRange {
    offset: u32,
    count: u32,
};

#if LIGHT_LISTS
fn list_entry(list: u32) -> LightRange {
    let e = HEADER_WORDS + ENTRY_WORDS * list;
    return LightRange(light_lists[e], light_lists[e + 1u]);
}

fn cluster_slice(view_z: f32) -> u32 {
    let s = f32(list_params.lists_per_tile);
    let k = floor(log(max(view_z, frame.near) / frame.near) / log(frame.far / frame.near) * s);
    return u32(clamp(k, 0.0, s - 1.0));
}

// `pixel` in framebuffer coordinates, `view_z` the positive view-space depth.
fn light_range(pixel: vec2<f32>, view_z: f32) -> LightRange {
    let t = vec2<u32>(pixel) / list_params.tile;
    let tile = t.y * list_params.tiles_x + t.x;
    var list = tile * list_params.lists_per_tile;
    if (list_params.variant == VARIANT_HALF_Z) {
        let first_max = bitcast<f32>(light_lists[HEADER_WORDS + ENTRY_WORDS * list + 3u]);
        if (view_z > first_max) {
            list += 1u;
        }
    } else if (list_params.variant == VARIANT_CLUSTERED) {
        list += cluster_slice(view_z);
    }
    return list_entry(list);
}

fn light_at(r: LightRange, k: u32) -> u32 {
    return light_lists[list_params.pool_offset + r.offset + k];
}
#else
fn light_range(pixel: vec2<f32>, view_z: f32) -> LightRange {
    return LightRange(0u, frame.light_count);
}

fn light_at(r: LightRange, k: u32) -> u32 {
    return k;
}
#endif
