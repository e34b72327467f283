// The walk over a pixel's lights, one for every reader: the light loop (common/light_loop.wgsl),
// visibility shading's faster loops, light statistics and the shadow passes.
// A cursor visits the pixel's lights in list order:
//     for (var c = light_first(pixel, view_z); light_valid(c); c = light_next(c, view_z)) {
//         let i = light_index(c);
// the same for every culling variant, a light linked list (LINKED_LISTS: links whose
// depth span misses the surface are skipped here, so no caller tests spans) and all
// lights (neither LINKED_LISTS nor LIGHT_LISTS). Tile-list readers that need the list
// itself call `light_range` once, then `light_at` for k in 0..count.

struct LightRange {
    offset: u32,
    count: u32,
};

#if LINKED_LISTS
// A link of the pixel's list (LINK_END past the last), and how many links may follow:
// the longest list the build wrote (header word 3) bounds every walk, so a lane that
// reads no list (llvmpipe's helper lanes, a corrupted pool) cannot spin.
struct LightCursor {
    link: u32,
    left: u32,
};

fn light_valid(c: LightCursor) -> bool {
    return c.link != LINK_END && c.left > 0u;
}

// The link after `c`, whatever its span.
fn light_link_after(c: LightCursor) -> LightCursor {
    return LightCursor(light_lists[link_params.pool_offset + LINK_WORDS * c.link + 2u], c.left - 1u);
}

// Whether `view_z` (positive view depth) lies in the link's light span.
fn light_in_span(c: LightCursor, view_z: f32) -> bool {
    let span = unpack2x16float(light_lists[link_params.pool_offset + LINK_WORDS * c.link]);
    return view_z >= span.x && view_z <= span.y;
}

// `c` or the first link after it whose span holds `view_z` (or the end).
fn light_skip_to_span(c: LightCursor, view_z: f32) -> LightCursor {
    var s = c;
    while (light_valid(s) && !light_in_span(s, view_z)) {
        s = light_link_after(s);
    }
    return s;
}

// `pixel` in framebuffer coordinates.
fn light_first(pixel: vec2<f32>, view_z: f32) -> LightCursor {
    let p = min(vec2<u32>(pixel) / link_params.scale, vec2<u32>(link_params.width, link_params.height) - 1u);
    let head = LightCursor(light_lists[LINK_HEADER_WORDS + p.y * link_params.width + p.x], light_lists[3]);
    return light_skip_to_span(head, view_z);
}

fn light_next(c: LightCursor, view_z: f32) -> LightCursor {
    return light_skip_to_span(light_link_after(c), view_z);
}

fn light_index(c: LightCursor) -> u32 {
    return light_lists[link_params.pool_offset + LINK_WORDS * c.link + 1u];
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

// Tile lists bound no depth span per light: every entry is visited.
fn light_next(c: LightCursor, view_z: f32) -> LightCursor {
    return LightCursor(c.range, c.k + 1u);
}

fn light_index(c: LightCursor) -> u32 {
    return light_at(c.range, c.k);
}
#endif
