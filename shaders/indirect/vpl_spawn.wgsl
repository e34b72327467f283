// VplSpawn (Harada, McKee, Yang, "Forward+"; AMD's Leo demo): virtual point lights from the reflective shadow maps,
// appended after the scene's lights. Entry points, one dispatch each, in order:
//   copy:   the scene's lights into the light arrays the later passes read;
//   gather: one candidate per n×n block of each view: the block's summed flux at its
//           flux-weighted position and normal;
//   select: one workgroup: when more candidates have flux than there is room, the
//           exact flux threshold (a radix select over the luminance's float bits,
//           which order like integers for positive floats) and how many candidates at
//           the threshold stay;
//   append: every kept candidate takes a slot from the atomic light counter.
// The counter (control[0]) is then copied into the frame uniform's light count, so
// culling and shading see the VPLs without the CPU reading anything back.

#include "common/types.wgsl"

struct SpawnParams {
    scene_lights: u32,
    views: u32,
    candidates: u32,
    room: u32,
};

struct Candidate {
    position: vec3<f32>,
    // bitcast<u32>(luminance of the flux); 0: an empty block
    key: u32,
    normal: vec3<f32>,
    view: u32,
    flux: vec3<f32>,
    _pad: u32,
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
// 0 light count (atomic; starts at the scene's), 1 dropped, 2 threshold key,
// 3 kept at the threshold, 4 taken at the threshold (atomic), 5 candidates with flux
@group(0) @binding(10) var<storage, read_write> control: array<atomic<u32>, 8>;

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
    let origin = vec2<u32>(info.x + (id.x % n) * side, info.y + (id.x / n) * side);
    var flux = vec3<f32>(0.0);
    var position = vec3<f32>(0.0);
    var normal = vec3<f32>(0.0);
    var weight = 0.0;
    for (var y = 0u; y < side; y++) {
        for (var x = 0u; x < side; x++) {
            let t = origin + vec2<u32>(x, y);
            let f = textureLoad(rsm_flux, t, 0).rgb;
            let w = dot(f, LUMA);
            if (w > 0.0) {
                flux += f;
                weight += w;
                position += w * textureLoad(rsm_position, t, 0).xyz;
                normal += w * textureLoad(rsm_normal, t, 0).xyz;
            }
        }
    }
    var c: Candidate;
    c.flux = flux;
    c.view = v;
    c.key = 0u;
    if (weight > 0.0 && dot(normal, normal) > 0.0) {
        c.position = position / weight;
        c.normal = normalize(normal);
        c.key = bitcast<u32>(dot(flux, LUMA));
    }
    let first = bitcast<vec4<u32>>(rsm_views[vb + 7u]).w;
    candidates[first + id.x] = c;
}

var<workgroup> hist: array<atomic<u32>, 256>;
var<workgroup> with_flux: atomic<u32>;
var<workgroup> with_flux_total: u32;
var<workgroup> prefix: u32;
var<workgroup> want: u32;

@compute @workgroup_size(256)
fn select_room(@builtin(local_invocation_index) local: u32) {
    if (local == 0u) {
        atomicStore(&with_flux, 0u);
        prefix = 0u;
        atomicStore(&control[0], params.scene_lights);
        atomicStore(&control[1], 0u);
        atomicStore(&control[4], 0u);
    }
    workgroupBarrier();
    for (var c = local; c < params.candidates; c += 256u) {
        if (candidates[c].key != 0u) {
            atomicAdd(&with_flux, 1u);
        }
    }
    workgroupBarrier();
    if (local == 0u) {
        with_flux_total = atomicLoad(&with_flux);
    }
    let total = workgroupUniformLoad(&with_flux_total);
    if (total <= params.room) {
        // Everything fits: keep every key above 0.
        if (local == 0u) {
            atomicStore(&control[2], 0u);
            atomicStore(&control[3], 0u);
            atomicStore(&control[5], total);
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
            if (key != 0u && (key & high) == (p & high)) {
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
        atomicStore(&control[5], total);
    }
}

@compute @workgroup_size(64)
fn append(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.candidates) {
        return;
    }
    let c = candidates[id.x];
    if (c.key == 0u) {
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
    light_properties[i] = LightProperties(c.flux * (art.y / PI), art.w, LIGHT_VPL, mask, i - params.scene_lights, 0u);
}
