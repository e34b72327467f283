// The light loop's building block: which lights to visit for a pixel. Tile-list readers
// call `light_range` once, then `light_at` for k in 0..count, the same for every
// culling variant (and for all lights when LIGHT_LISTS is off). The light loop walks a
// cursor instead (`light_first`, `light_valid`, `light_next`, `light_index`), which
// also walks a light linked list (LINKED_LISTS), whose links are visited in order.

struct LightRange {
    offset: u32,
    count: u32,
};

#if LINKED_LISTS
struct LightCursor {
    link: u32,
    light: u32,
};

// The first link from `link` on whose depth span `view_z` lies (LINK_END if none).
fn link_from(link: u32, view_z: f32) -> LightCursor {
    var l = link;
    loop {
        if (l == LINK_END) {
            return LightCursor(LINK_END, 0u);
        }
        let w = link_params.pool_offset + LINK_WORDS * l;
        let span = unpack2x16float(light_lists[w]);
        if (view_z >= span.x && view_z <= span.y) {
            return LightCursor(l, light_lists[w + 1u]);
        }
        l = light_lists[w + 2u];
    }
}

// `pixel` in framebuffer coordinates, `view_z` the positive view-space depth.
fn light_first(pixel: vec2<f32>, view_z: f32) -> LightCursor {
    let p = min(vec2<u32>(pixel) / link_params.scale, vec2<u32>(link_params.width, link_params.height) - 1u);
    return link_from(light_lists[LINK_HEADER_WORDS + p.y * link_params.width + p.x], view_z);
}

fn light_valid(c: LightCursor) -> bool {
    return c.link != LINK_END;
}

fn light_next(c: LightCursor, view_z: f32) -> LightCursor {
    return link_from(light_lists[link_params.pool_offset + LINK_WORDS * c.link + 2u], view_z);
}

fn light_index(c: LightCursor) -> u32 {
    return c.light;
}
#else
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

struct LightCursor {
    range: LightRange,
    k: u32,
};

fn light_first(pixel: vec2<f32>, view_z: f32) -> LightCursor {
    return LightCursor(light_range(pixel, view_z), 0u);
}

fn light_valid(c: LightCursor) -> bool {
    return c.k < c.range.count;
}

fn light_next(c: LightCursor, view_z: f32) -> LightCursor {
    return LightCursor(c.range, c.k + 1u);
}

fn light_index(c: LightCursor) -> u32 {
    return light_at(c.range, c.k);
}
#endif
