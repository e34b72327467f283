//! The sweep's progress bar (indicatif): one bar over all points, with the point being run as
//! its message. Everything printed during a sweep goes through [`SweepProgress::println`] or
//! [`SweepProgress::warn`] so it lands above the bar instead of through it. When stderr is not
//! a terminal indicatif hides the bar (and would drop its `println`s), so the lines are then
//! printed plainly: a CI log still gets one line per point.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Progress of a sweep of `total` points.
pub struct SweepProgress {
    bar: ProgressBar,
}

impl SweepProgress {
    /// A bar on stderr (hidden by indicatif when stderr is not a terminal).
    pub fn new(total: usize) -> Self {
        Self::with_target(total, ProgressDrawTarget::stderr())
    }

    /// A bar drawn to `target` (`ProgressDrawTarget::hidden()` in tests).
    pub fn with_target(total: usize, target: ProgressDrawTarget) -> Self {
        let bar = ProgressBar::with_draw_target(Some(total as u64), target);
        // The template is a literal: a bad one is a bug here, so fall back rather than fail.
        if let Ok(style) = ProgressStyle::with_template(
            "{elapsed_precise} [{bar:30}] {pos}/{len} eta {eta} {wide_msg}",
        ) {
            bar.set_style(style.progress_chars("=> "));
        }
        Self { bar }
    }

    /// Whether lines are printed plainly because no bar is drawn.
    pub fn is_plain(&self) -> bool {
        self.bar.is_hidden()
    }

    /// Shows the point that is starting.
    pub fn start(&self, point: &str) {
        self.bar.set_message(point.to_string());
    }

    /// Counts a finished point.
    pub fn finish_point(&self) {
        self.bar.inc(1);
    }

    /// A log line: above the bar, or on stdout when there is no bar.
    pub fn println(&self, line: &str) {
        if self.is_plain() {
            println!("{line}");
        } else {
            self.bar.println(line);
        }
    }

    /// A warning: above the bar, or on stderr when there is no bar.
    pub fn warn(&self, message: &str) {
        if self.is_plain() {
            eprintln!("warning: {message}");
        } else {
            self.bar.println(format!("warning: {message}"));
        }
    }

    /// Removes the bar once the sweep is over.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
