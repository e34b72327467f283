// Light culling's coarse stage (COARSE > 1) and its wide stage (WIDE_STAGE, WIDE_PASS):
// lights culled against coarse (wide) tiles before the tiles test them. Included by
// cull/light_culling.wgsl, whose bindings, defines and workgroup memory it uses.

// The coarse stage: one workgroup per coarse tile of COARSE×COARSE tiles; each
// invocation folds COARSE_FOLD × COARSE_FOLD pixels into its part of the depth range. No depth mask:
// every fine tile applies its own. Lights are taken a chunk of COARSE_CHUNK at a time:
// every invocation tests one light a step and sets the hits' bits in workgroup memory,
// with no barrier inside the chunk (per-batch ranks cost two barriers and a dozen
// workgroup loads a batch, which bound this stage at high light counts); then each
// invocation counts the bits of its own run of words, a prefix sum over the invocations
// places the runs, and each writes its hits in ascending light order.
@compute @workgroup_size(COARSE_SIDE, COARSE_SIDE, 1)
fn coarse(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(local_invocation_id) lid: vec3<u32>,
) {
    // Ordered before the first chunk's bits by the depth range's barriers (the wide
    // pass's by the barrier below).
    for (var k = 0u; k < COARSE_WORDS_PER_THREAD; k++) {
        atomicStore(&coarse_hits[local * COARSE_WORDS_PER_THREAD + k], 0u);
    }
    let coarse_x = (list_params.tiles_x + COARSE - 1u) / COARSE;
#if WIDE_PASS
    // A wide tile: its whole frustum between the depths 0 and 1 (no depth read; every
    // range a tile or coarse tile takes lies within it), every light a candidate.
    let span = TILE * COARSE * WIDE;
    let origin = group.xy * span;
    let lo = view_depth(0.0);
    let hi = view_depth(1.0);
    let empty = false;
    let bounds = tile_bounds(origin, span, lo, hi, false);
    let wide_x = (coarse_x + WIDE - 1u) / WIDE;
    let base_word = (group.y * wide_x + group.x) * WIDE_STRIDE;
    let capacity = WIDE_CAPACITY;
    let count = frame.light_count;
    workgroupBarrier();
#else
    let span = TILE * COARSE;
    let origin = group.xy * span;
    let range = workgroup_depth_range(local, COARSE_SIDE, block_depth_range(origin + lid.xy * COARSE_FOLD, COARSE_FOLD));
    let lo = bitcast<f32>(range.x);
    let hi = bitcast<f32>(range.y);
    let empty = range.y == 0u;
    let bounds = tile_bounds(origin, span, lo, hi, empty);
    let base_word = (group.y * coarse_x + group.x) * COARSE_STRIDE;
    let capacity = COARSE_CAPACITY;
#if WIDE_STAGE
    // The candidates: the wide tile's lights where they fit its list.
    let wide_x = (coarse_x + WIDE - 1u) / WIDE;
    wide_base = ((group.y / WIDE) * wide_x + group.x / WIDE) * WIDE_STRIDE;
    if (local == 0u) {
        wide_count = wide_lists[wide_base];
    }
    let listed = workgroupUniformLoad(&wide_count);
    from_wide = listed <= WIDE_CAPACITY;
    let count = select(frame.light_count, listed, from_wide);
#else
    let count = frame.light_count;
#endif
#endif

    var total = 0u;
    // Each step's sphere is loaded a step ahead (COARSE_CHUNK is a multiple of THREADS,
    // so the next step is the same invocation's next candidate across chunks too).
    var next_light = coarse_candidate(local, count);
    var next_sphere = stage_sphere(next_light);
    for (var chunk = 0u; chunk < count; chunk += COARSE_CHUNK) {
        let end = min(count, chunk + COARSE_CHUNK);
        if (!empty) {
            for (var i = chunk + local; i < end; i += THREADS) {
                let light = next_light;
                let sphere = next_sphere;
                if (i + THREADS < count) {
                    next_light = coarse_candidate(i + THREADS, count);
                    next_sphere = stage_sphere(next_light);
                }
                // An all-ones mask: the depth-mask test passes here.
                if (light_touches_tile(light, sphere, bounds, lo, hi, 0xffffffffu, lo, hi, STAGE_REACH)) {
                    let bit = i - chunk;
                    atomicOr(&coarse_hits[bit / 32u], 1u << (bit % 32u));
                }
            }
        }
        workgroupBarrier();
        let first_word = local * COARSE_WORDS_PER_THREAD;
        var mine = 0u;
        for (var k = 0u; k < COARSE_WORDS_PER_THREAD; k++) {
            mine += countOneBits(atomicLoad(&coarse_hits[first_word + k]));
        }
        let placed = exclusive_scan(local, mine, THREADS);
        var slot = total + placed.x;
        for (var k = 0u; k < COARSE_WORDS_PER_THREAD; k++) {
            // Only this invocation reads or clears its words until the next barrier.
            var bits = atomicLoad(&coarse_hits[first_word + k]);
            atomicStore(&coarse_hits[first_word + k], 0u);
            let first = chunk + (first_word + k) * 32u;
            while (bits != 0u) {
                if (slot < capacity) {
                    store_candidate(base_word + 1u + slot, coarse_candidate(first + firstTrailingBit(bits), count));
                }
                slot += 1u;
                bits &= bits - 1u;
            }
        }
        // At most the light count: no overflow.
        total += placed.y;
        // The next chunk sets bits other invocations have just cleared.
        workgroupBarrier();
    }
    if (local == 0u) {
        store_candidate(base_word, total);
    }
}

// Candidate k of the coarse stage (k < count): entry k of its wide tile's list
// (WIDE_STAGE, where the list fits), else light k. Bits and list slots go by k, so lists stay ascending.
// Past `count` it returns k (a prefetch that is never used).
fn coarse_candidate(k: u32, count: u32) -> u32 {
#if WIDE_STAGE
#if WIDE_PASS
#else
    if (from_wide && k < count) {
        return wide_lists[wide_base + 1u + k];
    }
#endif
#endif
    return k;
}

// Where the stage writes: the wide lists (WIDE_PASS) or the coarse lists.
fn store_candidate(word: u32, value: u32) {
#if WIDE_PASS
    wide_lists[word] = value;
#else
    coarse_lists[word] = value;
#endif
}

// The cone test's widening of the stage's tile: twice the coarse stage's for the wide
// pass (as its spheres, below).
#if WIDE_PASS
const STAGE_REACH: f32 = 2.0 * COARSE_REACH;
#else
const STAGE_REACH: f32 = COARSE_REACH;
#endif

// The stage's sphere of light i: the coarse one, and for the wide pass widened again by
// COARSE_REACH of its distance, since a wide tile's planes round differently from its
// coarse tiles' as those do from their tiles' (so every light a coarse tile keeps, its
// wide tile keeps).
fn stage_sphere(i: u32) -> vec4<f32> {
    let s = light_sphere(i, true);
#if WIDE_PASS
    let r = abs(s.w) + COARSE_REACH * length(s.xyz);
    return vec4<f32>(s.xyz, select(r, -r, s.w < 0.0));
#else
    return s;
#endif
}
