// Visibility shading's faster light loops; both add exactly what common/light_loop.wgsl's
// shade_surface adds, in list order, so the image is the same to the bit:
// - `staged_lights` (STAGED_LIGHTS): when every pixel of an 8×8 workgroup reads the same
//   tile list (one list per tile, the tile 8 or 16 pixels, so the workgroup lies inside
//   one tile), the workgroup loads the list in batches, one light per invocation, into
//   workgroup memory, and every pixel runs the batch from there: one global load per
//   light and workgroup instead of three dependent loads per light and pixel.
// - `shade_range_first` (RANGE_FIRST): the per-pixel cursor for lists that differ
//   between pixels (HalfZ, Clustered, linked lists) and for all lights.
// Both test the range window from the light's geometry before reading its properties:
// a light out of range (window <= 0) gives zero radiance, which shade_surface never adds
// (it adds only radiance > 0), so skipping it first changes no bit. The window tested is
// the one incident_reached then uses (light_reach, computed once).

// The emitted and ambient light every loop starts from, as shade_surface does.
fn surface_unlit(p: ShadingPoint, m: MaterialSample) -> vec3<f32> {
    return material_emission(m) + frame.ambient.rgb * material_eval(m, p.normal);
}

// Light (g, props) at reach r added to `color`, when the material takes it and it
// gives radiance, as shade_surface adds it.
fn add_reached(color: vec3<f32>, g: LightGeometry, props: LightProperties, r: LightReach, m: MaterialSample) -> vec3<f32> {
    if ((props.material_mask & MATERIAL_TYPE_BIT) == 0u) {
        return color;
    }
    let inc = incident_reached(g, props, r);
    if (any(inc.radiance > vec3<f32>(0.0))) {
        return color + inc.radiance * material_eval(m, inc.dir);
    }
    return color;
}

// A squared distance past which range_window is surely zero: dist_sq over
// fl(range²)·1.001 rounded down is over range² by 1e-3 at least, so the quotient r in
// range_window, within 2.5 ulp (Vulkan's OpFDiv), is over 1, r² rounds to 1 or more, and
// 1 − r² clamps to 0, fused or not. A NaN or infinite range rejects nothing here; the
// exact test after it decides.
fn reject_beyond(range: f32) -> f32 {
    return range * range * 1.001;
}

#if RANGE_FIRST
fn shade_range_first(p: ShadingPoint, m: MaterialSample, pixel: vec2<f32>, view_z: f32) -> vec3<f32> {
    var color = surface_unlit(p, m);
    for (var c = light_first(pixel, view_z); light_valid(c); c = light_next(c)) {
        if (!light_in_span(c, view_z)) {
            continue;
        }
        let i = light_index(c);
        let g = light_geometry[i];
        // Far out of range: no division (reject_beyond's bound; the exact window decides
        // the rest).
        let d = g.position - p.position;
        if (dot(d, d) > reject_beyond(g.range)) {
            continue;
        }
        let r = light_reach(g, p.position);
        if (r.window <= 0.0) {
            continue;
        }
        color = add_reached(color, g, light_properties[i], r, m);
    }
    return color;
}
#endif

#if STAGED_LIGHTS
// One light per invocation of the 8×8 workgroup, two batches (the one shaded, the one
// stored): 2 × 64 × 80 bytes of workgroup memory.
const STAGE_BATCH: u32 = 64u;
// xyz: the light's position; w: a squared distance past which it surely adds nothing
// here (`reject_beyond`), -1 when this material does not take it.
var<workgroup> staged_reach: array<vec4<f32>, 128>;
var<workgroup> staged_geometry: array<LightGeometry, 128>;
var<workgroup> staged_properties: array<LightProperties, 128>;


// The tile list of the workgroup at `group` (8×8 pixels from group × 8): with one list
// per tile and the tile a multiple of 8, the list of each of its pixels.
fn group_list(group: vec2<u32>) -> LightRange {
    let t = group * 8u / list_params.tile;
    return list_entry(t.y * list_params.tiles_x + t.x);
}

struct ListedLight {
    g: LightGeometry,
    props: LightProperties,
};

fn listed_light(i: u32) -> ListedLight {
    return ListedLight(light_geometry[i], light_properties[i]);
}

fn stage(slot: u32, l: ListedLight) {
    // dist_sq >= 0 rejects a light the material does not take; a NaN dist_sq goes on to
    // add_reached, which skips it.
    var beyond = reject_beyond(l.g.range);
    if ((l.props.material_mask & MATERIAL_TYPE_BIT) == 0u) {
        beyond = -1.0;
    }
    staged_reach[slot] = vec4<f32>(l.g.position, beyond);
    staged_geometry[slot] = l.g;
    staged_properties[slot] = l.props;
}

// `list` is workgroup-uniform (from the workgroup id), so every invocation runs the same
// batches and meets every barrier; `shades` says whether this one's pixel takes the
// lights (p and m are its surface then). Loads run ahead in registers: a batch's lights
// are loaded while the batch before is shaded, and their list indices one batch earlier
// still, so each load has a batch of shading to arrive in. Batches alternate between
// two halves of workgroup memory, so one barrier a batch suffices: a batch is stored
// after the barrier that ends the shading of the batch that used its half before.
// Per light and pixel: one 16-byte read and a dot product for lights out of range; the
// exact window, the properties and the BRDF only for the rest.
fn staged_lights(unlit: vec3<f32>, shades: bool, p: ShadingPoint, m: MaterialSample, lane: u32, list: LightRange) -> vec3<f32> {
    var color = unlit;
    var light: ListedLight;
    if (lane < list.count) {
        light = listed_light(light_at(list, lane));
    }
    var index = 0u;
    if (STAGE_BATCH + lane < list.count) {
        index = light_at(list, STAGE_BATCH + lane);
    }
    for (var base = 0u; base < list.count; base += STAGE_BATCH) {
        let half_start = (base / STAGE_BATCH) % 2u * STAGE_BATCH;
        if (base + lane < list.count) {
            stage(half_start + lane, light);
        }
        workgroupBarrier();
        if (base + STAGE_BATCH + lane < list.count) {
            light = listed_light(index);
        }
        if (base + 2u * STAGE_BATCH + lane < list.count) {
            index = light_at(list, base + 2u * STAGE_BATCH + lane);
        }
        if (shades) {
            let n = min(STAGE_BATCH, list.count - base);
            for (var j = half_start; j < half_start + n; j += 1u) {
                let reach = staged_reach[j];
                // light_reach's arithmetic, from the same position bits.
                let d = reach.xyz - p.position;
                let dist_sq = dot(d, d);
                if (dist_sq > reach.w) {
                    continue;
                }
                let g = staged_geometry[j];
                let r = LightReach(d, dist_sq, range_window(dist_sq, g.range));
                if (r.window <= 0.0) {
                    continue;
                }
                color = add_reached(color, g, staged_properties[j], r, m);
            }
        }
    }
    return color;
}
#endif
