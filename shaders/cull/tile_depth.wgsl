// Light culling's depth range of a tile: each pixel's (or sample's) view-depth range,
// folded over the workgroup by subgroup or workgroup reductions, the 2.5D depth cells of
// the DepthMask variant and the Clustered variant's slice bounds. Included by
// cull/light_culling.wgsl, whose bindings, defines and workgroup memory it uses.

// The view-depth range sample `s` of a pixel adds to its tile (for a single-sample
// depth, `s` is the mip level 0), or (-1, -1) where it holds nothing to light.
fn sample_range(pixel: vec2<u32>, s: u32) -> vec2<f32> {
    let none = vec2<f32>(-1.0);
    if (any(pixel >= frame.size)) {
        return none;
    }
#if FLOAT_DEPTH
    let d = textureLoad(depth, pixel, s).x;
#else
    let d = textureLoad(depth, pixel, s);
#endif
#if TRANSPARENT
#if FLOAT_TRANSPARENT
    let t = textureLoad(transparent_depth, pixel, s).x;
#else
    let t = textureLoad(transparent_depth, pixel, s);
#endif
    // No transparent surface here, or every one is behind the opaque surface.
    if (t >= 1.0 || t > d) {
        return none;
    }
#if TRANSPARENT_FAR
    // Every transparent surface here lies within [t, far]; those behind d are hidden.
    let far = max(textureLoad(transparent_far, pixel, 0).x, t);
    return vec2<f32>(view_depth(t), view_depth(min(far, d)));
#else
    return vec2<f32>(view_depth(t), view_depth(d));
#endif
#else
    if (d >= 1.0) {
        return none;
    }
    let z = view_depth(d);
    return vec2<f32>(z, z);
#endif
}

// Folds every sample of a pixel into `acc`: the (min, max) float bits of the view
// depths of the samples that hold geometry. Depths are non-negative, so their bits order
// like integers; (FAR_BITS, 0) holds nothing.
fn add_depth_sample(acc: vec2<u32>, pixel: vec2<u32>) -> vec2<u32> {
    var a = acc;
    for (var s = 0u; s < SAMPLES; s++) {
        let r = sample_range(pixel, s);
        if (r.x >= 0.0) {
            a = vec2<u32>(min(a.x, bitcast<u32>(r.x)), max(a.y, bitcast<u32>(r.y)));
        }
    }
    return a;
}

// The (min, max) bits (add_depth_sample) of the step × step pixels from `corner`.
fn block_depth_range(corner: vec2<u32>, step: u32) -> vec2<u32> {
    var acc = vec2<u32>(FAR_BITS, 0u);
    for (var dy = 0u; dy < step; dy++) {
        for (var dx = 0u; dx < step; dx++) {
            acc = add_depth_sample(acc, corner + vec2<u32>(dx, dy));
        }
    }
    return acc;
}

#if SUBGROUPS
// The (min, max) of every invocation's `v`, for every invocation, with one barrier: each
// subgroup reduces its own, and its first active invocation folds that into two
// workgroup words with atomics (a few per word, not one per invocation). Min and max are
// exact in any order, so this is bit for bit the other way's result. The barrier also
// orders what was stored before it.
fn workgroup_depth_range(local: u32, side: u32, v: vec2<u32>) -> vec2<u32> {
    let inverted_min = subgroupMax(~v.x);
    let max_bits = subgroupMax(v.y);
    if (subgroupBroadcastFirst(local) == local) {
        atomicMax(&depth_inverted_min, inverted_min);
        atomicMax(&depth_max, max_bits);
    }
    workgroupBarrier();
    return vec2<u32>(~atomicLoad(&depth_inverted_min), atomicLoad(&depth_max));
}
#else
// The (min, max) of every invocation's `v`, for every invocation of a workgroup of
// side² invocations: each of the first `side` invocations folds a column of `side`
// values, then every invocation folds the `side` column results. Min and max are exact
// in any order, so this is bit for bit what atomics on two workgroup words gave, without
// 2·side² atomics queueing on the same two words. Two barriers; the first also orders
// what was stored before it.
fn workgroup_depth_range(local: u32, side: u32, v: vec2<u32>) -> vec2<u32> {
    depth_partial[local] = v;
    workgroupBarrier();
    if (local < side) {
        // Reads only words side.. and writes only its own word below side.
        var a = v;
        for (var k = 1u; k < side; k++) {
            let b = depth_partial[local + k * side];
            a = vec2<u32>(min(a.x, b.x), max(a.y, b.y));
        }
        depth_partial[local] = a;
    }
    workgroupBarrier();
    var a = depth_partial[0];
    for (var k = 1u; k < side; k++) {
        let b = depth_partial[k];
        a = vec2<u32>(min(a.x, b.x), max(a.y, b.y));
    }
    return a;
}
#endif

// The 2.5D mask's cells every sample of a pixel occupies within [lo, hi].
fn add_depth_cells(pixel: vec2<u32>, lo: f32, hi: f32) {
    var cells = 0u;
    for (var s = 0u; s < SAMPLES; s++) {
        let r = sample_range(pixel, s);
        if (r.x >= 0.0) {
            cells |= cells_between(cell_of(r.x, lo, hi), cell_of(r.y, lo, hi));
        }
    }
    if (cells != 0u) {
        atomicOr(&depth_mask, cells);
    }
}

// Depth cell of z in [lo, hi] for the 2.5D mask: 32 equal cells.
fn cell_of(z: f32, lo: f32, hi: f32) -> u32 {
    let t = (z - lo) / max(hi - lo, 1e-30);
    return u32(clamp(t * 32.0, 0.0, 31.0));
}

fn cells_between(a: u32, b: u32) -> u32 {
    let width = b - a + 1u;
    let ones = select((1u << width) - 1u, 0xffffffffu, width >= 32u);
    return ones << a;
}

// Exponential slice bounds for the clustered variant.
fn slice_bound(k: u32, slices: u32) -> f32 {
    return frame.near * pow(frame.far / frame.near, f32(k) / f32(slices));
}
