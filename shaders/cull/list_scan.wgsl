// Light culling's prefix sums: the workgroup scan the coarse stage places its hits with,
// and the compact lists' scan between the two runs of `main` (COMPACT). Included by
// cull/light_culling.wgsl, whose bindings and defines it uses.

// Exclusive prefix sum of `v` over the workgroup's `n` invocations (n ≤ SCAN_MAX, a
// power of two: THREADS for the coarse stage, SCAN_THREADS for the list scans;
// Hillis–Steele): (the sum of the invocations' before this one, the sum of all). Sums
// saturate at u32::MAX, which is associative, so a saturated total is still exact below
// the bound (the coarse stage's sums, at most the light count, never saturate). Ends with
// a barrier: the next call may store into scan_sums at once.
const SCAN_MAX: u32 = 256u;
var<workgroup> scan_sums: array<u32, SCAN_MAX>;

fn add_sat(a: u32, b: u32) -> u32 {
    let s = a + b;
    return select(s, 0xffffffffu, s < a);
}

fn exclusive_scan(local: u32, v: u32, n: u32) -> vec2<u32> {
    scan_sums[local] = v;
    workgroupBarrier();
    for (var d = 1u; d < n; d *= 2u) {
        var add = 0u;
        if (local >= d) {
            add = scan_sums[local - d];
        }
        workgroupBarrier();
        scan_sums[local] = add_sat(scan_sums[local], add);
        workgroupBarrier();
    }
    var before = 0u;
    if (local > 0u) {
        before = scan_sums[local - 1u];
    }
    let total = scan_sums[n - 1u];
    workgroupBarrier();
    return vec2<u32>(before, total);
}

#if COMPACT
// The prefix sum between the two runs of `main`: blocked, not decoupled look-back (WGSL
// promises no forward progress between workgroups, so a workgroup spinning on another's
// flag may never see it), and not one workgroup over every list (at 1920×1080 with 16
// clusters that is 130,560 lists in one workgroup's loop); `exclusive_scan` above.
const SCAN_THREADS: u32 = 256u;
const SCAN_PER_THREAD: u32 = SCAN_BLOCK / SCAN_THREADS;

fn list_count() -> u32 {
    return list_params.tiles_x * list_params.tiles_y * list_params.lists_per_tile;
}

// Block b's sum of the counts of its lists longer than their slot, saturated where it
// wrapped.
fn block_sum(b: u32) -> u32 {
    if (atomicLoad(&list_block_sums[2u * b + 1u]) != 0u) {
        return 0xffffffffu;
    }
    return atomicLoad(&list_block_sums[2u * b]);
}

// A workgroup per block of SCAN_BLOCK lists, SCAN_PER_THREAD consecutive lists an
// invocation: each list's offset and the count it keeps under the bound. Each workgroup
// sums the blocks before its own itself (a few at most: 8 at 1920×1080 with 16-pixel
// tiles, 128 with 16 clusters), so no dispatch scans the blocks first (saturating sums
// are associative: the same offsets in any order); the first writes header word 0, the
// indices the lists longer than their scratch slot want (all lists' without scratch). A list that
// fits its scratch slot (1..=scratch lights) stays there, whole; the others lie in the
// pool after every slot, back to back in list order (empty ones too, holding nothing,
// so that without scratch every offset is the sum of the counts before it).
@compute @workgroup_size(SCAN_THREADS, 1, 1)
fn scan_lists(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    let lists = list_count();
    let scratch = compact.scratch;
    let first = group.x * SCAN_BLOCK + local * SCAN_PER_THREAD;
    var counts: array<u32, SCAN_PER_THREAD>;
    var sum = 0u;
    for (var j = 0u; j < SCAN_PER_THREAD; j++) {
        let l = first + j;
        var c = 0u;
        if (l < lists) {
            c = atomicLoad(&light_lists[HEADER_WORDS + ENTRY_WORDS * l + 1u]);
        }
        counts[j] = c;
        if (c > scratch) {
            sum = add_sat(sum, c);
        }
    }
    let before = exclusive_scan(local, sum, SCAN_THREADS).x;
    let blocks = (lists + SCAN_BLOCK - 1u) / SCAN_BLOCK;
    var earlier = 0u;
    var every = 0u;
    for (var b = local; b < blocks; b += SCAN_THREADS) {
        let v = block_sum(b);
        every = add_sat(every, v);
        if (b < group.x) {
            earlier = add_sat(earlier, v);
        }
    }
    let block_start = exclusive_scan(local, earlier, SCAN_THREADS).y;
    let wanted = exclusive_scan(local, every, SCAN_THREADS).y;
    if (group.x == 0u && local == 0u) {
        atomicStore(&light_lists[0], wanted);
    }
    // At most half the index array (`ListLayout::scratch_per_list`): no overflow.
    let pool_start = scratch * lists;
    var offset = add_sat(block_start, before);
    let pool = list_params.pool_indices;
    for (var j = 0u; j < SCAN_PER_THREAD; j++) {
        let l = first + j;
        let c = counts[j];
        if (l < lists) {
            let e = HEADER_WORDS + ENTRY_WORDS * l;
            if (c > 0u && c <= scratch) {
                atomicStore(&light_lists[e], l * scratch);
            } else {
                let start = min(add_sat(pool_start, offset), pool);
                let kept = min(c, pool - start);
                atomicStore(&light_lists[e], start);
                atomicStore(&light_lists[e + 1u], kept);
                if (kept < c) {
                    atomicAdd(&light_lists[1], 1u);
                }
            }
        }
        if (c > scratch) {
            offset = add_sat(offset, c);
        }
    }
}
#endif
