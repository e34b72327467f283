//! PNG plots of frame time against light count and against error, drawn with plotters.

use super::{BenchRow, ReportError};
use plotters::prelude::*;
use std::collections::BTreeMap;
use std::path::Path;

static FONT: &[u8] = include_bytes!("../fonts/DejaVuSansMono.ttf");

fn register_fonts() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        for family in ["sans-serif", "serif", "monospace"] {
            plotters::style::register_font(family, plotters::style::FontStyle::Normal, FONT)
                .unwrap_or_else(|_| panic!("bundled font is a valid TrueType font"));
        }
    });
}

/// Size of the plot PNGs.
pub const PLOT_SIZE: (u32, u32) = (1024, 640);

/// A point: (x, median, p10, p90).
type Point = (f64, f64, f64, f64);
/// Labelled series of points, each sorted by x, in legend order.
type Series = Vec<(String, Vec<Point>)>;

/// Axis label: integers as integers, otherwise up to 4 significant digits, scientific notation
/// outside `[1e-3, 1e5)`.
fn axis_label(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    if x.abs() < 1e-3 || x.abs() >= 1e5 {
        return format!("{x:.1e}");
    }
    if x.fract() == 0.0 {
        return format!("{x:.0}");
    }
    let digits = (3 - x.abs().log10().floor() as i32).clamp(0, 6) as usize;
    let s = format!("{x:.digits$}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Which axes of a plot are logarithmic.
#[derive(Clone, Copy)]
struct LogAxes {
    x: bool,
    y: bool,
}

fn render_plot(
    path: &Path,
    title: &str,
    x_desc: &str,
    log: LogAxes,
    series: &Series,
) -> Result<(), ReportError> {
    let log_x = log.x;
    register_fonts();
    let (w, h) = PLOT_SIZE;
    let mut buf = vec![0u8; (w * h * 3) as usize];
    let plot_err = |e: &dyn std::fmt::Display| ReportError::Plot {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(&e))?;
        let pts = series.iter().flat_map(|(_, p)| p);
        let (mut x0, mut x1, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
        let mut y0 = f64::INFINITY;
        for &(x, _, yl, yh) in pts {
            x0 = x0.min(x);
            x1 = x1.max(x);
            y1 = y1.max(yh);
            y0 = y0.min(yl);
        }
        if !x0.is_finite() {
            (x0, x1) = (1.0, 10.0);
        }
        if log_x {
            x0 = x0.max(1e-12);
            x1 = x1.max(x0 * 10.0);
            (x0, x1) = (x0 / 1.5, x1 * 1.5);
        } else {
            let pad = ((x1 - x0) * 0.05).max(x1.abs() * 0.05).max(1e-9);
            // Errors are non-negative: start the axis at 0 so "exact" sits on the axis.
            (x0, x1) = (if x0 >= 0.0 { 0.0 } else { x0 - pad }, x1 + pad);
        }
        let (y0, y1) = match (log.y, y1 > 0.0) {
            (true, true) => {
                let y0 = if y0 > 0.0 { y0 } else { y1 * 1e-3 };
                (y0 / 1.5, y1.max(y0 * 10.0) * 1.5)
            }
            (true, false) => (0.1, 10.0),
            (false, true) => (0.0, y1 * 1.1),
            (false, false) => (0.0, 1.0),
        };
        let mut builder = ChartBuilder::on(&root);
        builder
            .caption(title, ("sans-serif", 24))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(72);
        macro_rules! draw {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(x_desc)
                    .x_label_formatter(&|x: &f64| axis_label(*x))
                    .y_label_formatter(&|y: &f64| axis_label(*y))
                    .y_desc(if log.y {
                        "frame time, median (ms, log); bars p10-p90"
                    } else {
                        "frame time, median (ms); bars p10-p90"
                    })
                    .draw()
                    .map_err(|e| plot_err(&e))?;
                for (i, (name, points)) in series.iter().enumerate() {
                    let color = Palette99::pick(i).to_rgba();
                    chart
                        .draw_series(LineSeries::new(
                            points.iter().map(|p| (p.0, p.1)),
                            color.stroke_width(2),
                        ))
                        .map_err(|e| plot_err(&e))?
                        .label(name.as_str())
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                        });
                    chart
                        .draw_series(
                            points
                                .iter()
                                .map(|p| Circle::new((p.0, p.1), 4, color.filled())),
                        )
                        .map_err(|e| plot_err(&e))?;
                    chart
                        .draw_series(points.iter().map(|p| {
                            PathElement::new(vec![(p.0, p.2), (p.0, p.3)], color.stroke_width(1))
                        }))
                        .map_err(|e| plot_err(&e))?;
                }
                chart
                    .configure_series_labels()
                    .position(SeriesLabelPosition::UpperLeft)
                    .background_style(&WHITE.mix(0.85))
                    .border_style(&BLACK)
                    .draw()
                    .map_err(|e| plot_err(&e))?;
            }};
        }
        match (log_x, log.y) {
            (true, true) => draw!(builder
                .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
                .map_err(|e| plot_err(&e))?),
            (true, false) => draw!(builder
                .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
                .map_err(|e| plot_err(&e))?),
            (false, true) => draw!(builder
                .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
                .map_err(|e| plot_err(&e))?),
            (false, false) => draw!(builder
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(|e| plot_err(&e))?),
        }
        root.present().map_err(|e| plot_err(&e))?;
    }
    crate::bench::image_io::write_png_rgb8(path, buf, w, h)?;
    Ok(())
}

/// Whether `rows` hold more than one scene: each scene's points are then series of their
/// own, so no line joins points of two scenes.
fn several_scenes(rows: &[BenchRow]) -> bool {
    rows.iter().any(|r| r.scene != rows[0].scene)
}

/// A row's series name: its technique, after its scene where the rows hold several.
fn series_name(r: &BenchRow, several_scenes: bool) -> String {
    if several_scenes {
        format!("{}: {}", r.scene, r.technique)
    } else {
        r.technique.clone()
    }
}

/// The series of frame time against light count: one per technique (per scene and
/// technique where the rows hold several scenes), each sorted by light count.
fn time_vs_lights_series(rows: &[BenchRow]) -> Series {
    let scenes = several_scenes(rows);
    let mut series: BTreeMap<String, Vec<Point>> = BTreeMap::new();
    for r in rows.iter().filter(|r| r.light_count > 0) {
        if let Some(t) = r.frame_ms {
            series.entry(series_name(r, scenes)).or_default().push((
                r.light_count as f64,
                t.median,
                t.p10,
                t.p90,
            ));
        }
    }
    series
        .into_iter()
        .map(|(name, mut points)| {
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            (name, points)
        })
        .collect()
}

/// Plot median frame time (p10–p90 bars) against light count (log x), one line per technique
/// (and scene, where the rows hold several).
pub fn plot_time_vs_lights(path: impl AsRef<Path>, rows: &[BenchRow]) -> Result<(), ReportError> {
    let series = time_vs_lights_series(rows);
    render_plot(
        path.as_ref(),
        "Frame time vs light count",
        "lights (log)",
        LogAxes { x: true, y: false },
        &series,
    )
}

/// Plot median frame time (p10–p90 bars) against RMSE (linear x from 0; rows without RMSE are
/// left out), one series per technique, points joined in order of RMSE (a parameter sweep then
/// draws its time/error trade-off curve). If the rows hold several light counts, each
/// (technique, light count) pair is its own series, labelled `technique @ N lights`, and
/// several scenes put the scene before it, so points of different scenes or sizes are
/// never joined.
pub fn plot_time_vs_error(path: impl AsRef<Path>, rows: &[BenchRow]) -> Result<(), ReportError> {
    let with_error = || {
        rows.iter()
            .filter(|r| r.rmse.is_some_and(f64::is_finite) && r.frame_ms.is_some())
    };
    let first_count = with_error().next().map(|r| r.light_count);
    let several_counts = with_error().any(|r| Some(r.light_count) != first_count);
    let scenes = several_scenes(rows);
    let mut series: BTreeMap<(String, u32), Vec<Point>> = BTreeMap::new();
    for r in with_error() {
        if let (Some(e), Some(t)) = (r.rmse, r.frame_ms) {
            let key = (
                series_name(r, scenes),
                if several_counts { r.light_count } else { 0 },
            );
            series
                .entry(key)
                .or_default()
                .push((e, t.median, t.p10, t.p90));
        }
    }
    let series: Series = series
        .into_iter()
        .map(|((technique, lights), mut points)| {
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            let name = if several_counts {
                format!("{technique} @ {lights} lights")
            } else {
                technique
            };
            (name, points)
        })
        .collect();
    render_plot(
        path.as_ref(),
        "Frame time vs error",
        "RMSE vs reference (linear)",
        LogAxes { x: false, y: false },
        &series,
    )
}

/// A graph's series in [`plot_time_vs_seed_error`]: its name (the last path component)
/// without `k<N>` tokens, so graphs that differ only in their sample count (the stochastic
/// graphs' `stochastic_k4_off`) form one curve: `stochastic_off`.
fn family(technique: &str) -> String {
    let stem = technique.rsplit('/').next().unwrap_or(technique);
    let is_count =
        |t: &&str| t.len() > 1 && t.starts_with('k') && t[1..].chars().all(|c| c.is_ascii_digit());
    stem.split('_')
        .filter(|t| !is_count(t))
        .collect::<Vec<_>>()
        .join("_")
}

/// Plot median frame time (p10–p90 bars) against the expected relative MSE of one frame,
/// `seed_rel_bias2 + seed_rel_variance` (rows without seed columns are left out): the error
/// of a stochastic graph without the luck of one frame. Both axes are logarithmic (errors
/// and times span decades: the atlas beside one-sample frames); errors of 0 or below are
/// drawn at the left edge, a third of the smallest positive one. Graphs that differ
/// only in a `k<N>` token of their name form one series (`family`), joined in order of
/// error: a sample-count sweep draws its trade-off curve. Where the rows hold several
/// scenes or light counts, those are part of the series, as in [`plot_time_vs_error`].
pub fn plot_time_vs_seed_error(
    path: impl AsRef<Path>,
    rows: &[BenchRow],
) -> Result<(), ReportError> {
    let with_error = || {
        rows.iter().filter_map(|r| {
            let e = r.seed_rel_bias2? + r.seed_rel_variance?;
            Some((r, e, r.frame_ms?)).filter(|_| e.is_finite())
        })
    };
    let first = with_error()
        .next()
        .map(|(r, ..)| (r.scene.clone(), r.light_count));
    let several = with_error().any(|(r, ..)| Some((r.scene.clone(), r.light_count)) != first);
    // Log axes: an error of 0 (the reference, exact graphs) or a slightly negative one is
    // drawn a third of the way below the smallest positive error, at the axis's left edge.
    let smallest = with_error()
        .map(|(_, e, _)| e)
        .filter(|&e| e > 0.0)
        .fold(f64::INFINITY, f64::min);
    let floor = if smallest.is_finite() {
        smallest / 3.0
    } else {
        1e-6
    };
    let mut series: BTreeMap<String, Vec<Point>> = BTreeMap::new();
    for (r, e, t) in with_error() {
        let mut name = family(&r.technique);
        if several {
            name = format!("{name} @ {} {} lights", r.scene, r.light_count);
        }
        series
            .entry(name)
            .or_default()
            .push((e.max(floor), t.median, t.p10, t.p90));
    }
    let series: Series = series
        .into_iter()
        .map(|(name, mut points)| {
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            (name, points)
        })
        .collect();
    render_plot(
        path.as_ref(),
        "Frame time vs expected error over seeds",
        "rel MSE expected of one frame: bias² + variance over seeds (log; 0 at the left edge)",
        LogAxes { x: true, y: true },
        &series,
    )
}

/// Time (y, ms) against error (x) for labelled (error, ms) series: the VPL error sweep.
pub fn plot_time_vs_error_points(
    path: impl AsRef<Path>,
    title: &str,
    x_desc: &str,
    series: &[(String, Vec<(f64, f64)>)],
) -> Result<(), ReportError> {
    let series: Series = series
        .iter()
        .map(|(name, pts)| {
            let mut p: Vec<Point> = pts.iter().map(|&(e, t)| (e, t, t, t)).collect();
            p.sort_by(|a, b| a.0.total_cmp(&b.0));
            (name.clone(), p)
        })
        .collect();
    render_plot(
        path.as_ref(),
        title,
        x_desc,
        LogAxes { x: true, y: false },
        &series,
    )
}

#[cfg(test)]
mod tests {
    use super::{axis_label, family, time_vs_lights_series};
    use crate::bench::report::{BenchRow, TimingSummary};

    fn row(scene: &str, technique: &str, lights: u32, ms: f64) -> BenchRow {
        BenchRow {
            scene: scene.into(),
            technique: technique.into(),
            light_count: lights,
            frame_ms: Some(TimingSummary {
                median: ms,
                p10: ms,
                p90: ms,
            }),
            ..Default::default()
        }
    }

    /// A sweep over two scenes draws each scene's light-count curve apart: a line that
    /// joined the gallery's 1,024-light point to the chairs' would be no curve at all.
    #[test]
    fn each_scene_has_its_own_light_count_curves() {
        let mut rows = Vec::new();
        for (scene, ms) in [("gallery", 1.0), ("chairs", 2.0)] {
            for technique in ["exact", "sampled"] {
                for lights in [4096, 1024] {
                    rows.push(row(scene, technique, lights, ms + f64::from(lights) / 1e4));
                }
            }
        }
        let series = time_vs_lights_series(&rows);
        let names: Vec<&str> = series.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(
            names,
            [
                "chairs: exact",
                "chairs: sampled",
                "gallery: exact",
                "gallery: sampled"
            ]
        );
        for (name, points) in &series {
            let xs: Vec<f64> = points.iter().map(|p| p.0).collect();
            assert_eq!(xs, [1024.0, 4096.0], "{name}");
            let base = if name.starts_with("chairs") { 2.0 } else { 1.0 };
            assert!(
                points
                    .iter()
                    .all(|p| (p.1 - base - p.0 / 1e4).abs() < 1e-12),
                "{name}"
            );
        }
        // One scene: the techniques alone name the series.
        let one: Vec<BenchRow> = rows.into_iter().filter(|r| r.scene == "gallery").collect();
        let names: Vec<String> = time_vs_lights_series(&one)
            .into_iter()
            .map(|(n, _)| n)
            .collect();
        assert_eq!(names, ["exact", "sampled"]);
    }

    #[test]
    fn sample_counts_are_dropped_from_the_series_name() {
        assert_eq!(
            family("../benches/graphs/stochastic_k4_spatiotemporal"),
            "stochastic_spatiotemporal"
        );
        assert_eq!(family("stochastic_k16_off"), "stochastic_off");
        assert_eq!(
            family("visibility_raycast_shadows_naive"),
            "visibility_raycast_shadows_naive"
        );
        assert_eq!(family("keep_k_kx"), "keep_k_kx");
    }

    #[test]
    fn axis_labels_are_short() {
        assert_eq!(axis_label(0.0), "0");
        assert_eq!(axis_label(1000.0), "1000");
        assert_eq!(axis_label(0.15000000000000002), "0.15");
        assert_eq!(axis_label(0.39999999), "0.4");
        assert_eq!(axis_label(12.5), "12.5");
        assert_eq!(axis_label(2e-5), "2.0e-5");
    }
}
