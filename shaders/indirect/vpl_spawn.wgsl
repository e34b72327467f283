// VplSpawn (Harada, McKee, Yang, "Forward+"; AMD's Leo demo): virtual point lights from the reflective shadow maps,
// appended after the scene's lights. Entry points, one dispatch each, in order:
//   copy:   the scene's lights into the light arrays the later passes read;
//   gather: one candidate per n×n block of each view: the block's summed flux at its
//           flux-weighted position and normal, and the surface area its texels cover;
//   merge:  (merge > 1) per group of merge×merge neighbouring candidates of a view: when
//           every member faces within merge_cos of the group's flux-weighted normal and
//           lies near its plane, the group becomes one candidate carrying the members'
//           summed flux and area;
//   select: one workgroup: the total flux; candidates under min_flux of it are
//           negligible; when more of the rest than there is room, the exact flux
//           threshold (a radix select over the luminance's float bits, which order like
//           integers for positive floats) and how many candidates at the threshold stay;
//   append: every kept candidate takes a slot from the atomic light counter.
// The counter (control[0]) is then copied into the frame uniform's light count, so
// culling and shading see the VPLs without the CPU reading anything back.

#include "common/types.wgsl"

struct SpawnParams {
    scene_lights: u32,
    views: u32,
    candidates: u32,
    room: u32,
    merge: u32,
    merge_cos: f32,
    min_flux: f32,
    // bit 0: redistribute the negligible flux; bit 1: the disc falloff; bit 2: the disc's
    // radius as the least clamp
    flags: u32,
};

const REDISTRIBUTE: u32 = 1u;
const DISC: u32 = 2u;
const AREA_CLAMP: u32 = 4u;

struct Candidate {
    position: vec3<f32>,
    // bitcast<u32>(luminance of the flux); 0: an empty block (or one merged away)
    key: u32,
    normal: vec3<f32>,
    view: u32,
    flux: vec3<f32>,
    // the surface area the candidate's texels cover
    area: f32,
    // 1: merged into another candidate of its group
    absorbed: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
};

@group(0) @binding(0) var<uniform> params: SpawnParams;
@group(0) @binding(1) var<storage, read> scene_light_geometry: array<LightGeometry>;
@group(0) @binding(2) var<storage, read> scene_light_properties: array<LightProperties>;
@group(0) @binding(3) var<storage, read_write> light_geometry: array<LightGeometry>;
@group(0) @binding(4) var<storage, read_write> light_properties: array<LightProperties>;
@group(0) @binding(5) var<storage, read> rsm_views: array<vec4<f32>>;
@group(0) @binding(6) var rsm_normal: texture_2d<f32>;
@group(0) @binding(7) var rsm_flux: texture_2d<f32>;
@group(0) @binding(8) var rsm_position: texture_2d<f32>;
@group(0) @binding(9) var<storage, read_write> candidates: array<Candidate>;
// 0 light count (atomic; starts at the scene's), 1 dropped for room, 2 threshold key,
// 3 kept at the threshold, 4 taken at the threshold (atomic), 5 candidates with flux,
// 6 the negligible key (keys at or under it are dropped), 7 negligible candidates,
// 8 their luminance (f32 bits), 9 every candidate's luminance (f32 bits), 10 the kept
// VPLs' flux scale (f32 bits), 11 candidates merged into another
@group(0) @binding(10) var<storage, read_write> control: array<atomic<u32>, 12>;

const VIEW_VEC4S: u32 = 8u;
const LIGHT_VPL: u32 = 4u;
const PI: f32 = 3.14159265358979;
const LUMA: vec3<f32> = vec3<f32>(0.2126, 0.7152, 0.0722);

@compute @workgroup_size(64)
fn copy(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i < params.scene_lights) {
        light_geometry[i] = scene_light_geometry[i];
        light_properties[i] = scene_light_properties[i];
    }
}

// x: block of the view (n² of them), y: view.
@compute @workgroup_size(64)
fn gather(@builtin(global_invocation_id) id: vec3<u32>) {
    let v = id.y;
    let vb = 1u + VIEW_VEC4S * v;
    let info = bitcast<vec4<u32>>(rsm_views[vb + 4u]);
    let n = info.w;
    if (v >= params.views || id.x >= n * n) {
        return;
    }
    let tile = bitcast<vec4<u32>>(rsm_views[0]).y;
    let side = tile / n;
    let texel_solid_angle = rsm_views[vb + 5u].x;
    let axis = rsm_views[vb + 7u].xyz;
    let light_position = scene_light_geometry[info.z].position;
    let origin = vec2<u32>(info.x + (id.x % n) * side, info.y + (id.x / n) * side);
    var flux = vec3<f32>(0.0);
    var position = vec3<f32>(0.0);
    var normal = vec3<f32>(0.0);
    var weight = 0.0;
    var area = 0.0;
    for (var y = 0u; y < side; y++) {
        for (var x = 0u; x < side; x++) {
            let t = origin + vec2<u32>(x, y);
            let f = textureLoad(rsm_flux, t, 0).rgb;
            let w = dot(f, LUMA);
            if (w > 0.0) {
                let p = textureLoad(rsm_position, t, 0).xyz;
                let nrm = textureLoad(rsm_normal, t, 0).xyz;
                flux += f;
                weight += w;
                position += w * p;
                normal += w * nrm;
                area += texel_area(p, nrm, light_position, axis, texel_solid_angle);
            }
        }
    }
    var c: Candidate;
    c.flux = flux;
    c.view = v;
    c.key = 0u;
    c.area = area;
    c.absorbed = 0u;
    if (weight > 0.0 && dot(normal, normal) > 0.0) {
        c.position = position / weight;
        c.normal = normalize(normal);
        c.key = bitcast<u32>(dot(flux, LUMA));
    }
    let first = bitcast<vec4<u32>>(rsm_views[vb + 7u]).w;
    candidates[first + id.x] = c;
}

// The surface area a map texel covers: its solid angle from the light (the square
// texel's, times cos³ off the view's axis) times d², over the cosine at the surface
// (the normal faces the light). Grazing texels are bounded at a cosine of 0.1.
fn texel_area(p: vec3<f32>, nrm: vec3<f32>, light: vec3<f32>, axis: vec3<f32>, solid_angle: f32) -> f32 {
    let d = p - light;
    let dist_sq = dot(d, d);
    let dir = d * inverseSqrt(max(dist_sq, 1e-30));
    let c = max(dot(axis, dir), 0.0);
    let facing = max(dot(nrm, -dir), 0.1);
    return solid_angle * c * c * c * dist_sq / facing;
}

// x: merge group of the view ((n / g)² of them, g = min(merge, n)), y: view.
@compute @workgroup_size(64)
fn merge(@builtin(global_invocation_id) id: vec3<u32>) {
    let v = id.y;
    let vb = 1u + VIEW_VEC4S * v;
    let n = bitcast<vec4<u32>>(rsm_views[vb + 4u]).w;
    let g = min(params.merge, n);
    let across = n / g;
    if (v >= params.views || id.x >= across * across) {
        return;
    }
    let first = bitcast<vec4<u32>>(rsm_views[vb + 7u]).w;
    let origin = first + (id.x / across) * g * n + (id.x % across) * g;
    var flux = vec3<f32>(0.0);
    var position = vec3<f32>(0.0);
    var normal = vec3<f32>(0.0);
    var weight = 0.0;
    var area = 0.0;
    var members = 0u;
    var leader = 0u;
    for (var y = 0u; y < g; y++) {
        for (var x = 0u; x < g; x++) {
            let i = origin + y * n + x;
            let c = candidates[i];
            if (c.key != 0u) {
                let w = bitcast<f32>(c.key);
                if (members == 0u) {
                    leader = i;
                }
                members += 1u;
                flux += c.flux;
                weight += w;
                position += w * c.position;
                normal += w * c.normal;
                area += c.area;
            }
        }
    }
    if (members < 2u || dot(normal, normal) <= 0.0) {
        return;
    }
    let mean = normalize(normal);
    let centre = position / weight;
    // Members must also lie near the group's plane: within the group's disc radius times
    // the tangent of the normals' bound, so parallel surfaces at different depths (a
    // floor seen past a ledge) do not merge into a point between them.
    let cos_bound = max(params.merge_cos, 0.01);
    let depth_bound = sqrt(area / PI) * sqrt(max(1.0 - cos_bound * cos_bound, 0.0)) / cos_bound;
    for (var y = 0u; y < g; y++) {
        for (var x = 0u; x < g; x++) {
            let c = candidates[origin + y * n + x];
            if (c.key != 0u && (dot(c.normal, mean) < params.merge_cos || abs(dot(c.position - centre, mean)) > depth_bound)) {
                return;
            }
        }
    }
    for (var y = 0u; y < g; y++) {
        for (var x = 0u; x < g; x++) {
            let i = origin + y * n + x;
            if (i != leader && candidates[i].key != 0u) {
                candidates[i].key = 0u;
                candidates[i].absorbed = 1u;
            }
        }
    }
    candidates[leader].flux = flux;
    candidates[leader].position = centre;
    candidates[leader].normal = mean;
    candidates[leader].area = area;
    candidates[leader].key = bitcast<u32>(dot(flux, LUMA));
}

var<workgroup> hist: array<atomic<u32>, 256>;
var<workgroup> partial: array<f32, 256>;
var<workgroup> with_flux: atomic<u32>;
var<workgroup> with_flux_total: u32;
var<workgroup> negligible: atomic<u32>;
var<workgroup> negligible_total: u32;
var<workgroup> absorbed: atomic<u32>;
var<workgroup> prefix: u32;
var<workgroup> want: u32;

// The workgroup's sum of one value a thread (a tree in `partial`; every thread gets it).
fn workgroup_sum(local: u32, value: f32) -> f32 {
    workgroupBarrier();
    partial[local] = value;
    workgroupBarrier();
    for (var stride = 128u; stride > 0u; stride = stride >> 1u) {
        if (local < stride) {
            partial[local] += partial[local + stride];
        }
        workgroupBarrier();
    }
    return workgroupUniformLoad(&partial[0]);
}

@compute @workgroup_size(256)
fn select_room(@builtin(local_invocation_index) local: u32) {
    if (local == 0u) {
        atomicStore(&with_flux, 0u);
        atomicStore(&negligible, 0u);
        atomicStore(&absorbed, 0u);
        prefix = 0u;
        atomicStore(&control[0], params.scene_lights);
        atomicStore(&control[1], 0u);
        atomicStore(&control[4], 0u);
    }
    workgroupBarrier();
    var own = 0.0;
    for (var c = local; c < params.candidates; c += 256u) {
        let key = candidates[c].key;
        if (key != 0u) {
            atomicAdd(&with_flux, 1u);
            own += bitcast<f32>(key);
        }
        if (candidates[c].absorbed != 0u) {
            atomicAdd(&absorbed, 1u);
        }
    }
    let total_flux = workgroup_sum(local, own);
    // Keys at or under `floor_key` are negligible (none while min_flux is 0).
    var floor_key = 0u;
    if (params.min_flux > 0.0) {
        floor_key = bitcast<u32>(params.min_flux * total_flux);
    }
    var dropped_flux = 0.0;
    for (var c = local; c < params.candidates; c += 256u) {
        let key = candidates[c].key;
        if (key != 0u && key <= floor_key) {
            atomicAdd(&negligible, 1u);
            dropped_flux += bitcast<f32>(key);
        }
    }
    let negligible_flux = workgroup_sum(local, dropped_flux);
    if (local == 0u) {
        with_flux_total = atomicLoad(&with_flux);
        negligible_total = atomicLoad(&negligible);
        var scale = 1.0;
        if ((params.flags & REDISTRIBUTE) != 0u && total_flux > negligible_flux) {
            scale = total_flux / (total_flux - negligible_flux);
        }
        atomicStore(&control[5], with_flux_total);
        atomicStore(&control[6], floor_key);
        atomicStore(&control[7], negligible_total);
        atomicStore(&control[8], bitcast<u32>(negligible_flux));
        atomicStore(&control[9], bitcast<u32>(total_flux));
        atomicStore(&control[10], bitcast<u32>(scale));
        atomicStore(&control[11], atomicLoad(&absorbed));
    }
    let eligible = workgroupUniformLoad(&with_flux_total) - workgroupUniformLoad(&negligible_total);
    if (eligible <= params.room) {
        // Everything left fits: keep every key above the negligible one.
        if (local == 0u) {
            atomicStore(&control[2], floor_key);
            atomicStore(&control[3], 0u);
        }
        return;
    }
    if (local == 0u) {
        want = params.room;
    }
    // Four 8-bit digits from the top: the digit where the count from above reaches
    // `want`, then the same within that digit.
    for (var round = 0u; round < 4u; round++) {
        let shift = 24u - 8u * round;
        atomicStore(&hist[local], 0u);
        workgroupBarrier();
        let high = select(0u, 0xffffffffu << (shift + 8u), round > 0u);
        let p = workgroupUniformLoad(&prefix);
        for (var c = local; c < params.candidates; c += 256u) {
            let key = candidates[c].key;
            if (key > floor_key && (key & high) == (p & high)) {
                atomicAdd(&hist[(key >> shift) & 0xffu], 1u);
            }
        }
        workgroupBarrier();
        if (local == 0u) {
            var above = 0u;
            for (var d = 255i; d >= 0i; d--) {
                let h = atomicLoad(&hist[u32(d)]);
                if (above + h >= want) {
                    prefix = prefix | (u32(d) << shift);
                    want = want - above;
                    break;
                }
                above += h;
            }
        }
        workgroupBarrier();
    }
    if (local == 0u) {
        atomicStore(&control[2], prefix);
        atomicStore(&control[3], want);
    }
}

@compute @workgroup_size(64)
fn append(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.candidates) {
        return;
    }
    let c = candidates[id.x];
    // Empty, merged away, or negligible (counted by select_room).
    if (c.key <= atomicLoad(&control[6])) {
        return;
    }
    let threshold = atomicLoad(&control[2]);
    var keep = c.key > threshold;
    if (!keep && c.key == threshold) {
        keep = atomicAdd(&control[4], 1u) < atomicLoad(&control[3]);
    }
    if (!keep) {
        atomicAdd(&control[1], 1u);
        return;
    }
    let i = atomicAdd(&control[0], 1u);
    let vb = 1u + VIEW_VEC4S * c.view;
    let art = rsm_views[vb + 5u];
    let mask = bitcast<u32>(rsm_views[vb + 6u].w);
    // A Lambertian emitter of the block's flux: intensity Φ/π along its normal.
    light_geometry[i] = LightGeometry(c.position, art.z, c.normal, 0.0);
    // _pad0: the VPL's number among the VPLs, its bit in a VplVisibility pass's masks.
    let scale = bitcast<f32>(atomicLoad(&control[10]));
    var disc_sq = 0.0;
    var clamp = art.w;
    if ((params.flags & DISC) != 0u) {
        disc_sq = c.area / PI;
    }
    if ((params.flags & AREA_CLAMP) != 0u) {
        clamp = max(clamp, sqrt(c.area / PI));
    }
    light_properties[i] = LightProperties(c.flux * (scale * art.y / PI), clamp, LIGHT_VPL, mask, i - params.scene_lights, disc_sq);
}
