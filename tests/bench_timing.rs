//! The sweep's timing method on a real device: the graphs of a point are warmed up for at
//! least `warmup_seconds` of wall-clock time, then timed in `rounds` interleaved rounds
//! whose spread each row reports.

use lightgraph::bench::sweep::{self, Sweep};
use lightgraph::render::Renderer;
use std::path::Path;

const SWEEP: &str = r#"Sweep(
    scenes: ["builtin:depth_discontinuity"],
    graphs: ["forward_plus.ron", "tiled_deferred.ron"],
    lights: [16],
    resolutions: [(64, 36)],
    warmup: 1,
    warmup_seconds: 0.4,
    frames: 6,
    rounds: 3,
    brute_force_limit: 0,
    light_stats: false,
)"#;

#[test]
fn warms_up_by_time_and_reports_the_spread_of_interleaved_rounds() {
    let plan = Sweep::parse(SWEEP, Path::new("timing.ron")).expect("the sweep parses");
    let mut renderer = Renderer::headless().expect("a wgpu adapter (lavapipe on CI)");
    let rows = sweep::run(&plan, Path::new("."), &mut renderer, |_| {}).expect("sweep");
    assert_eq!(rows.len(), 2);
    for r in &rows {
        let warmup = r
            .warmup_s
            .expect("every row says how long the warm-up took");
        assert!(warmup >= 0.4, "{}: warm-up {warmup} s < 0.4 s", r.technique);
        if !renderer.ctx.has_timestamps {
            eprintln!("{}: no timestamp queries, times not checked", r.technique);
            continue;
        }
        assert_eq!(r.rounds, Some(3), "{}", r.technique);
        let (lo, hi) = (r.round_ms_min.unwrap(), r.round_ms_max.unwrap());
        let median = r.frame_ms.unwrap().median;
        // At least half of every round's frames lie at or above its median, so at least
        // half of all frames lie above the smallest round median (and likewise below the
        // largest): the overall median lies between them.
        assert!(
            lo <= median && median <= hi,
            "{}: median {median} outside rounds {lo}..{hi}",
            r.technique
        );
    }
}

#[test]
fn a_negative_warm_up_is_refused_with_its_line() {
    let bad = SWEEP.replace("warmup_seconds: 0.4", "warmup_seconds: -1.0");
    let e = Sweep::parse(&bad, Path::new("timing.ron"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("timing.ron") && e.contains("7: warmup_seconds -1"),
        "{e}"
    );
}
