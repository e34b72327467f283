// The light loop: radiance leaving a surface towards the eye, from every light its list
// (or all lights) names. Included after the material code by the forward fragment
// shader and by the deferred compute shader, so both shade with the same code.
// `pixel` is the framebuffer position, `view_z` the positive view-space depth.

#include "common/shading_point.wgsl"

// Light arriving as `inc`, reflected towards the eye. A light seen as a disc of angular
// radius θ (a VPL, `inc.spread` = θ²) reflects through glossy lobes widened to take it
// in: directions spread over the disc spread half vectors over radius θ/2, whose slope
// variance (θ/2)²/4 per axis adds to the lobe's α²/2, so α² grows by θ²/8 (measured
// against the path-traced bounce in docs/indirect_light.md).
// One material_eval call site either way: the loop's code grows by the widening only.
// NO_VPLS (a scene without indirect lights) leaves the widening out: its code slowed the
// loops of frames that never take it by 2-5%.
fn reflect_incident(m: MaterialSample, inc: Incident) -> vec3<f32> {
    var lobes = m;
#if NO_VPLS
#else
    if (inc.spread > 0.0) {
        lobes = material_widened(m, inc.spread * 0.125);
    }
#endif
    return material_eval(lobes, inc.dir);
}

fn shade_surface(p: ShadingPoint, m: MaterialSample, pixel: vec2<f32>, view_z: f32) -> vec3<f32> {
    var color = material_emission(m) + frame.ambient.rgb * material_eval(m, p.normal);
#if VPL_VISIBILITY
    vpl_select(vec2<u32>(pixel), p.position, p.normal);
#endif
#if SHADOWS
    // Casters are numbered before the material mask is applied, as job creation does.
    var caster = 0u;
    let pixel_index = u32(pixel.y) * frame.size.x + u32(pixel.x);
#endif
#if LIGHT_SAMPLES
    let sample_pixel = u32(pixel.y) * frame.size.x + u32(pixel.x);
#endif
#if SAMPLED_ONLY
    // Every light casts (the scene has no other, and no VPLs): the exact lights and the
    // samples after the loop stand for all of them, so the list is not walked.
#else
    for (var c = light_first(pixel, view_z); light_valid(c); c = light_next(c, view_z)) {
        let i = light_index(c);
        // Out of range adds nothing (and numbers no caster): rejected before the light's
        // properties are read (the gallery's glass at 65,536 lights, H100: transparent
        // shading 0.644 -> 0.575 ms).
        let reach = light_geometry[i].position - p.position;
        if (dot(reach, reach) > reject_beyond(light_geometry[i].range)) {
            continue;
        }
        let props = light_properties[i];
#if VPL_VISIBILITY
        // A VPL hidden from this pixel's block (VplVisibility) adds nothing; VPLs cast no
        // shadow, so skipping one changes no caster number.
        if (!vpl_visible(props)) {
            continue;
        }
#endif
#if LIGHT_SAMPLES
        // A shadow-casting light is one of the pixel's exact lights or left to the
        // samples: both are added after the loop.
        if ((props.flags & LIGHT_CASTS_SHADOW) != 0u) {
            continue;
        }
        if ((props.material_mask & MATERIAL_TYPE_BIT) == 0u) {
            continue;
        }
        let inc = incident_light(light_geometry[i], props, p.position);
        if (any(inc.radiance > vec3<f32>(0.0))) {
            color += inc.radiance * reflect_incident(m, inc);
        }
#else
#if SHADOWS
        let g = light_geometry[i];
        let inc = incident_light(g, props, p.position);
        var visibility = select(0.0, 1.0, any(inc.radiance > vec3<f32>(0.0)));
        if (visibility > 0.0 && (props.flags & LIGHT_CASTS_SHADOW) != 0u) {
            visibility = shadow_visibility(pixel_index, caster, i, g.position, p);
            caster += 1u;
        }
        if (visibility > 0.0 && (props.material_mask & MATERIAL_TYPE_BIT) != 0u) {
            color += (visibility * inc.radiance) * reflect_incident(m, inc);
        }
#else
        if ((props.material_mask & MATERIAL_TYPE_BIT) == 0u) {
            continue;
        }
        let inc = incident_light(light_geometry[i], props, p.position);
        if (any(inc.radiance > vec3<f32>(0.0))) {
            color += inc.radiance * reflect_incident(m, inc);
        }
#endif
#endif
    }
#endif
#if LIGHT_SAMPLES
    color += exact_light(sample_pixel, p, m) + sampled_light(sample_pixel, p, m);
#endif
    return color;
}

#if LIGHT_SAMPLES
// The flag of common/shadows.wgsl, which this loop does not include.
const LIGHT_CASTS_SHADOW: u32 = 1u;

// The pixel's exact lights whose rays reached them, unshadowed (SAMPLE_NONE has the
// hidden bit too: light indices stay under 2^31).
fn exact_light(pixel: u32, p: ShadingPoint, m: MaterialSample) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    for (var j = 0u; j < SAMPLE_EXACT; j++) {
        let light = light_samples[exact_word(pixel, j)];
        if ((light & SAMPLE_HIDDEN) != 0u) {
            continue;
        }
        let props = light_properties[light];
        if ((props.material_mask & MATERIAL_TYPE_BIT) == 0u) {
            continue;
        }
        let inc = incident_light(light_geometry[light], props, p.position);
        if (any(inc.radiance > vec3<f32>(0.0))) {
            sum += inc.radiance * reflect_incident(m, inc);
        }
    }
    return sum;
}

// The sampled estimate of the other shadow-casting lights: each reservoir's light times
// its contribution weight (zero when its ray was blocked), averaged over the reservoirs.
fn sampled_light(pixel: u32, p: ShadingPoint, m: MaterialSample) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    for (var j = 0u; j < SAMPLE_COUNT; j++) {
        let base = reservoir_word(SAMPLE_REGION, pixel, j);
        let light = light_samples[base];
        let weight = bitcast<f32>(light_samples[base + 1u]);
        if (light == SAMPLE_NONE || !(weight > 0.0)) {
            continue;
        }
        let props = light_properties[light];
        if ((props.material_mask & MATERIAL_TYPE_BIT) == 0u) {
            continue;
        }
        let inc = incident_light(light_geometry[light], props, p.position);
        sum += (weight * inc.radiance) * reflect_incident(m, inc);
    }
    return sum / f32(SAMPLE_COUNT);
}
#endif
