// Visibility shading's faster light loops; both add exactly what common/light_loop.wgsl's
// shade_surface adds, in list order, so the image is the same to the bit:
// - `staged_lights` (STAGED_LIGHTS): when every pixel of an 8×8 workgroup reads the same
//   tile list (one list per tile, the tile 8 or 16 pixels, so the workgroup lies inside
//   one tile), the workgroup loads the list in batches, one light per invocation, into
//   workgroup memory, and every pixel runs the batch from there: one global load per
//   light and workgroup instead of three dependent loads per light and pixel.
// - `shade_range_first` (RANGE_FIRST): each pixel walks its own list (tile lists of any
//   culling variant two lights a step, a light linked list by its cursor, or all lights).
// Both test the range window from the light's geometry before reading its properties:
// a light out of range (window <= 0) gives zero radiance, which shade_surface never adds
// (it adds only radiance > 0), so skipping it first changes no bit. The window tested is
// the one incident_reached then uses (light_reach, computed once).

// The emitted and ambient light every loop starts from, as shade_surface does.
fn surface_unlit(p: ShadingPoint, m: MaterialSample) -> vec3<f32> {
    return material_emission(m) + frame.ambient.rgb * material_eval(m, p.normal);
}

#if SHADOWS
// The shaded pixel (its mask's index) and its next caster number: casters are the
// shadow-casting lights that reach it (radiance > 0), numbered in list order whatever
// the material takes, as job creation and shade_surface number them.
var<private> shadow_pixel: u32;
var<private> shadow_caster: u32;
#endif

// Light `i` (g, props) at reach r added to `color`, when the material takes it and it
// gives radiance (and, with SHADOWS, scaled by the fraction of it that reaches p: its
// caster bit or its atlas taps), as shade_surface adds it.
fn add_reached(color: vec3<f32>, i: u32, g: LightGeometry, props: LightProperties, r: LightReach, p: ShadingPoint, m: MaterialSample) -> vec3<f32> {
#if VPL_VISIBILITY
    // As shade_surface: a hidden VPL adds nothing and numbers no caster.
    if (!vpl_visible(props)) {
        return color;
    }
#endif
#if SHADOWS
    if ((props.flags & LIGHT_CASTS_SHADOW) != 0u) {
        let inc = incident_reached(g, props, r);
        if (!any(inc.radiance > vec3<f32>(0.0))) {
            return color;
        }
        let caster = shadow_caster;
        shadow_caster += 1u;
        if ((props.material_mask & MATERIAL_TYPE_BIT) == 0u) {
            return color;
        }
        let visibility = shadow_visibility(shadow_pixel, caster, i, g.position, p);
        if (visibility <= 0.0) {
            return color;
        }
        return color + (visibility * inc.radiance) * reflect_incident(m, inc);
    }
#endif
    if ((props.material_mask & MATERIAL_TYPE_BIT) == 0u) {
        return color;
    }
    let inc = incident_reached(g, props, r);
    if (any(inc.radiance > vec3<f32>(0.0))) {
        return color + inc.radiance * reflect_incident(m, inc);
    }
    return color;
}

#if RANGE_FIRST
// Light i (its position and range in q) added to `color` when its range window is
// positive: first reject_beyond's bound (no division), then the exact window.
fn add_in_range(color: vec3<f32>, q: vec4<f32>, i: u32, p: ShadingPoint, m: MaterialSample) -> vec3<f32> {
    let d = q.xyz - p.position;
    let dist_sq = dot(d, d);
    if (dist_sq > reject_beyond(q.w)) {
        return color;
    }
    let r = LightReach(d, dist_sq, range_window(dist_sq, q.w));
    if (r.window <= 0.0) {
        return color;
    }
    return add_reached(color, i, light_geometry[i], light_properties[i], r, p, m);
}

// What the range test reads of a light: its position and range (16 bytes).
fn light_reach_of(i: u32) -> vec4<f32> {
    return vec4<f32>(light_geometry[i].position, light_geometry[i].range);
}

#if LINKED_LISTS
fn shade_range_first(p: ShadingPoint, m: MaterialSample, pixel: vec2<f32>, view_z: f32) -> vec3<f32> {
    var color = surface_unlit(p, m);
    for (var c = light_first(pixel, view_z); light_valid(c); c = light_next(c, view_z)) {
        let i = light_index(c);
        color = add_in_range(color, light_reach_of(i), i, p, m);
    }
    return color;
}
#else
// Two lights a step: both lights' indices, then both positions, are loaded before either
// is tested, so each load waits once for two (on the H200 at 65,536 lights 3.64 ms
// against 4.03 one at a time, 3,072 lights 0.234 against 0.251; four a step was slower
// at 3,072, the registers it holds cost warps). Lights are still added in list order.
fn shade_range_first(p: ShadingPoint, m: MaterialSample, pixel: vec2<f32>, view_z: f32) -> vec3<f32> {
    return shade_list(p, m, light_range(pixel, view_z));
}

// The lights of list `r` added to the surface's unlit colour, two a step.
fn shade_list(p: ShadingPoint, m: MaterialSample, r: LightRange) -> vec3<f32> {
    var color = surface_unlit(p, m);
    var k = 0u;
    for (; k + 2u <= r.count; k += 2u) {
        let i0 = light_at(r, k);
        let i1 = light_at(r, k + 1u);
        let q0 = light_reach_of(i0);
        let q1 = light_reach_of(i1);
        color = add_in_range(color, q0, i0, p, m);
        color = add_in_range(color, q1, i1, p, m);
    }
    if (k < r.count) {
        let i = light_at(r, k);
        color = add_in_range(color, light_reach_of(i), i, p, m);
    }
    return color;
}
#endif
#endif

#if SUBGROUP_LIST
// The subgroup's one list, a subgroup of lights at a time: each invocation loads one
// light's index and reach (independent loads, in parallel), then every invocation tests
// and adds them in list order, each light's index and reach taken from the invocation
// that loaded it. A light's chain of dependent loads (its index, then its reach) was what
// bounded the per-pixel walk: on an NVIDIA H100 at 65,536 lights the walk and range tests
// alone took 1.30 of harada's 2.72 ms of shading.
// Lights that reach no shaded point of the subgroup are not passed round at all: a light
// whose squared distance to the box around those points is over reject_beyond's bound is
// over it from every point in the box (the box's nearest point is nearer, and rounding is
// monotonic), so each pixel's own test would have skipped it. The subgroup's pixels are an
// 8×4 block, so this culls the tile list per block, exactly (harada at 65,536 lights:
// 2.45 → 2.15 ms on the H100; docs/visibility_buffer.md). `shades`: this invocation's
// pixel is shaded (the others' points, rebuilt from another triangle, stay out of the
// box). Every invocation of the subgroup must run it.
fn shade_list_subgroup(p: ShadingPoint, m: MaterialSample, r: LightRange, shades: bool, sg_lane: u32, sg_size: u32) -> vec3<f32> {
    var color = surface_unlit(p, m);
    let far = 3.0e38;
    let lo = subgroupMin(select(vec3<f32>(far), p.position, shades));
    let hi = subgroupMax(select(vec3<f32>(-far), p.position, shades));
    for (var base = 0u; base < r.count; base += sg_size) {
        var i = 0u;
        var q = vec4<f32>(0.0);
        var near = false;
        if (base + sg_lane < r.count) {
            i = light_at(r, base + sg_lane);
            q = light_reach_of(i);
            // Not over the bound, NaN included: those go on to each pixel's own test.
            let e = q.xyz - clamp(q.xyz, lo, hi);
            near = !(dot(e, e) > reject_beyond(q.w));
        }
        // The near lights in list order, a 32-bit word of the ballot at a time.
        let ballot = subgroupBallot(near);
        for (var w = 0u; w * 32u < sg_size; w += 1u) {
            var bits = ballot[w];
            while (bits != 0u) {
                let j = w * 32u + firstTrailingBit(bits);
                bits &= bits - 1u;
                let qj = subgroupShuffle(q, j);
                let ij = subgroupShuffle(i, j);
                color = add_in_range(color, qj, ij, p, m);
            }
        }
    }
    return color;
}
#endif

#if LIGHT_LISTS
// The tile list of the workgroup at `group` (SHADING_GROUP² pixels from group ×
// SHADING_GROUP): with one list per tile and the tile a multiple of SHADING_GROUP, the
// list of each of its pixels.
fn group_list(group: vec2<u32>) -> LightRange {
    let t = group * SHADING_GROUP / list_params.tile;
    return list_entry(t.y * list_params.tiles_x + t.x);
}
#endif

#if STAGED_LIGHTS
// One light per invocation of the 8×8 workgroup, two batches (the one shaded, the one
// stored): 2 × 64 × 80 bytes of workgroup memory (84 with SHADOWS).
const STAGE_BATCH: u32 = 64u;
// xyz: the light's position; w: a squared distance past which it surely adds nothing
// here (`reject_beyond`), -1 when this material does not take it.
var<workgroup> staged_reach: array<vec4<f32>, 128>;
var<workgroup> staged_geometry: array<LightGeometry, 128>;
var<workgroup> staged_properties: array<LightProperties, 128>;
#if SHADOWS
// The lights' indices: the atlas finds a caster's views by its index.
var<workgroup> staged_index: array<u32, 128>;
#endif

struct ListedLight {
    index: u32,
    g: LightGeometry,
    props: LightProperties,
};

fn listed_light(i: u32) -> ListedLight {
    return ListedLight(i, light_geometry[i], light_properties[i]);
}

fn stage(slot: u32, l: ListedLight) {
    // dist_sq >= 0 rejects a light the material does not take; a NaN dist_sq goes on to
    // add_reached, which skips it.
    var beyond = reject_beyond(l.g.range);
    var untaken = (l.props.material_mask & MATERIAL_TYPE_BIT) == 0u;
#if SHADOWS
    // A caster the material does not take still takes its caster number (add_reached).
    untaken = untaken && (l.props.flags & LIGHT_CASTS_SHADOW) == 0u;
#endif
    if (untaken) {
        beyond = -1.0;
    }
    staged_reach[slot] = vec4<f32>(l.g.position, beyond);
    staged_geometry[slot] = l.g;
    staged_properties[slot] = l.props;
#if SHADOWS
    staged_index[slot] = l.index;
#endif
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
#if SHADOWS
                let index = staged_index[j];
#else
                let index = 0u; // read only by the shadow lookup
#endif
                color = add_reached(color, index, g, staged_properties[j], r, p, m);
            }
        }
    }
    return color;
}
#endif
