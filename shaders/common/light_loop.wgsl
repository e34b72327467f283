// The light loop: radiance leaving a surface towards the eye, from every light its list
// (or all lights) names. Included after the material code by the forward fragment
// shader and by the deferred compute shader, so both shade with the same code.
// `pixel` is the framebuffer position, `view_z` the positive view-space depth.
fn shade_surface(p: ShadingPoint, m: MaterialSample, pixel: vec2<f32>, view_z: f32) -> vec3<f32> {
    var color = material_emission(m) + frame.ambient.rgb * material_eval(m, p.normal);
    let range = light_range(pixel, view_z);
    for (var k = 0u; k < range.count; k++) {
        let i = light_at(range, k);
        let props = light_properties[i];
        if ((props.material_mask & MATERIAL_TYPE_BIT) == 0u) {
            continue;
        }
        let inc = incident_light(light_geometry[i], props, p.position);
        if (any(inc.radiance > vec3<f32>(0.0))) {
            color += inc.radiance * material_eval(m, inc.dir);
        }
    }
    return color;
}
