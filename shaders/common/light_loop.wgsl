// The light loop: radiance leaving a surface towards the eye, from every light its list
// (or all lights) names. Included after the material code by the forward fragment
// shader and by the deferred compute shader, so both shade with the same code.
// `pixel` is the framebuffer position, `view_z` the positive view-space depth.

#include "common/shading_point.wgsl"

fn shade_surface(p: ShadingPoint, m: MaterialSample, pixel: vec2<f32>, view_z: f32) -> vec3<f32> {
    var color = material_emission(m) + frame.ambient.rgb * material_eval(m, p.normal);
#if VPL_VISIBILITY
    vpl_pixel = vec2<u32>(pixel);
#endif
#if SHADOWS
    // Casters are numbered before the material mask is applied, as job creation does.
    var caster = 0u;
    let pixel_index = u32(pixel.y) * frame.size.x + u32(pixel.x);
#endif
    for (var c = light_first(pixel, view_z); light_valid(c); c = light_next(c, view_z)) {
        let i = light_index(c);
        let props = light_properties[i];
#if VPL_VISIBILITY
        // A VPL hidden from this pixel's block (VplVisibility) adds nothing; VPLs cast no
        // shadow, so skipping one changes no caster number.
        if (!vpl_visible(props)) {
            continue;
        }
#endif
#if SHADOWS
        let g = light_geometry[i];
        let inc = incident_light(g, props, p.position);
        var visibility = select(0.0, 1.0, any(inc.radiance > vec3<f32>(0.0)));
        if (visibility > 0.0 && (props.flags & LIGHT_CASTS_SHADOW) != 0u) {
            visibility = shadow_visibility(pixel_index, caster, i, g.position, p);
            caster += 1u;
        }
        if (visibility > 0.0 && (props.material_mask & MATERIAL_TYPE_BIT) != 0u) {
            color += (visibility * inc.radiance) * material_eval(m, inc.dir);
        }
#else
        if ((props.material_mask & MATERIAL_TYPE_BIT) == 0u) {
            continue;
        }
        let inc = incident_light(light_geometry[i], props, p.position);
        if (any(inc.radiance > vec3<f32>(0.0))) {
            color += inc.radiance * material_eval(m, inc.dir);
        }
#endif
    }
    return color;
}
