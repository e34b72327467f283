// Punctual light attenuation (KHR_lights_punctual): the range window reaches exactly
// zero at the range, so a culled light contributes nothing.

// Distances below 1 cm are clamped so a surface at a light's centre stays finite.
const MIN_DISTANCE_SQ: f32 = 1e-4;

fn range_window(dist_sq: f32, range: f32) -> f32 {
    let r = dist_sq / (range * range);
    return clamp(1.0 - r * r, 0.0, 1.0);
}

// A squared distance past which range_window is surely zero: dist_sq over
// fl(range²)·1.001 rounded down is over range² by 1e-3 at least, so the quotient r in
// range_window, within 2.5 ulp (Vulkan's OpFDiv), is over 1, r² rounds to 1 or more, and
// 1 − r² clamps to 0, fused or not. A NaN or infinite range rejects nothing here; the
// exact test after it decides.
fn reject_beyond(range: f32) -> f32 {
    return range * range * 1.001;
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
    // The light's angular radius squared as seen from `pos`: a VPL's disc (`disc_sq` over
    // the squared distance); 0 for a point.
    spread: f32,
};

// How far a light reaches a point: the vector to the light, its squared length, and the
// range window there (zero at and past the range).
struct LightReach {
    to_light: vec3<f32>,
    dist_sq: f32,
    window: f32,
};

fn light_reach(g: LightGeometry, pos: vec3<f32>) -> LightReach {
    let d = g.position - pos;
    let dist_sq = dot(d, d);
    return LightReach(d, dist_sq, range_window(dist_sq, g.range));
}

// `incident_light` from a reach computed before: radiance is exactly zero where
// `r.window <= 0.0`, so a loop that tests the window first (before reading p) and skips
// those lights skips only lights that add nothing.
fn incident_reached(g: LightGeometry, p: LightProperties, r: LightReach) -> Incident {
    var out: Incident;
    out.dir = r.to_light * inverseSqrt(max(r.dist_sq, 1e-30));
    if (r.window <= 0.0) {
        out.radiance = vec3<f32>(0.0);
        return out;
    }
    if ((p.flags & LIGHT_VPL) != 0u) {
        let lobe = max(dot(g.direction, -out.dir), 0.0);
        out.radiance = p.color * (lobe * r.window / max(r.dist_sq + p.disc_sq, p.cos_inner * p.cos_inner));
        out.spread = p.disc_sq / max(r.dist_sq, MIN_DISTANCE_SQ);
        return out;
    }
    let falloff = r.window / max(r.dist_sq, MIN_DISTANCE_SQ);
    out.radiance = p.color * (falloff * spot_factor(g, p, out.dir));
    return out;
}

fn incident_light(g: LightGeometry, p: LightProperties, pos: vec3<f32>) -> Incident {
    return incident_reached(g, p, light_reach(g, pos));
}

// A virtual point light (VplSpawn): a cosine-weighted hemisphere about `direction`
// (the surface it sits on emits like a Lambertian patch); `cos_inner` holds its distance
// clamp, below which 1/d² stops growing, and `disc_sq` the squared radius of the disc it
// stands for (1/d² becomes 1/(d² + r²), a disc's on-axis falloff); culled as a 90° spot
// light.
const LIGHT_VPL: u32 = 4u;
