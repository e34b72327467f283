// What a texel of an indirect light's reflective shadow map holds (Dachsbacher,
// Stamminger, "Reflective Shadow Maps"): the flux the light sends through the texel
// (intensity × its solid angle, whatever the surface's slope), times the diffuse albedo,
// and the normal turned to face the light. One function for both rasterizers of
// ReflectiveShadowMaps: the hardware pass's fragment stage (forward/forward.wgsl,
// fs_rsm) and the compute pass's resolve (indirect/rsm_raster.wgsl), so both store the
// same expression. Needs `rsm_views`, `light_geometry`, `light_properties` and the
// material code in the module.

// vec4 words of a view in the table (src/indirect/rsm_views.rs).
const RSM_VIEW_VEC4S: u32 = 8u;

struct RsmTexel {
    normal: vec3<f32>,
    flux: vec3<f32>,
    // The material's alpha (its cut-out test is the caller's).
    alpha: f32,
};

// The texel of view `view` that `surface` fills (its `view` is replaced by the direction
// to the light).
fn rsm_texel(surface: ShadingPoint, view: u32) -> RsmTexel {
    let b = 1u + RSM_VIEW_VEC4S * view;
    let info = bitcast<vec4<u32>>(rsm_views[b + 4u]);
    let texel_solid_angle = rsm_views[b + 5u].x;
    let axis = rsm_views[b + 7u].xyz;
    let g = light_geometry[info.z];
    var p = surface;
    let to_light = g.position - p.position;
    if (dot(p.normal, to_light) < 0.0) {
        p.normal = -p.normal;
    }
    p.view = normalize(to_light);
    let m = material_setup(p);
    let props = light_properties[info.z];
    var inc = incident_light(g, props, p.position);
    // A surface the light does not light reflects none of it.
    if ((props.material_mask & MATERIAL_TYPE_BIT) == 0u) {
        inc.radiance = vec3<f32>(0.0);
    }
    let dist_sq = dot(to_light, to_light);
    let c = max(dot(axis, -inc.dir), 0.0);
    let flux = material_diffuse(m) * inc.radiance * (dist_sq * texel_solid_angle * c * c * c);
    return RsmTexel(p.normal, flux, material_alpha(m));
}
