// Punctual light attenuation (KHR_lights_punctual): the range window reaches exactly
// zero at the range, so a culled light contributes nothing.

// Distances below 1 cm are clamped so a surface at a light's centre stays finite.
const MIN_DISTANCE_SQ: f32 = 1e-4;

fn range_window(dist_sq: f32, range: f32) -> f32 {
    let r = dist_sq / (range * range);
    return clamp(1.0 - r * r, 0.0, 1.0);
}

fn spot_factor(g: LightGeometry, p: LightProperties, to_light_dir: vec3<f32>) -> f32 {
    if (g.cos_outer <= -1.0) {
        return 1.0;
    }
    let cd = dot(g.direction, -to_light_dir);
    let scale = 1.0 / max(0.001, p.cos_inner - g.cos_outer);
    let a = clamp((cd - g.cos_outer) * scale, 0.0, 1.0);
    return a * a;
}

// Radiance arriving at `pos` from light i, and the unit direction towards it.
struct Incident {
    radiance: vec3<f32>,
    dir: vec3<f32>,
};

fn incident_light(g: LightGeometry, p: LightProperties, pos: vec3<f32>) -> Incident {
    let d = g.position - pos;
    let dist_sq = dot(d, d);
    var out: Incident;
    out.dir = d * inverseSqrt(max(dist_sq, 1e-30));
    let window = range_window(dist_sq, g.range);
    if (window <= 0.0) {
        out.radiance = vec3<f32>(0.0);
        return out;
    }
    if ((p.flags & LIGHT_VPL) != 0u) {
        let lobe = max(dot(g.direction, -out.dir), 0.0);
        out.radiance = p.color * (lobe * window / max(dist_sq, p.cos_inner * p.cos_inner));
        return out;
    }
    let falloff = window / max(dist_sq, MIN_DISTANCE_SQ);
    out.radiance = p.color * (falloff * spot_factor(g, p, out.dir));
    return out;
}

// A virtual point light (VplSpawn): a cosine-weighted hemisphere about `direction`
// (the surface it sits on emits like a Lambertian patch); `cos_inner` holds its distance
// clamp, below which 1/d² stops growing; culled as a 90° spot light.
const LIGHT_VPL: u32 = 4u;
