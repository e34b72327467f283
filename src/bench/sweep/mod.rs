//! Benchmark sweeps: scenes × light counts × resolutions × graphs. The graphs of a point
//! are timed together on the GPU (warmed up by time, then interleaved rounds: see
//! `bench::timing`) and each is compared with the reference image of the same scene
//! (brute force unless the sweep names another graph).

use super::cases::SceneCase;
use super::timing;
use crate::render::RenderError;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use thiserror::Error;

mod runner;
mod seeds;
pub use runner::{run, with_light_count, SweepEvent};

/// A sweep file (RON, scene-file extensions: `Some(..)` may be left out, `Random(count: ..)`).
/// Every point is a scene × case × light count × resolution × graph.
#[derive(Clone, Debug, Deserialize)]
#[serde(rename = "Sweep", deny_unknown_fields)]
pub struct Sweep {
    /// `builtin:NAME` or a scene file path (relative to the sweep file).
    pub(crate) scenes: Vec<String>,
    /// Graph files, relative to the project's graphs/ folder.
    pub graphs: Vec<String>,
    /// Light counts; empty keeps each scene's own lights. Lights are placed uniformly
    /// in the scene bounds (AMD sample: radius 0.075 × |half-extent|, half spots).
    #[serde(default)]
    pub lights: Vec<u32>,
    /// Variations of every scene (lights, ranges, intensities, near/far, camera at a light's
    /// centre), applied after the light count: see [`SceneCase`]. Empty runs the scenes as
    /// they are.
    #[serde(default)]
    pub(crate) cases: Vec<SceneCase>,
    /// Output sizes (width, height), each side 1..=16384.
    pub resolutions: Vec<(u32, u32)>,
    /// Warm-up frames every graph of a point runs at least.
    #[serde(default = "default_warmup")]
    pub warmup: u32,
    /// Wall-clock seconds the graphs of a point run, in turn, before timing starts: GPUs
    /// reach their clocks after about a second of work.
    #[serde(default = "default_warmup_seconds")]
    pub warmup_seconds: f64,
    /// Timed frames per graph, split over `rounds` rounds (rounded up).
    #[serde(default = "default_frames")]
    pub frames: u32,
    /// Rounds of timed frames; each runs every graph of the point in turn.
    #[serde(default = "default_rounds")]
    pub rounds: u32,
    /// Above this many lights the reference is not run (no error columns).
    #[serde(default = "default_brute_force_limit")]
    pub(crate) brute_force_limit: u32,
    /// The graph whose image the error columns compare against, like `graphs` (default
    /// `brute_force.ron`). Brute force does not trace shadows: name a shadow-tracing graph to
    /// compare ray-cast shadows with something shadowed.
    #[serde(default = "default_reference")]
    pub(crate) reference: String,
    /// Per-graph exceptions to `reference`: graph → its reference graph, e.g.
    /// `{"raycast_shadows.ron": "raycast_shadows_naive.ron"}`. Keys must be in `graphs`.
    #[serde(default)]
    pub(crate) references: BTreeMap<String, String>,
    /// Render an extra frame per point for the light statistics (the listed/exact column);
    /// it costs as much as a brute-force frame.
    #[serde(default = "yes")]
    pub(crate) light_stats: bool,
    /// Seconds of light motion between frames: every warm-up and timed frame first moves
    /// the lights there (`PreparedFrame::update_lights`). See [`crate::bench::animate`].
    #[serde(default)]
    pub(crate) animate: Option<f64>,
    /// The spread over seeds: each graph's frame is rendered this many more times with
    /// other seeds (passes that take one, `LightSampling`, get seed + 1 ..= seed + S;
    /// other graphs render the same frame again), and the row gets the sample variance
    /// and squared bias over them on rel_mse's scale ([`crate::bench::seed_spread()`]).
    /// 0, the default, is off; else 2..=[`MAX_SEEDS`]. Needs a reference image; not with
    /// `animate`.
    #[serde(default)]
    pub seeds: u32,
}

fn yes() -> bool {
    true
}
fn default_warmup() -> u32 {
    5
}
fn default_warmup_seconds() -> f64 {
    1.0
}
fn default_frames() -> u32 {
    30
}
fn default_rounds() -> u32 {
    5
}
fn default_brute_force_limit() -> u32 {
    16384
}
fn default_reference() -> String {
    "brute_force.ron".into()
}

/// Most timed frames per graph and point: 100,000 frames of a 1 ms graph already take
/// 100 s a point; the times are kept in memory (8 bytes a frame).
pub const MAX_FRAMES: u32 = 100_000;
/// Most warm-up frames per graph and point (warming up by time is what reaches the clocks).
pub const MAX_WARMUP_FRAMES: u32 = 100_000;
/// Most points one sweep runs (scenes × cases × light counts × resolutions × graphs):
/// every point renders and times each of its graphs, so 100,000 already take days; the
/// product of five long lists would also overflow the count.
pub const MAX_POINTS: u64 = 100_000;
/// Most seeds a sweep's `seeds` asks for: each is a frame prepared (its pipelines built
/// for the seed) and rendered per graph and point.
pub const MAX_SEEDS: u32 = 1024;
/// Most rounds per point: each round keeps a median; more rounds than timed frames do not
/// run anyway (one frame a round at least).
pub const MAX_ROUNDS: u32 = 10_000;

/// `LINE: ` of the first `field:` outside comments (a whole identifier), or nothing.
fn field_line(text: &str, field: &str) -> String {
    text.lines()
        .position(|l| {
            let code = l.split("//").next().unwrap_or("");
            code.match_indices(field).any(|(i, _)| {
                let before = code[..i].chars().next_back();
                let after = code[i + field.len()..].trim_start();
                !before.is_some_and(|c| c.is_alphanumeric() || c == '_') && after.starts_with(':')
            })
        })
        .map_or(String::new(), |i| format!("{}: ", i + 1))
}

/// Why a sweep stopped.
#[derive(Debug, Error)]
pub enum SweepError {
    /// The sweep file could not be read or parsed.
    #[error("{file}: {message}")]
    File {
        /// The sweep file.
        file: PathBuf,
        /// What is wrong, with the line where known.
        message: String,
    },
    /// A scene could not be loaded or a case not applied: (scene, reason).
    #[error("scene {0}: {1}")]
    Scene(String, String),
    /// A graph could not be checked or compiled: (graph, reason).
    #[error("graph {0}: {1}")]
    Graph(String, String),
    /// Rendering a point failed on the GPU.
    #[error(transparent)]
    Render(#[from] RenderError),
}

impl Sweep {
    /// Reads and checks a sweep file; errors name the file and line.
    pub fn load(path: &Path) -> Result<Self, SweepError> {
        let text = std::fs::read_to_string(path).map_err(|e| SweepError::File {
            file: path.to_path_buf(),
            message: e.to_string(),
        })?;
        Self::parse(&text, path)
    }

    /// Parses and checks sweep text (`path` names it in messages).
    pub fn parse(text: &str, path: &Path) -> Result<Self, SweepError> {
        let error = |message: String| SweepError::File {
            file: path.to_path_buf(),
            message,
        };
        let sweep: Sweep = crate::scene::scene_file::ron_options()
            .from_str(text)
            .map_err(|e: ron::error::SpannedError| {
                error(format!(
                    "{}:{}: {}",
                    e.span.start.line, e.span.start.col, e.code
                ))
            })?;
        // Line of the first occurrence of `needle`, for errors found after parsing.
        let line_of = |needle: &str| {
            text.lines()
                .position(|l| l.contains(needle))
                .map_or(String::new(), |i| format!("{}: ", i + 1))
        };
        for (i, c) in sweep.cases.iter().enumerate() {
            c.check().map_err(|m| {
                let line = line_of(&format!("\"{}\"", c.name));
                error(format!("{line}cases[{i}] (\"{}\"): {m}", c.name))
            })?;
        }
        // Counts that size allocations and loops, checked against their limits at the
        // line of their field.
        let counts = [
            ("warmup", sweep.warmup, MAX_WARMUP_FRAMES),
            ("frames", sweep.frames, MAX_FRAMES),
            ("rounds", sweep.rounds, MAX_ROUNDS),
        ];
        for (field, value, limit) in counts {
            if value > limit {
                let line = field_line(text, field);
                return Err(error(format!(
                    "{line}{field} {value} is over the limit of {limit}"
                )));
            }
        }
        if let Some(&n) = sweep
            .lights
            .iter()
            .find(|&&n| n as u64 > crate::scene::scene_file::MAX_SCENE_LIGHTS)
        {
            let line = field_line(text, "lights");
            return Err(error(format!(
                "{line}lights {n} is over the limit of {} (a scene file's limit)",
                crate::scene::scene_file::MAX_SCENE_LIGHTS
            )));
        }
        if let Some(step) = sweep.animate.filter(|s| !(s.is_finite() && *s > 0.0)) {
            let line = line_of("animate");
            return Err(error(format!(
                "{line}animate {step} must be a finite number of seconds > 0"
            )));
        }
        if sweep.seeds == 1 || sweep.seeds > MAX_SEEDS {
            let line = field_line(text, "seeds");
            return Err(error(format!(
                "{line}seeds {} must be 0 (off) or lie in 2..={MAX_SEEDS}: a variance needs two images",
                sweep.seeds
            )));
        }
        if sweep.seeds > 0 && sweep.animate.is_some() {
            let line = field_line(text, "seeds");
            return Err(error(format!(
                "{line}seeds cannot be combined with animate: the seeded frames run with still lights, while the measured frame's history (temporal reuse) saw them move"
            )));
        }
        if !(0.0..=3600.0).contains(&sweep.warmup_seconds) {
            let line = line_of("warmup_seconds");
            return Err(error(format!(
                "{line}warmup_seconds {} must lie in 0..=3600",
                sweep.warmup_seconds
            )));
        }
        for &(w, h) in &sweep.resolutions {
            if w == 0 || h == 0 || w > 16384 || h > 16384 {
                let line = line_of("resolutions");
                return Err(error(format!(
                    "{line}resolution ({w}, {h}) must lie in 1..=16384"
                )));
            }
        }
        match sweep.points() {
            Some(n) if n <= MAX_POINTS => {}
            n => {
                let line = line_of("Sweep");
                let n = n.map_or("over 2^64".to_string(), |n| n.to_string());
                return Err(error(format!(
                    "{line}the sweep has {n} points (scenes × cases × light counts × resolutions × graphs), over the limit of {MAX_POINTS}"
                )));
            }
        }
        if let Some(g) = sweep.references.keys().find(|g| !sweep.graphs.contains(g)) {
            let line = line_of("references");
            return Err(error(format!(
                "{line}references names graph \"{g}\", which is not in graphs"
            )));
        }
        Ok(sweep)
    }

    /// The reference graph the error columns of `graph` compare against.
    pub fn reference_for(&self, graph: &str) -> &str {
        self.references.get(graph).unwrap_or(&self.reference)
    }

    /// The timing settings.
    pub(crate) fn method(&self) -> timing::Method {
        timing::Method {
            warmup_frames: self.warmup,
            warmup_seconds: self.warmup_seconds,
            rounds: self.rounds,
            frames: self.frames,
        }
    }

    /// Number of points the sweep runs (at most [`MAX_POINTS`] once parsed).
    pub fn point_count(&self) -> usize {
        self.points()
            .map_or(usize::MAX, |n| n.min(usize::MAX as u64) as usize)
    }

    /// scenes × cases × light counts × resolutions × graphs; `None` past u64.
    fn points(&self) -> Option<u64> {
        [
            self.scenes.len(),
            self.cases.len().max(1),
            self.lights.len().max(1),
            self.resolutions.len(),
            self.graphs.len(),
        ]
        .iter()
        .try_fold(1u64, |product, &n| product.checked_mul(n as u64))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 8,000 entries in each of the five lists: 3.3e19 points, past u64 (the count
    /// wrapped in release builds and panicked with overflow checks; the sweep fuzz
    /// target's binary found it), refused at the `Sweep(` line.
    #[test]
    fn too_many_points_are_refused_even_past_u64() {
        let list = |item: &str| vec![item; 8000].join(", ");
        let text = format!(
            "Sweep(\n scenes: [{}],\n graphs: [{}],\n lights: [{}],\n resolutions: [{}],\n cases: [{}],\n)",
            list("\"builtin:harada\""),
            list("\"a.ron\""),
            list("1"),
            list("(1, 1)"),
            list("(name: \"c\")"),
        );
        let e = Sweep::parse(&text, "big.ron".as_ref())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("big.ron: 1: the sweep has over 2^64 points")
                && e.contains("limit of 100000"),
            "{e}"
        );
        let fewer = text.replace(&list("1"), "1");
        let e = Sweep::parse(&fewer, "big.ron".as_ref())
            .unwrap_err()
            .to_string();
        assert!(e.contains("has 4096000000000000 points"), "{e}");
    }

    const SWEEP: &str = r#"Sweep(
        scenes: ["builtin:chairs"],
        graphs: ["forward_plus.ron", "raycast_shadows.ron"],
        resolutions: [(16, 9)],
        references: {"raycast_shadows.ron": "raycast_shadows_naive.ron"},
    )"#;

    #[test]
    fn references_name_a_graph_per_graph() {
        let s = Sweep::parse(SWEEP, "s.ron".as_ref()).unwrap();
        assert_eq!(s.reference_for("forward_plus.ron"), "brute_force.ron");
        assert_eq!(
            s.reference_for("raycast_shadows.ron"),
            "raycast_shadows_naive.ron"
        );
        let typo = SWEEP.replace("\"raycast_shadows.ron\":", "\"raycast_shadow.ron\":");
        let e = Sweep::parse(&typo, "s.ron".as_ref())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("5: references names graph \"raycast_shadow.ron\""),
            "{e}"
        );
    }

    #[test]
    fn the_atlas_raster_sweep_parses() {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/sweeps/shadow_atlas_raster.ron");
        let s = Sweep::load(&path).unwrap_or_else(|e| panic!("{e}"));
        // Two scenes × (four atlas graphs + the ray-cast reference).
        assert_eq!(s.point_count(), 10);
        assert_eq!(
            s.reference_for("../benches/graphs/visibility_shadow_atlas_compute_cached.ron"),
            "visibility_raycast_shadows.ron"
        );
    }

    #[test]
    fn the_shadow_sweep_parses() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/sweeps/raycast_shadows.ron");
        let s = Sweep::load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.point_count(), 10);
        assert_eq!(s.reference_for("forward_plus.ron"), "brute_force.ron");
    }
}
