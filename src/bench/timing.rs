//! How a sweep times the graphs of one point. A count of warm-up frames does not bring a
//! GPU to its clocks (five 2 ms frames left an H200 near idle, and the same point read 1.74,
//! 3.43 and 7.56 ms in three runs), so:
//! - every graph of the point runs in turn until `warmup_seconds` of wall-clock time have
//!   passed (and each has run `warmup` frames);
//! - then `rounds` rounds, each running every graph for its share of `frames` frames, the
//!   order rotated each round so no graph always runs after the same one;
//! - each graph's time is the median of its frames, its spread the range of its round
//!   medians; the SM clock is read before the warm-up and after the last round.

use super::gpu_clock::{self, SmClock};
use crate::render::{PreparedFrame, RenderError, Renderer};
use std::time::{Duration, Instant};

/// The sweep's timing settings.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Method {
    pub(crate) warmup_frames: u32,
    pub(crate) warmup_seconds: f64,
    pub(crate) rounds: u32,
    /// Timed frames per graph over all rounds.
    pub(crate) frames: u32,
}

impl Method {
    /// Rounds that run: `rounds`, at least 1, at most one a timed frame.
    pub(crate) fn round_count(&self) -> u32 {
        self.rounds.max(1).min(self.frames)
    }
    /// Frames each graph runs in one round: `frames` split over the rounds, rounded up.
    pub(crate) fn frames_per_round(&self) -> u32 {
        match self.round_count() {
            0 => 0,
            r => self.frames.div_ceil(r),
        }
    }
}

/// One graph's timings on a point (empty where the adapter has no timestamps).
#[derive(Clone, Debug, Default)]
pub(crate) struct GraphTimes {
    /// Whole-frame GPU time of every timed frame, ms (the sum of its passes).
    pub(crate) frames: Vec<f64>,
    /// Every pass's GPU time per frame, ms, in schedule order.
    pub(crate) per_pass: Vec<(String, Vec<f64>)>,
    /// The median frame of each round, ms.
    pub(crate) round_medians: Vec<f64>,
}

/// What timing one point gave.
#[derive(Clone, Debug)]
pub(crate) struct PointTimes {
    /// Per graph, in the order given.
    pub(crate) graphs: Vec<GraphTimes>,
    /// Wall-clock time the warm-up took.
    pub(crate) warmup: Duration,
    pub(crate) clock_start: Option<SmClock>,
    pub(crate) clock_end: Option<SmClock>,
}

/// Warms up and times `frames` (one per graph of a point) by [`Method`].
pub(crate) fn time_point(
    frames: &[&PreparedFrame],
    renderer: &Renderer,
    method: &Method,
) -> Result<PointTimes, RenderError> {
    time_point_with(frames, renderer, method, &mut |_| Ok(()))
}

/// [`time_point`] calling `before(graph)` ahead of every frame it runs (warm-up and
/// timed), e.g. to move the lights.
pub(crate) fn time_point_with(
    frames: &[&PreparedFrame],
    renderer: &Renderer,
    method: &Method,
    before: &mut dyn FnMut(usize) -> Result<(), RenderError>,
) -> Result<PointTimes, RenderError> {
    let clock_start = gpu_clock::read();
    let started = Instant::now();
    let warmup_time = Duration::from_secs_f64(method.warmup_seconds.clamp(0.0, 3600.0));
    let mut warmed = 0;
    while !frames.is_empty() && (warmed < method.warmup_frames || started.elapsed() < warmup_time) {
        for (g, f) in frames.iter().enumerate() {
            before(g)?;
            f.execute(renderer)?;
        }
        warmed += 1;
    }
    let warmup = started.elapsed();
    let mut graphs = vec![GraphTimes::default(); frames.len()];
    let per_round = method.frames_per_round();
    for round in 0..method.round_count() as usize {
        for k in 0..frames.len() {
            let g = (k + round) % frames.len();
            let mut this_round = Vec::with_capacity(per_round as usize);
            for _ in 0..per_round {
                before(g)?;
                if let Some(times) = frames[g].execute(renderer)? {
                    let total = times.iter().map(|t| t.1).sum::<f64>();
                    this_round.push(total);
                    record_passes(&mut graphs[g].per_pass, times);
                }
            }
            if let Some(m) = median(&this_round) {
                graphs[g].round_medians.push(m);
            }
            graphs[g].frames.extend(this_round);
        }
    }
    Ok(PointTimes {
        graphs,
        warmup,
        clock_start,
        clock_end: gpu_clock::read(),
    })
}

fn record_passes(per_pass: &mut Vec<(String, Vec<f64>)>, times: Vec<(String, f64)>) {
    for (name, ms) in times {
        match per_pass.iter_mut().find(|p| p.0 == name) {
            Some(p) => p.1.push(ms),
            None => per_pass.push((name, vec![ms])),
        }
    }
}

fn median(samples: &[f64]) -> Option<f64> {
    super::report::summarize(samples).map(|s| s.median)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_split_over_rounds() {
        let m = |frames, rounds| Method {
            warmup_frames: 0,
            warmup_seconds: 0.0,
            rounds,
            frames,
        };
        let split = |m: Method| (m.round_count(), m.frames_per_round());
        assert_eq!(split(m(30, 5)), (5, 6));
        assert_eq!(split(m(31, 5)), (5, 7));
        assert_eq!(split(m(2, 5)), (2, 1));
        assert_eq!(split(m(4, 0)), (1, 4));
        assert_eq!(split(m(0, 5)), (0, 0));
    }
}
