//! Compact light lists (`LightCulling(..., lists: Compact(max_indices: N))`): count →
//! prefix sum → fill, so every list holds exactly its lights at any density, and only the
//! total is bounded by the graph.
//!
//! Where fixed lists of 256 overflow (harada's 3,072 lights at 64×36; 3,000 random lights
//! at 96×64), every culling variant at each tile size must give:
//! - no list cut, no fill that disagrees with its count, every offset the sum of the
//!   counts before it (checked on the CPU from the entries read back);
//! - exactly the lists of fixed lists roomy enough not to overflow (same counts), and so
//!   the same image to the bit (same lights, same ascending order, same shading code);
//! - brute force's image within the culling tests' 2e-6 (see tests/culling_exact.rs).
//!
//! A bound smaller than the lists want cuts the last lists in list order, fills the
//! index array to its last word, and is counted (lists cut, indices wanted) and reported.
//!
//! Scratch slots (`Compact(max_indices: N, scratch: S)`, S 256 unless given): a list of
//! 1..=S lights lies whole in its own slot from the count; only longer lists are filled,
//! into the pool after the slots. The checks above run with the default slots (harada's
//! and the dense set's lists are both shorter and longer than 256); with S equal to a
//! list's own count (the boundary); without slots (S 0, the layout before slots) bit for
//! bit the same lists; and a bound reached with slots in use cuts only pooled lists.
//! `mutations_are_caught` runs these checks on deliberately broken copies of the culling
//! shader (scan off by one, the block scan's carry dropped from its total or its offsets,
//! bound ignored, fill out of order, count short, and nine ways of breaking the slots)
//! and requires each check to fail, so none of them passes vacuously.

mod common;
use common::*;
use lightgraph::render::{FrameResult, Renderer};
use lightgraph::scene::Scene;
use lightgraph::shader::ShaderLibrary;

/// Every variant at 8 and 16 pixels, and the compute-first frame's Frustum at 32.
const ALL: [(u32, &str); 9] = [
    (8, "Frustum"),
    (8, "HalfZ"),
    (8, "DepthMask"),
    (8, "Clustered(slices: 16)"),
    (16, "Frustum"),
    (16, "HalfZ"),
    (16, "DepthMask"),
    (16, "Clustered(slices: 16)"),
    (32, "Frustum"),
];
const TOLERANCE: f32 = 2e-6;
/// Room for everything these scenes want (4 MiB of indices).
const ROOMY: u32 = 1 << 20;

/// Compact lists with the default scratch slots.
fn compact(tile: u32, variant: &str, max_indices: u32) -> String {
    graph_with_culling(
        "forward_plus.ron",
        &format!("LightCulling(tile: {tile}, variant: {variant}, lists: Compact(max_indices: {max_indices}))"),
    )
}

fn compact_scratch(tile: u32, variant: &str, max_indices: u32, scratch: u32) -> String {
    graph_with_culling(
        "forward_plus.ron",
        &format!("LightCulling(tile: {tile}, variant: {variant}, lists: Compact(max_indices: {max_indices}, scratch: {scratch}))"),
    )
}

fn fixed(tile: u32, variant: &str, capacity: u32) -> String {
    graph_with_culling(
        "forward_plus.ron",
        &format!("LightCulling(tile: {tile}, variant: {variant}, capacity: {capacity})"),
    )
}

/// The worst relative error against the reference (to the pixel, or to 1e-3 of the
/// peak for dark pixels), as in tests/culling_exact.rs.
fn worst_error(image: &[[f32; 4]], reference: &[[f32; 4]]) -> f32 {
    assert_eq!(image.len(), reference.len());
    let peak = reference
        .iter()
        .flat_map(|p| p[..3].to_vec())
        .fold(0.0f32, f32::max);
    let mut worst = 0.0f32;
    for (a, b) in image.iter().zip(reference) {
        for ch in 0..3 {
            let d = (a[ch] - b[ch]).abs() / b[ch].abs().max(1e-3 * peak).max(1e-30);
            if d.is_nan() {
                return f32::INFINITY;
            }
            worst = worst.max(d);
        }
    }
    worst
}

/// What is wrong with one compact frame's report on its own.
fn report_failures(what: &str, out: &FrameResult) -> Vec<String> {
    let c = &out.culling[0];
    let mut f = Vec::new();
    if c.overflowed_lists != 0 || c.mismatched_lists != 0 || c.misplaced_lists != 0 {
        f.push(format!(
            "{what}: {} lists cut, {} fills mismatched, {} lists misplaced",
            c.overflowed_lists, c.mismatched_lists, c.misplaced_lists
        ));
    }
    if c.wanted != Some(c.listed()) {
        f.push(format!(
            "{what}: lists want {:?} indices but hold {}",
            c.wanted,
            c.listed()
        ));
    }
    f
}

/// The scratch slots a check gives compact lists.
#[derive(Clone, Copy, Debug)]
enum Scratch {
    /// The graph's default (256).
    Default,
    /// The median of the non-empty lists' counts: one list at least fills its slot to
    /// the last index, and lists lie on both sides of it.
    OwnCount,
}

/// The median of the non-empty counts.
fn median_count(counts: &[u32]) -> u32 {
    let mut c: Vec<u32> = counts.iter().copied().filter(|&c| c > 0).collect();
    c.sort_unstable();
    c[c.len() / 2]
}

/// Compact lists at each (tile, variant) against roomy fixed lists and brute force;
/// returns what is wrong (empty when everything holds).
fn exactness_failures(
    r: &mut Renderer,
    scene: &Scene,
    (w, h): (u32, u32),
    combos: &[(u32, &str)],
) -> Vec<String> {
    scratch_exactness_failures(r, scene, (w, h), combos, Scratch::Default)
}

fn scratch_exactness_failures(
    r: &mut Renderer,
    scene: &Scene,
    (w, h): (u32, u32),
    combos: &[(u32, &str)],
    scratch: Scratch,
) -> Vec<String> {
    let reference = render_file(r, "brute_force.ron", scene, w, h);
    let mut failures = Vec::new();
    for &(tile, variant) in combos {
        let mut what = format!("{} {w}x{h} tile {tile} {variant}", scene.name);
        // Fixed lists as long as the scene has lights cannot overflow.
        let roomy = render_text(r, &fixed(tile, variant, 4096), scene, w, h);
        assert_eq!(roomy.culling[0].overflowed_lists, 0, "{what}: fixed 4096");
        let graph = match scratch {
            Scratch::Default => compact(tile, variant, ROOMY),
            Scratch::OwnCount => {
                let s = median_count(&roomy.culling[0].counts);
                what += &format!(" scratch {s}");
                compact_scratch(tile, variant, ROOMY, s)
            }
        };
        let out = render_text(r, &graph, scene, w, h);
        failures.extend(report_failures(&what, &out));
        let both_sides = matches!(scratch, Scratch::OwnCount);
        failures.extend(slot_failures(
            &what,
            &out,
            &roomy.culling[0].counts,
            both_sides,
        ));
        if out.culling[0].counts != roomy.culling[0].counts {
            let differ = (out.culling[0].counts.iter())
                .zip(&roomy.culling[0].counts)
                .filter(|(a, b)| a != b)
                .count();
            failures.push(format!("{what}: {differ} lists differ from fixed lists"));
        }
        if out.image != roomy.image {
            failures.push(format!("{what}: the image differs from fixed lists'"));
        }
        // The per-pixel statistics read the lists through the same include.
        let stats = |o: &FrameResult| {
            o.light_stats
                .as_ref()
                .map(|s| (s.listed_total, s.exact_total, s.max_listed))
        };
        if stats(&out) != stats(&roomy) || stats(&out).is_none() {
            failures.push(format!("{what}: light statistics differ from fixed lists'"));
        }
        let e = worst_error(&out.image, &reference.image);
        if e > TOLERANCE {
            failures.push(format!("{what}: relative error {e:e} against brute force"));
        }
    }
    failures
}

/// Lists of 1..=scratch lights must lie in their slots and hold what the report says;
/// with `both_sides`, the frame must have lists on both sides of the slot (else it tests
/// one kind only).
fn slot_failures(
    what: &str,
    out: &FrameResult,
    roomy_counts: &[u32],
    both_sides: bool,
) -> Vec<String> {
    let c = &out.culling[0];
    let s = c.layout.scratch_per_list();
    let short: u64 = (roomy_counts.iter())
        .filter(|&&n| n > 0 && n <= s)
        .map(|&n| n as u64)
        .sum();
    let mut f = Vec::new();
    if c.scratch_held != short {
        f.push(format!(
            "{what}: {} indices in scratch slots of {s}, not the {short} of the lists that fit",
            c.scratch_held
        ));
    }
    if both_sides && (s == 0 || short == 0 || !roomy_counts.iter().any(|&n| n > s)) {
        f.push(format!(
            "{what}: slots of {s} must hold some lists and not others"
        ));
    }
    f
}

/// The density the fixed layout cannot hold: lists of 256 overflow in `lists` tiles, and
/// the image is wrong there.
fn assert_fixed_overflows(r: &mut Renderer, scene: &Scene, w: u32, h: u32, lists: u32) {
    let out = render_text(r, &fixed(16, "Frustum", 256), scene, w, h);
    assert_eq!(
        out.culling[0].overflowed_lists, lists,
        "{}: fixed lists of 256 overflow in {lists} tiles",
        scene.name
    );
    let reference = render_file(r, "brute_force.ron", scene, w, h);
    assert!(worst_error(&out.image, &reference.image) > 1e-2);
}

fn harada() -> Scene {
    lightgraph::scene::builtin::harada()
}

#[test]
fn harada_at_64x36_is_exact_for_every_variant() {
    let mut r = renderer();
    let scene = harada();
    assert_eq!(scene.lights.len(), 3072);
    assert_fixed_overflows(&mut r, &scene, 64, 36, 6);
    let failures = exactness_failures(&mut r, &scene, (64, 36), &ALL);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn dense_random_lights_are_exact_for_every_variant() {
    let mut r = renderer();
    let scene = random_scene(3000, 23);
    let out = render_text(&mut r, &fixed(16, "Frustum", 256), &scene, 96, 64);
    assert!(
        out.culling[0].overflowed_lists >= 6,
        "the set must be dense"
    );
    let failures = exactness_failures(&mut r, &scene, (96, 64), &ALL);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Every other reader of tile lists where fixed lists of 256 overflow (harada at 64×36):
/// deferred shading, the packed G-buffer's, the light linked list's build (tile lists as
/// candidates) in both shading paths, transparent shading (the glass scene with 3,072
/// lights); each equal to its own brute force.
#[test]
fn every_list_reader_takes_compact_lists() {
    let mut r = renderer();
    let harada = harada();
    let (w, h) = (64, 36);
    let forward = render_file(&mut r, "brute_force.ron", &harada, w, h);
    let deferred = render_file(&mut r, "deferred_brute_force.ron", &harada, w, h);
    let glass = lightgraph::bench::sweep::with_light_count(
        &lightgraph::scene::builtin::by_name("glass").unwrap(),
        3072,
    );
    let glass_reference = render_file(&mut r, "transparent_brute_force.ron", &glass, w, h);
    let mut failures = Vec::new();
    let mut check = |graph: &str, scene: &Scene, reference: &[[f32; 4]], tol: f32| {
        let out = render_file(&mut r, graph, scene, w, h);
        assert!(!out.culling.is_empty(), "{graph}: no culling report");
        for (i, c) in out.culling.iter().enumerate() {
            assert!(
                matches!(
                    c.layout.storage,
                    lightgraph::graph::ListStorage::Compact { .. }
                ),
                "{graph}: ships compact lists"
            );
            failures.extend(report_failures(&format!("{graph} pass {i}"), &out));
        }
        let e = worst_error(&out.image, reference);
        println!("{graph}: worst relative error {e:e}");
        if e > tol {
            failures.push(format!("{graph}: relative error {e:e}"));
        }
    };
    check(
        "tiled_deferred_prepass.ron",
        &harada,
        &deferred.image,
        TOLERANCE,
    );
    check("tiled_deferred.ron", &harada, &deferred.image, TOLERANCE);
    // Rebuilt positions: tests/culling_exact.rs's bound for the packed G-buffer.
    check("tiled_deferred_packed.ron", &harada, &deferred.image, 1e-3);
    check("light_linked_list.ron", &harada, &forward.image, TOLERANCE);
    check(
        "light_linked_list_deferred.ron",
        &harada,
        &deferred.image,
        TOLERANCE,
    );
    check("transparent.ron", &glass, &glass_reference.image, TOLERANCE);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Thousands of lists (tile 8, 64 clusters at 640×480: 307,200 lists, 300 scan blocks)
/// take both levels of the scan, the block loop included (256 blocks a round): every
/// list without scratch slots, the lists past their slot of 1 with the default (256
/// lowered to ⌊ROOMY / 2L⌋ = 1 there).
fn many_lists_failures(r: &mut Renderer, scratch: u32) -> Vec<String> {
    let scene = random_scene(40, 29);
    let (w, h) = (640, 480);
    let variant = "Clustered(slices: 64)";
    let graph = compact_scratch(8, variant, ROOMY, scratch);
    let out = render_text(r, &graph, &scene, w, h);
    assert_eq!(out.culling[0].layout.lists(), 307_200);
    assert_eq!(out.culling[0].layout.scratch_per_list(), scratch.min(1));
    let what = format!("640x480 tile 8 64 clusters, scratch {scratch}");
    let mut f = report_failures(&what, &out);
    let roomy = render_text(r, &fixed(8, variant, 64), &scene, w, h);
    assert_eq!(roomy.culling[0].overflowed_lists, 0);
    if out.culling[0].counts != roomy.culling[0].counts || out.image != roomy.image {
        f.push(format!("{what}: lists or image differ from fixed lists'"));
    }
    if scratch > 0 {
        f.extend(slot_failures(&what, &out, &roomy.culling[0].counts, true));
    }
    f
}

#[test]
fn hundreds_of_thousands_of_lists_scan_in_two_levels() {
    let mut r = renderer();
    let mut failures = many_lists_failures(&mut r, 0);
    failures.extend(many_lists_failures(&mut r, 256));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A bound of half what the lists want, without scratch slots: what must hold when it is
/// reached.
fn bound_failures(r: &mut Renderer) -> Vec<String> {
    let scene = harada();
    let (w, h) = (64, 36);
    let full = render_text(r, &compact_scratch(16, "Frustum", ROOMY, 0), &scene, w, h);
    let wanted = full.culling[0].listed();
    let max = (wanted / 2) as u32;
    let out = render_text(r, &compact_scratch(16, "Frustum", max, 0), &scene, w, h);
    let c = &out.culling[0];
    let mut f = Vec::new();
    if c.wanted != Some(wanted) {
        f.push(format!("wanted {:?}, not {wanted}", c.wanted));
    }
    // The array fills to its last word; lists keep their start in list order, so the
    // lists before the cut are whole, one is cut short and the rest are empty.
    if c.listed() != max as u64 {
        f.push(format!("{} indices held, not the bound {max}", c.listed()));
    }
    let whole = c
        .counts
        .iter()
        .zip(&full.culling[0].counts)
        .take_while(|(a, b)| a == b)
        .count();
    if whole == c.counts.len() {
        f.push("no list was cut".into());
        return f;
    }
    if c.counts[whole + 1..].iter().any(|&n| n != 0) {
        f.push(format!("lists after the cut hold lights: {:?}", c.counts));
    }
    let cut_nonempty = full.culling[0].counts[whole..]
        .iter()
        .filter(|&&n| n > 0)
        .count();
    if c.overflowed_lists as usize != cut_nonempty {
        f.push(format!(
            "{} lists counted as cut, {cut_nonempty} lost lights",
            c.overflowed_lists
        ));
    }
    if c.mismatched_lists != 0 || c.misplaced_lists != 0 {
        f.push(format!(
            "{} mismatched, {} misplaced",
            c.mismatched_lists, c.misplaced_lists
        ));
    }
    let warnings = c.warnings().join("\n");
    let expect = format!(
        "the lists wanted {wanted} light indices, over max_indices {max}: {} lists lost lights",
        c.overflowed_lists
    );
    if !warnings.contains(&expect) {
        f.push(format!("warning missing: {warnings}"));
    }
    f
}

#[test]
fn reaching_the_bound_is_counted_and_reported() {
    let mut r = renderer();
    let failures = bound_failures(&mut r);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A bound reached with scratch slots in use (harada at 64×36, tile 8: 40 lists). Slots of
/// S, a count some list has, and a bound of 2·L·S: the slots take L·S, exactly half,
/// so S is not lowered, and the pool's L·S holds less than the lists longer than S want.
/// Lists of 1..=S lights stay whole; the pooled ones keep their start in list order
/// (whole before the cut, one cut short, the rest empty); the pool fills to its last
/// word; the cut lists are counted; and the bound the warning names fits exactly: one
/// index less cuts one list.
fn scratch_bound_failures(r: &mut Renderer) -> Vec<String> {
    let scene = harada();
    let (w, h, tile) = (64, 36, 8);
    let roomy = render_text(r, &fixed(tile, "Frustum", 4096), &scene, w, h);
    let counts = roomy.culling[0].counts.clone();
    let lists = counts.len() as u64;
    let pooled_past = |s: u32| -> u64 {
        let long = counts.iter().filter(|&&n| n > s);
        long.map(|&n| n as u64).sum()
    };
    // The largest count whose pool of L·S is too small for the lists past it.
    let mut sizes: Vec<u32> = counts.iter().copied().filter(|&n| n > 0).collect();
    sizes.sort_unstable();
    let s = *sizes
        .iter()
        .rev()
        .find(|&&s| lists * s as u64 > 0 && lists * (s as u64) < pooled_past(s))
        .expect("a slot size whose pool overflows");
    let pool = lists * s as u64;
    let max = 2 * pool;
    let graph = |max: u64| compact_scratch(tile, "Frustum", max as u32, s);
    let out = render_text(r, &graph(max), &scene, w, h);
    let c = &out.culling[0];
    let what = format!("tile {tile} scratch {s} max_indices {max}");
    let mut f = Vec::new();
    if c.layout.scratch_per_list() != s {
        f.push(format!("{what}: slots of {}", c.layout.scratch_per_list()));
    }
    // What each list must keep.
    let mut left = pool;
    let mut short = 0u64;
    let mut cut = 0;
    let expect: Vec<u32> = (counts.iter())
        .map(|&n| {
            if n <= s {
                short += n as u64;
                return n;
            }
            let kept = (n as u64).min(left);
            left -= kept;
            cut += (kept < n as u64) as u32;
            kept as u32
        })
        .collect();
    let wanted: u64 = counts.iter().map(|&n| n as u64).sum();
    let (long_lists, short_lists) = (
        counts.iter().filter(|&&n| n > s).count(),
        counts.iter().filter(|&&n| n > 0 && n <= s).count(),
    );
    println!(
        "{what}: {short_lists} lists in slots ({short} indices), {long_lists} past them want {} of the pool's {pool}; {cut} cut",
        pooled_past(s)
    );
    if c.counts != expect {
        f.push(format!("{what}: kept {:?}, not {expect:?}", c.counts));
    }
    if left != 0 || c.listed() != short + pool {
        f.push(format!(
            "{what}: {} indices held, not the {short} in slots and the pool's {pool}",
            c.listed()
        ));
    }
    if cut == 0 || short_lists == 0 || c.overflowed_lists != cut {
        f.push(format!(
            "{what}: {} lists counted as cut, {cut} lost lights, {short_lists} in slots",
            c.overflowed_lists
        ));
    }
    if c.wanted != Some(wanted) || c.scratch_held != short {
        f.push(format!(
            "{what}: wanted {:?} with {} in slots, not {wanted} with {short}",
            c.wanted, c.scratch_held
        ));
    }
    if c.mismatched_lists != 0 || c.misplaced_lists != 0 {
        f.push(format!(
            "{what}: {} mismatched, {} misplaced",
            c.mismatched_lists, c.misplaced_lists
        ));
    }
    // The pool must hold what the lists past their slot want, with the slots unlowered.
    let fits = pool + pooled_past(s);
    let warnings = c.warnings().join("\n");
    let expect_warning = format!(
        "{} lists lost lights (max_indices: {fits} fits this frame)",
        c.overflowed_lists
    );
    if !warnings.contains(&expect_warning) || !warnings.contains("scratch slot") {
        f.push(format!("{what}: warning wrong: {warnings}"));
    }
    let out = render_text(r, &graph(fits), &scene, w, h);
    f.extend(report_failures(&format!("{what} at {fits}"), &out));
    if out.culling[0].counts != counts {
        f.push(format!("{what}: max_indices {fits} does not fit"));
    }
    let out = render_text(r, &graph(fits - 1), &scene, w, h);
    if out.culling[0].overflowed_lists != 1 || out.culling[0].listed() != wanted - 1 {
        f.push(format!("{what}: max_indices {} fits", fits - 1));
    }
    f
}

#[test]
fn reaching_the_bound_with_scratch_slots_is_counted_and_reported() {
    let mut r = renderer();
    let failures = scratch_bound_failures(&mut r);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn scratch_slots_of_a_lists_own_count_are_exact() {
    let mut r = renderer();
    let harada = harada();
    let mut failures =
        scratch_exactness_failures(&mut r, &harada, (64, 36), &ALL, Scratch::OwnCount);
    let dense = random_scene(3000, 23);
    failures.extend(scratch_exactness_failures(
        &mut r,
        &dense,
        (96, 64),
        &ALL,
        Scratch::OwnCount,
    ));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Renders one frame and reads its light lists back: each list's light indices.
fn render_lists(
    r: &mut Renderer,
    graph_text: &str,
    scene: &Scene,
    (w, h): (u32, u32),
) -> (FrameResult, Vec<Vec<u32>>) {
    use lightgraph::graph::{self, FrameSize};
    let checked = graph::check_text(
        std::path::Path::new("<test>"),
        graph_text,
        &ShaderLibrary::builtin(),
    )
    .expect("valid graph");
    let size = FrameSize {
        width: w,
        height: h,
        lights: scene.lights.len() as u32,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    let gpu = lightgraph::render::SceneGpu::upload(&r.ctx.device, &r.ctx.queue, scene)
        .expect("materials");
    let stats = compiled.has_forward_shading();
    let prepared = r
        .prepare(compiled, scene, &gpu, size, stats)
        .expect("prepare");
    let out = prepared.render(r).expect("render");
    let bytes = prepared.read_buffer(r, "light_lists").expect("the lists");
    let words: &[u32] = bytemuck::cast_slice(&bytes);
    let layout = out.culling[0].layout;
    let pool = layout.pool_offset_words() as usize;
    let lists = (0..layout.lists() as usize)
        .map(|l| {
            let e = 4 + 4 * l;
            let (offset, count) = (words[e] as usize, words[e + 1] as usize);
            words[pool + offset..pool + offset + count].to_vec()
        })
        .collect();
    (out, lists)
}

/// What differs between lists without scratch slots and with slots of `scratch` (and
/// with the default ones): every list's light indices, in order, and the image, bit for
/// bit.
fn same_lists_failures(
    r: &mut Renderer,
    scene: &Scene,
    size: (u32, u32),
    combos: &[(u32, &str)],
) -> Vec<String> {
    let mut f = Vec::new();
    for &(tile, variant) in combos {
        let what = format!("{} tile {tile} {variant}", scene.name);
        let (none, none_lists) =
            render_lists(r, &compact_scratch(tile, variant, ROOMY, 0), scene, size);
        f.extend(report_failures(&format!("{what} scratch 0"), &none));
        let own = median_count(&none.culling[0].counts);
        let graphs = [
            compact_scratch(tile, variant, ROOMY, own),
            compact(tile, variant, ROOMY),
        ];
        for graph in graphs {
            let (out, lists) = render_lists(r, &graph, scene, size);
            let s = out.culling[0].layout.scratch_per_list();
            if s == 0 || out.culling[0].scratch_held == 0 {
                f.push(format!("{what}: no list in slots of {s}"));
            }
            let differ = lists.iter().zip(&none_lists).filter(|(a, b)| a != b);
            let differ = differ.count();
            if differ > 0 || lists.len() != none_lists.len() {
                f.push(format!(
                    "{what}: {differ} lists differ between slots of {s} and none"
                ));
            }
            if out.image != none.image {
                f.push(format!(
                    "{what}: the image differs between slots of {s} and none"
                ));
            }
        }
    }
    f
}

#[test]
fn scratch_slots_give_the_same_lists_as_none() {
    let mut r = renderer();
    let failures = same_lists_failures(&mut r, &harada(), (64, 36), &ALL);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The GPU sweep (benches/sweeps/compact_lists.ron) end to end at 64×36 with 3,072 lights:
/// compact rows hold every light and equal brute force of their shading path; the fixed
/// rows of 256 overflow and are wrong; the list columns are filled.
#[test]
fn the_compact_lists_sweep_runs_at_a_tiny_size() {
    use lightgraph::bench::sweep::{self, Sweep};
    let path = lightgraph::project_root().join("benches/sweeps/compact_lists.ron");
    let mut plan = Sweep::load(&path).expect("the sweep parses");
    plan.resolutions = vec![(64, 36)];
    plan.lights = vec![3072];
    (plan.warmup, plan.warmup_seconds, plan.frames, plan.rounds) = (1, 0.0, 1, 1);
    let mut r = renderer();
    let rows = sweep::run(&plan, path.parent().unwrap(), &mut r, |_| {}).expect("sweep");
    let mut failures = Vec::new();
    for row in rows.iter().filter(|r| r.reference.is_some()) {
        let what = format!("{} {}", row.technique, row.light_count);
        let storage = row.list_storage.clone().unwrap_or_default();
        let cut = row.overflow_tiles.unwrap_or(0);
        let (Some(mib), Some(held)) = (row.list_mib, row.list_indices) else {
            failures.push(format!("{what}: no list columns"));
            continue;
        };
        println!(
            "{what}: {storage}, {mib:.2} MiB, {held} indices, {cut} cut, max rel {:?}",
            row.max_rel
        );
        if storage.starts_with("compact:") {
            // The packed G-buffer rebuilds positions (tests/culling_exact.rs: 1e-3 here).
            let tolerance = if row.technique.contains("packed") {
                1e-3
            } else {
                2e-6
            };
            let exact = row.max_rel.is_some_and(|e| e <= tolerance);
            if cut != 0 || row.list_indices_wanted != Some(held) || !exact {
                failures.push(format!(
                    "{what}: compact lists cut {cut} or wrong ({:?})",
                    row.max_rel
                ));
            }
        } else if storage == "fixed:256" && (cut == 0 || row.max_rel.is_none_or(|e| e < 1e-2)) {
            failures.push(format!("{what}: fixed lists of 256 did not overflow here"));
        }
    }
    assert_eq!(rows.iter().filter(|r| r.list_storage.is_some()).count(), 9);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The culling shader and the files it includes for its stages.
const CULLING_FILES: [&str; 4] = [
    "cull/light_culling.wgsl",
    "cull/tile_depth.wgsl",
    "cull/coarse_stage.wgsl",
    "cull/list_scan.wgsl",
];

/// A copy of the culling shader's files with `from` replaced by `to` (which must occur
/// once in them), used through the renderer's shader library until the guard is dropped.
struct Mutated<'a> {
    r: &'a mut Renderer,
    _dir: tempfile::TempDir,
    saved: Option<ShaderLibrary>,
}

impl<'a> Mutated<'a> {
    fn new(r: &'a mut Renderer, from: &str, to: &str) -> Self {
        let library = ShaderLibrary::builtin();
        let texts = CULLING_FILES.map(|f| library.read_source(f).unwrap());
        let sites: usize = texts.iter().map(|t| t.matches(from).count()).sum();
        assert_eq!(sites, 1, "mutation site: {from}");
        let (file, text) = CULLING_FILES
            .iter()
            .zip(&texts)
            .find(|(_, t)| t.contains(from))
            .unwrap();
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("cull")).unwrap();
        std::fs::write(dir.path().join(file), text.replace(from, to)).unwrap();
        let saved = std::mem::replace(&mut r.shaders, ShaderLibrary::with_builtin(dir.path()));
        // The cache is keyed by file name and defines, not text: start from empty.
        r.pipelines = Default::default();
        Self {
            r,
            _dir: dir,
            saved: Some(saved),
        }
    }
}

impl Drop for Mutated<'_> {
    fn drop(&mut self) {
        self.r.shaders = self.saved.take().unwrap();
        self.r.pipelines = Default::default();
    }
}

/// A tile size of each and a variant of one list and of many lists a tile: enough for a
/// mutation to show (the tests above run all eight).
const SOME: [(u32, &str); 2] = [(16, "Frustum"), (8, "Clustered(slices: 16)")];

#[test]
fn mutations_are_caught() {
    let mut r = renderer();
    let harada = harada();
    let dense = random_scene(3000, 23);
    let caught = |what: &str, f: Vec<String>| {
        println!("{what}: {} failures, first: {:?}", f.len(), f.first());
        assert!(!f.is_empty(), "{what} passed");
        f
    };
    // Scan off by one: each invocation's offset includes its own lists.
    {
        let m = Mutated::new(
            &mut r,
            "before = scan_sums[local - 1u];",
            "before = scan_sums[local];",
        );
        caught(
            "scan off by one, harada",
            exactness_failures(m.r, &harada, (64, 36), &SOME),
        );
        caught(
            "scan off by one, dense",
            exactness_failures(m.r, &dense, (96, 64), &SOME),
        );
    }
    // The total (header word 0) is the first invocation's share of the blocks only.
    {
        let m = Mutated::new(
            &mut r,
            "atomicStore(&light_lists[0], wanted);",
            "atomicStore(&light_lists[0], every);",
        );
        caught("blocks' total dropped", many_lists_failures(m.r, 0));
    }
    // A block's offset leaves out the blocks before it.
    {
        let m = Mutated::new(&mut r, "earlier = add_sat(earlier, v);", "earlier = 0u;");
        caught(
            "block offsets without the earlier blocks",
            many_lists_failures(m.r, 0),
        );
    }
    // A block's offset leaves out the block just before it.
    {
        let m = Mutated::new(&mut r, "if (b < group.x) {", "if (b + 1u < group.x) {");
        caught(
            "block offsets without the block before",
            many_lists_failures(m.r, 0),
        );
    }
    // The scan ignores the bound: lists run past the index array.
    {
        let m = Mutated::new(&mut r, "let kept = min(c, pool - start);", "let kept = c;");
        caught("bound ignored", bound_failures(m.r));
    }
    // The fill writes each batch in reverse: the same lights, out of ascending order.
    {
        let m = Mutated::new(
            &mut r,
            "atomicStore(&light_lists[offset + slot], i);",
            "atomicStore(&light_lists[offset + total + hits_in_batch(h) - 1u - rank_in_batch(h, local)], i);",
        );
        let f = caught(
            "fill reversed",
            exactness_failures(m.r, &harada, (64, 36), &SOME),
        );
        assert!(f.iter().any(|f| f.contains("image differs")), "{f:?}");
    }
    // The count misses the last batch of candidates: lists come out short.
    {
        let m = Mutated::new(
            &mut r,
            "atomicStore(&light_lists[e + 1u], total);",
            "atomicStore(&light_lists[e + 1u], total - hits_in_batch(1u - h));",
        );
        caught(
            "count short",
            exactness_failures(m.r, &dense, (96, 64), &SOME),
        );
    }
    // Scratch slots, at a list's own count (the boundary) on harada.
    let slot_mutations = [
        // A list of exactly `scratch` lights counted as pooled by the scan (but not by
        // the count run): offsets overlap.
        (
            "slot boundary",
            "if (c > 0u && c <= scratch) {",
            "if (c > 0u && c < scratch) {",
        ),
        // The count adds lists that fit their slot to the pool's sums.
        (
            "slot lists summed",
            "if (total > compact.scratch) {",
            "if (total > 0u) {",
        ),
        // The fill skips the first pooled list.
        (
            "first pooled list unfilled",
            "if (kept == 0u || start < compact.scratch * list_count()) {",
            "if (kept == 0u || start <= compact.scratch * list_count()) {",
        ),
        // The count writes nothing to the slots.
        (
            "slots unwritten",
            "var kept = compact.scratch;",
            "var kept = 0u;",
        ),
        // The count writes each list to the wrong slot.
        (
            "slots overlap",
            "var start = list_index * compact.scratch;",
            "var start = list_index;",
        ),
        // The pool starts over the slots.
        (
            "pool over the slots",
            "let pool_start = scratch * lists;",
            "let pool_start = 0u;",
        ),
        // The fill leaves the slot's lights out of the pooled list.
        (
            "slot not copied",
            "for (var k = local; k < min(compact.scratch, kept); k += MAIN_THREADS) {",
            "for (var k = local; k < 0u; k += MAIN_THREADS) {",
        ),
        // The fill tests the slot's last light again: listed twice.
        (
            "slot's last light again",
            "fill_below = atomicLoad(&light_lists[slot_word + compact.scratch - 1u]) + 1u;",
            "fill_below = atomicLoad(&light_lists[slot_word + compact.scratch - 1u]);",
        ),
        // The fill starts coarse candidates at a light index, not a position.
        (
            "fill starts too late",
            "first = select(below, compact.scratch, from_coarse);",
            "first = select(compact.scratch, below, from_coarse);",
        ),
    ];
    for (what, from, to) in slot_mutations {
        let m = Mutated::new(&mut r, from, to);
        caught(
            what,
            scratch_exactness_failures(m.r, &harada, (64, 36), &SOME, Scratch::OwnCount),
        );
    }
}
