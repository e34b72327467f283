// Deferred shading of a multisampled G-buffer: deferred_shading.wgsl's main when
// G_SAMPLES is the sample count. The pixel's output is the mean of its samples' colours,
// what msaa/resolve.wgsl takes after MSAA forward shading, with each distinct sample
// shaded once.
//
// Distinct: the G-buffer draw runs once per pixel and triangle at the centroid of the
// covered samples (as MSAA forward shading does), so the samples one triangle covers hold
// the same texels, and a sample whose position, normal and surface texels equal an
// earlier sample's, bit for bit, takes that sample's colour: shading is a function of
// those texels (the material index is the position's w) and the pixel alone. A pixel
// whose samples are all alike (Lauritzen's edge test) is shaded once, an edge pixel once
// per surface in it.
// The samples a workgroup must shade are pooled and shared out over its invocations
// (Lauritzen's repacking), so an edge pixel does not keep its neighbours waiting.
//
// Exact: the sum adds each sample's colour in sample order, starting from 0, as the
// resolve does (an empty sample adds 0 there, nothing here). A pixel whose samples hold
// several materials is summed over their dispatches in material order: each adds its own
// samples onto the previous materials' partial sum, read back from `hdr`, and the last
// divides. Those are the same terms regrouped by material: at most n-1 roundings apart.

const SAMPLES: u32 = u32(G_SAMPLES);
// Invocations of the 8×8 workgroup, one per pixel.
const GROUP: u32 = 64u;
// Samples shaded per round: every distinct sample of the workgroup's pixels at 4×, half
// of them at most at 8×.
const POOL: u32 = 256u;

// Jobs reserved by the invocations (each a contiguous range), and their total.
var<workgroup> job_count: atomic<u32>;
var<workgroup> job_total: u32;
// This round's jobs: the pixel's local index << 8 | sample, and the colours shaded.
var<workgroup> pool_job: array<u32, POOL>;
var<workgroup> pool_color: array<vec4<f32>, POOL>;

// Whether samples `a` and `b` of pixel `p` hold the same surface point (bits, so -0 and
// +0 differ, as the shading might).
fn same_surface(p: vec2<u32>, a: u32, b: u32) -> bool {
    let pa = bitcast<vec4<u32>>(textureLoad(g_position, p, a));
    let pb = bitcast<vec4<u32>>(textureLoad(g_position, p, b));
    let na = bitcast<vec4<u32>>(textureLoad(g_normal, p, a));
    let nb = bitcast<vec4<u32>>(textureLoad(g_normal, p, b));
#if G_SURFACE
    let sa = bitcast<vec4<u32>>(textureLoad(g_surface, p, a));
    let sb = bitcast<vec4<u32>>(textureLoad(g_surface, p, b));
    let da = bitcast<vec4<u32>>(textureLoad(g_uv_grad, p, a));
    let db = bitcast<vec4<u32>>(textureLoad(g_uv_grad, p, b));
#if G_UV1
    let ua = bitcast<vec4<u32>>(textureLoad(g_uv1, p, a));
    let ub = bitcast<vec4<u32>>(textureLoad(g_uv1, p, b));
    let ea = bitcast<vec4<u32>>(textureLoad(g_uv1_grad, p, a));
    let eb = bitcast<vec4<u32>>(textureLoad(g_uv1_grad, p, b));
    if (any(ua != ub) || any(ea != eb)) {
        return false;
    }
#endif
    return all(pa == pb) && all(na == nb) && all(sa == sb) && all(da == db);
#else
    return all(pa == pb) && all(na == nb);
#endif
}

// The colour and alpha of sample `s` of pixel `p` (the single-sample main's arithmetic).
fn shade_sample(p: vec2<u32>, s: u32) -> vec4<f32> {
    let g = textureLoad(g_position, p, s);
    var q: ShadingPoint;
    q.position = g.xyz;
    q.normal = textureLoad(g_normal, p, s).xyz;
    q.view = normalize(frame.camera_pos.xyz - q.position);
    load_surface(&q, p, s);
    let m = material_setup(q);
    let view_z = -(frame.view * vec4<f32>(q.position, 1.0)).z;
    let pixel = vec2<f32>(p) + 0.5;
    return vec4<f32>(shade_surface(q, m, pixel, view_z), material_alpha(m));
}

@compute @workgroup_size(8, 8, 1)
fn main(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) group: vec3<u32>,
) {
    let p = id.xy;
    let inside = all(p < frame.size);
    // This material's samples (bit s); whether other materials' samples come before it
    // (a partial sum to read) or after it (the mean is theirs to store).
    var mine = 0u;
    var earlier = false;
    var later = false;
    // rep[s]: the first sample with sample s's texels; `shaded`: samples that are their
    // own representative (bit s), the jobs this pixel posts.
    var rep: array<u32, SAMPLES>;
    var shaded = 0u;
    if (inside) {
        for (var s = 0u; s < SAMPLES; s++) {
            let here = i32(round(textureLoad(g_position, p, s).w));
            if (here == MATERIAL_INDEX) {
                mine |= 1u << s;
            } else if (here >= 0) {
                earlier = earlier || here < MATERIAL_INDEX;
                later = later || here > MATERIAL_INDEX;
            }
        }
    }
    if (mine != 0u) {
        var alike = true;
        for (var s = 1u; s < SAMPLES; s++) {
            if (!same_surface(p, 0u, s)) {
                alike = false;
                break;
            }
        }
        for (var s = 0u; s < SAMPLES; s++) {
            rep[s] = s;
            if ((mine & (1u << s)) == 0u) {
                continue;
            }
            if (alike) {
                rep[s] = 0u;
            } else {
                for (var t = 0u; t < s; t++) {
                    if ((shaded & (1u << t)) != 0u && same_surface(p, t, s)) {
                        rep[s] = t;
                        break;
                    }
                }
            }
            if (rep[s] == s) {
                shaded |= 1u << s;
            }
        }
    }

    // Reserve this pixel's jobs: [base, base + count) of the workgroup's list.
    let count = countOneBits(shaded);
    var base = 0u;
    if (count > 0u) {
        base = atomicAdd(&job_count, count);
    }
    workgroupBarrier();
    if (local == 0u) {
        job_total = atomicLoad(&job_count);
    }
    let total = workgroupUniformLoad(&job_total);

    // Shade the list POOL jobs a round, every invocation taking every GROUP-th job.
    var colors: array<vec4<f32>, SAMPLES>;
    for (var start = 0u; start < total; start += POOL) {
        var k = base;
        for (var s = 0u; s < SAMPLES; s++) {
            if ((shaded & (1u << s)) != 0u) {
                if (k >= start && k < start + POOL) {
                    pool_job[k - start] = (local << 8u) | s;
                }
                k++;
            }
        }
        workgroupBarrier();
        let jobs = min(total - start, POOL);
        for (var j = local; j < jobs; j += GROUP) {
            let job = pool_job[j];
            let l = job >> 8u;
            let q = group.xy * 8u + vec2<u32>(l % 8u, l / 8u);
            pool_color[j] = shade_sample(q, job & 0xffu);
        }
        workgroupBarrier();
        k = base;
        for (var s = 0u; s < SAMPLES; s++) {
            if ((shaded & (1u << s)) != 0u) {
                if (k >= start && k < start + POOL) {
                    colors[s] = pool_color[k - start];
                }
                k++;
            }
        }
        // The next round overwrites the pool.
        workgroupBarrier();
    }

    if (!inside) {
        return;
    }
    if (mine == 0u) {
        // Nothing drawn at any sample: the first material's dispatch clears the pixel.
        if (MATERIAL_INDEX == 0 && !earlier && !later) {
            textureStore(hdr, p, vec4<f32>(0.0));
        }
        return;
    }
    var sum = vec4<f32>(0.0);
    if (earlier) {
        sum = textureLoad(hdr, p);
    }
    for (var s = 0u; s < SAMPLES; s++) {
        if ((mine & (1u << s)) != 0u) {
            sum += colors[rep[s]];
        }
    }
    if (!later) {
        sum = sum / f32(SAMPLES);
    }
    textureStore(hdr, p, sum);
}
