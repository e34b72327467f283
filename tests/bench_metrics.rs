//! Analytic checks of the bench metrics, image I/O and reports (no GPU).

use lightgraph::bench::*;

const W: u32 = 16;
const H: u32 = 8;

fn gradient() -> Vec<[f32; 4]> {
    (0..W * H)
        .map(|i| {
            let x = (i % W) as f32 / W as f32;
            let y = (i / W) as f32 / H as f32;
            [x, y, 0.5 * (x + y), 1.0]
        })
        .collect()
}

fn no_flip() -> CompareOptions {
    CompareOptions {
        flip: false,
        ..Default::default()
    }
}

#[test]
fn identical_images() {
    let a = gradient();
    let m = compare(&a, &a, W, H, &CompareOptions::default()).unwrap();
    assert_eq!(m.rmse, 0.0);
    assert_eq!(m.max_abs, 0.0);
    assert!(m.psnr.is_infinite() && m.psnr > 0.0);
    assert_eq!(m.bad_pixels, 0);
    assert_eq!(m.compared_pixels, (W * H) as usize);
    assert!(m.flip_mean.unwrap().abs() < 1e-6, "{:?}", m.flip_mean);
    assert_eq!(m.psnr_peak, 1.0);
}

#[test]
fn constant_offset_gives_known_rmse_and_psnr() {
    let a = gradient();
    let b: Vec<[f32; 4]> = a
        .iter()
        .map(|p| [p[0] + 0.125, p[1] + 0.125, p[2] + 0.125, p[3]])
        .collect();
    let m = compare(&a, &b, W, H, &no_flip()).unwrap();
    assert!((m.rmse - 0.125).abs() < 1e-6, "{}", m.rmse);
    assert!((m.max_abs - 0.125).abs() < 1e-6);
    // Reference luminance stays below 1, so the peak is 1: PSNR = 10 log10(1 / 0.125²).
    let expected = 10.0 * (1.0 / (0.125f64 * 0.125)).log10();
    assert!((m.psnr - expected).abs() < 1e-4, "{} vs {expected}", m.psnr);
    // Relative MSE, computed here in f64 from the same pixels: 0.125² / (ref² + 0.01).
    let rel: f64 = a
        .iter()
        .flat_map(|p| {
            p[..3]
                .iter()
                .map(|&r| 0.125f64.powi(2) / (f64::from(r).powi(2) + 0.01))
        })
        .sum::<f64>()
        / (a.len() * 3) as f64;
    assert!(
        (m.rel_mse - rel).abs() < 1e-6 * rel,
        "{} vs {rel}",
        m.rel_mse
    );
    assert_eq!(m.bad_pixels, (W * H) as usize);
    assert!(m.flip_mean.is_none());

    // Threshold above the offset: no bad pixels.
    let opts = CompareOptions {
        bad_pixel_threshold: 0.2,
        ..no_flip()
    };
    assert_eq!(compare(&a, &b, W, H, &opts).unwrap().bad_pixels, 0);
}

#[test]
fn single_channel_offset_and_bright_peak() {
    // Grey 4.0 reference: luminance 4 is the peak.
    let a = vec![[4.0f32, 4.0, 4.0]; (W * H) as usize];
    let b: Vec<[f32; 3]> = a.iter().map(|p| [p[0] + 0.3, p[1], p[2]]).collect();
    let m = compare(&a, &b, W, H, &no_flip()).unwrap();
    let mse: f64 = 0.09 / 3.0;
    assert!((m.rmse - mse.sqrt()).abs() < 1e-6);
    assert!((m.psnr_peak - 4.0).abs() < 1e-6);
    assert!((m.psnr - 10.0 * (16.0 / mse).log10()).abs() < 1e-3);
}

#[test]
fn rgb_and_rgba_agree() {
    let a = gradient();
    let b: Vec<[f32; 4]> = a
        .iter()
        .map(|p| [p[0] * 0.9, p[1], p[2] + 0.01, 0.0])
        .collect();
    let a3: Vec<[f32; 3]> = a.iter().map(|p| [p[0], p[1], p[2]]).collect();
    let b3: Vec<[f32; 3]> = b.iter().map(|p| [p[0], p[1], p[2]]).collect();
    let m4 = compare(&a, &b, W, H, &CompareOptions::default()).unwrap();
    let m3 = compare(&a3, &b3, W, H, &CompareOptions::default()).unwrap();
    assert_eq!(m4, m3);
}

#[test]
fn non_finite_pixels_are_counted_and_excluded() {
    let a = gradient();
    let mut b = a.clone();
    b[3][1] = f32::NAN;
    b[7] = [f32::NAN, f32::INFINITY, 0.0, 1.0]; // NaN wins
    b[9][2] = f32::NEG_INFINITY;
    let mut a2 = a.clone();
    a2[20][0] = f32::INFINITY;
    let m = compare(&a2, &b, W, H, &CompareOptions::default()).unwrap();
    assert_eq!(
        m.test_non_finite,
        NonFinite {
            nan_pixels: 2,
            inf_pixels: 1
        }
    );
    assert_eq!(
        m.reference_non_finite,
        NonFinite {
            nan_pixels: 0,
            inf_pixels: 1
        }
    );
    assert_eq!(m.compared_pixels, (W * H) as usize - 4);
    assert_eq!(m.rmse, 0.0, "finite pixels are identical");
    assert_eq!(m.bad_pixels, 4);
    assert!(m.psnr.is_infinite());
    assert!(m.flip_mean.unwrap().is_finite());
}

#[test]
fn size_mismatch_is_an_error() {
    let a = gradient();
    let err = compare(&a, &a[1..], W, H, &no_flip()).unwrap_err();
    assert!(matches!(
        err,
        MetricsError::SizeMismatch {
            reference: 128,
            test: 127,
            ..
        }
    ));
    assert!(err.to_string().contains("16x8"));
}

#[test]
fn flip_grows_with_the_error() {
    let a = gradient();
    let small: Vec<[f32; 4]> = a.iter().map(|p| [p[0] + 0.02, p[1], p[2], 1.0]).collect();
    let large: Vec<[f32; 4]> = a.iter().map(|p| [p[0] + 0.5, p[1], p[2], 1.0]).collect();
    let t = Tonemap::default();
    let ppd = CompareOptions::default().pixels_per_degree;
    let fs = flip_mean(&a, &small, W, H, &t, ppd).unwrap();
    let fl = flip_mean(&a, &large, W, H, &t, ppd).unwrap();
    assert!(fs > 0.0 && fs < fl && fl <= 1.0, "{fs} {fl}");
}

#[test]
fn exr_round_trip_is_bit_exact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sub/out.exr");
    let specials = [
        0.0,
        -0.0,
        1.0,
        -2.5,
        1e-40, // subnormal
        f32::MIN_POSITIVE,
        3.4e38,
        65504.0,
        1.0 / 3.0,
        std::f32::consts::PI,
    ];
    let pixels: Vec<[f32; 4]> = (0..W * H)
        .map(|i| {
            let s = specials[i as usize % specials.len()];
            [
                s,
                i as f32 * 0.001_7,
                -(i as f32).sqrt(),
                1.0 - i as f32 / 1000.0,
            ]
        })
        .collect();
    write_exr(&path, &pixels, W, H).unwrap();
    let back = read_exr(&path).unwrap();
    assert_eq!((back.width, back.height), (W, H));
    for (a, b) in pixels.iter().zip(&back.pixels) {
        assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits), "{a:?} vs {b:?}");
    }

    // RGB input gets alpha 1.
    let rgb: Vec<[f32; 3]> = pixels.iter().map(|p| [p[0], p[1], p[2]]).collect();
    write_exr(&path, &rgb, W, H).unwrap();
    let back = read_exr(&path).unwrap();
    assert!(back.pixels.iter().all(|p| p[3] == 1.0));
    assert_eq!(back.pixels[5][0].to_bits(), rgb[5][0].to_bits());
}

#[test]
fn exr_keeps_nan_and_inf() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nan.exr");
    let mut pixels = gradient();
    pixels[0][0] = f32::NAN;
    pixels[1][1] = f32::INFINITY;
    write_exr(&path, &pixels, W, H).unwrap();
    let back = read_exr(&path).unwrap();
    assert!(back.pixels[0][0].is_nan());
    assert_eq!(back.pixels[1][1], f32::INFINITY);
}

#[test]
fn io_errors_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.exr");
    let err = read_exr(&missing).unwrap_err();
    assert!(err.to_string().contains("missing.exr"), "{err}");
    let err = write_exr(dir.path().join("bad.exr"), &gradient()[1..], W, H).unwrap_err();
    assert!(matches!(err, ImageIoError::SizeMismatch { .. }));
    assert!(err.to_string().contains("bad.exr"), "{err}");
}

#[test]
fn png_is_tonemapped_srgb() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.png");
    // Linear 1.0 through Reinhard is 0.5 display-linear, sRGB-encoded 0.7354 -> 188.
    let pixels = vec![[1.0f32, 0.0, f32::NAN]; (W * H) as usize];
    write_png_tonemapped(&path, &pixels, W, H, &Tonemap::default()).unwrap();
    let img = image::open(&path).unwrap().into_rgb8();
    assert_eq!(img.dimensions(), (W, H));
    assert_eq!(img.get_pixel(3, 3).0, [188, 0, 0]);
}

#[test]
fn difference_png_is_a_heat_map() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("diff.png");
    let a = gradient();
    let mut b = a.clone();
    b[5][0] += 2.0;
    b[6][2] += 1.0;
    b[7][1] = f32::NAN;
    let top = write_difference_png(&path, &a, &b, W, H, HeatScale::Auto).unwrap();
    assert!((top - 2.0).abs() < 1e-6);
    let img = image::open(&path).unwrap().into_rgb8();
    assert_eq!(img.get_pixel(5, 0).0, heat_color(1.0));
    assert_eq!(img.get_pixel(6, 0).0, heat_color(0.5));
    assert_eq!(img.get_pixel(7, 0).0, metrics::HEATMAP_NAN_COLOR);
    assert_eq!(img.get_pixel(0, 0).0, [0, 0, 0]);

    let flip_path = dir.path().join("flip.png");
    write_flip_png(&flip_path, &a, &b, W, H, &CompareOptions::default()).unwrap();
    assert_eq!(
        image::open(&flip_path).unwrap().into_rgb8().dimensions(),
        (W, H)
    );
}

fn rows() -> Vec<BenchRow> {
    let mut rows = Vec::new();
    for (tech, scale, err) in [
        ("brute_force", 0.01, None),
        ("forward_plus", 0.001, Some(1e-4)),
        ("clustered, \"q\"", 0.0012, Some(3e-3)),
    ] {
        for lights in [64u32, 1024, 16384] {
            let ms = 0.5 + scale * lights as f64;
            rows.push(BenchRow {
                scene: "sponza".into(),
                technique: tech.into(),
                params: "tile=16".into(),
                light_count: lights,
                width: 640,
                height: 360,
                adapter: "llvmpipe (LLVM 19, 256 bits)".into(),
                frame_ms: Some(spread(ms)),
                pass_ms: vec![
                    ("depth".into(), spread(0.2)),
                    ("shade".into(), spread(ms - 0.2)),
                ],
                rmse: err,
                psnr: err.map(|_| f64::INFINITY),
                max_lights_per_tile: Some(lights / 8),
                ..Default::default()
            });
        }
    }
    rows.push(BenchRow {
        technique: "forward_plus".into(),
        light_count: 1,
        pass_ms: vec![("cull".into(), spread(0.05))],
        ..Default::default()
    });
    rows
}

/// A timing with p10 at 0.9 and p90 at 1.2 of the median.
fn spread(median: f64) -> TimingSummary {
    TimingSummary {
        median,
        p10: median * 0.9,
        p90: median * 1.2,
    }
}

#[test]
fn csv_and_markdown() {
    let rows = rows();
    let csv = to_csv(&rows);
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), rows.len() + 1);
    let header: Vec<&str> = lines[0].split(',').collect();
    assert_eq!(&header[..report::CSV_COLUMNS.len()], &report::CSV_COLUMNS);
    assert_eq!(
        &header[report::CSV_COLUMNS.len()..],
        &[
            "pass_ms:depth",
            "pass_ms_p10:depth",
            "pass_ms_p90:depth",
            "pass_ms:shade",
            "pass_ms_p10:shade",
            "pass_ms_p90:shade",
            "pass_ms:cull",
            "pass_ms_p10:cull",
            "pass_ms_p90:cull"
        ]
    );
    assert!(csv.contains("\"clustered, \"\"q\"\"\""), "{csv}");
    assert!(lines[4].contains(",inf,"), "{}", lines[4]);
    assert!(
        lines
            .last()
            .unwrap()
            .ends_with(",,,,,,,0.05,0.045000000000000005,0.06"),
        "{}",
        lines.last().unwrap()
    );

    let md = to_markdown(&rows);
    assert!(
        md.contains("| sponza | forward_plus | tile=16 | 1024 | 640x360 |"),
        "{md}"
    );
    assert!(md.contains("Per-pass GPU time, ms: median (p10–p90)"));
    assert!(md.contains("| 0.200 (0.180–0.240) |"), "{md}");
    // The untimed row has empty time cells, not zeros.
    assert!(
        md.contains("| forward_plus |  | 1 | 0x0 |  | – | – | – |"),
        "{md}"
    );
    assert!(!md.contains("No GPU times"), "some rows are timed: {md}");
    assert!(md.contains("∞"));
    let table_rows = md.lines().filter(|l| l.starts_with("| sponza")).count();
    assert_eq!(table_rows, 2 * 9);
}

#[test]
fn timing_summary() {
    let s = summarize(&[5.0, 1.0, 3.0, 2.0, 4.0, f64::NAN]).unwrap();
    assert_eq!(s.median, 3.0);
    assert!((s.p10 - 1.4).abs() < 1e-12);
    assert!((s.p90 - 4.6).abs() < 1e-12);
    assert!(summarize(&[]).is_none());
}

#[test]
fn report_writes_all_files() {
    let dir = tempfile::tempdir().unwrap();
    let files = write_report(dir.path().join("bench"), &rows()).unwrap();
    assert_eq!(files.plots_skipped, None);
    for png in [&files.time_vs_lights, &files.time_vs_error] {
        let png = png.as_ref().expect("timed rows are plotted");
        let img = image::open(png).unwrap().into_rgb8();
        assert_eq!(img.dimensions(), report::PLOT_SIZE);
        // Something besides the white background was drawn.
        assert!(img.pixels().filter(|p| p.0 != [255, 255, 255]).count() > 1000);
    }
    assert!(std::fs::read_to_string(&files.csv)
        .unwrap()
        .starts_with("scene,"));
    assert!(std::fs::read_to_string(&files.markdown)
        .unwrap()
        .starts_with("| scene"));
    assert_eq!(
        std::fs::read_to_string(&files.non_finite).unwrap(),
        "scene,technique,params,light_count,width,height,kind,x,y,r,g,b\n"
    );
    assert_eq!(files.time_vs_seed_error, None, "no row has seed columns");
    // Empty input gives empty tables and no plots.
    let empty = write_report(dir.path().join("empty"), &[]).unwrap();
    assert_eq!(empty.plots_skipped.as_deref(), Some("no rows"));
}

/// Rows with seed columns: CSV columns after rel_mse, a Markdown table of rel MSE beside
/// its variance and bias² parts, and the time against expected error plot, whose series
/// join the graphs that differ in their sample count.
#[test]
fn seed_columns_in_the_report() {
    let mut rows = Vec::new();
    for (k, ms, variance) in [(1, 0.7, 4e-3), (4, 0.95, 1e-3), (8, 1.4, 5e-4)] {
        rows.push(BenchRow {
            scene: "harada_all_casting".into(),
            technique: format!("../benches/graphs/stochastic_k{k}_off"),
            width: 64,
            height: 36,
            frame_ms: Some(spread(ms)),
            rel_mse: Some(variance * 0.5),
            seeds: Some(8),
            seed_rel_variance: Some(variance),
            seed_rel_bias2: Some(-1e-5),
            ..Default::default()
        });
    }
    let csv = to_csv(&rows);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let at = |column: &str| header.iter().position(|h| *h == column).unwrap();
    assert_eq!(
        (at("seeds"), at("seed_rel_variance"), at("seed_rel_bias2")),
        (at("rel_mse") + 1, at("rel_mse") + 2, at("rel_mse") + 3)
    );
    let second: Vec<&str> = csv.lines().nth(2).unwrap().split(',').collect();
    assert_eq!(
        [
            second[at("seeds")],
            second[at("seed_rel_variance")],
            second[at("seed_rel_bias2")]
        ],
        ["8", "0.001", "-0.00001"]
    );
    let md = to_markdown(&rows);
    assert!(
        md.contains("| harada_all_casting | ../benches/graphs/stochastic_k4_off | 0 | 64x36 | 0.950 | 8 | 5.00e-4 | 0.0010 | -1.00e-5 |"),
        "{md}"
    );
    let dir = tempfile::tempdir().unwrap();
    let files = write_report(dir.path(), &rows).unwrap();
    let png = files.time_vs_seed_error.expect("seeded rows are plotted");
    let img = image::open(png).unwrap().into_rgb8();
    assert!(img.pixels().filter(|p| p.0 != [255, 255, 255]).count() > 1000);
    // Without seed columns the plot is gone, not left stale.
    let plain: Vec<BenchRow> = rows
        .iter()
        .map(|r| BenchRow {
            seeds: None,
            ..r.clone()
        })
        .collect();
    let files = write_report(dir.path(), &plain).unwrap();
    assert_eq!(files.time_vs_seed_error, None);
    assert!(!dir.path().join("time_vs_seed_error.png").exists());
}

#[test]
fn untimed_rows_say_why_and_draw_no_plots() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bench");
    // A stale plot from a timed run must not survive an untimed one.
    write_report(&out, &rows()).unwrap();
    let mut rows = rows();
    for r in &mut rows {
        r.frame_ms = None;
        r.pass_ms.clear();
        r.untimed = Some("llvmpipe has no timestamp queries".into());
    }
    let files = write_report(&out, &rows).unwrap();
    let reason = "llvmpipe has no timestamp queries";
    assert_eq!(files.plots_skipped.as_deref(), Some(reason));
    assert_eq!((files.time_vs_lights, files.time_vs_error), (None, None));
    assert!(!out.join("time_vs_lights.png").exists());
    assert!(!out.join("time_vs_error.png").exists());
    let md = std::fs::read_to_string(&files.markdown).unwrap();
    assert!(
        md.contains("No GPU times (llvmpipe has no timestamp queries): the time columns are empty"),
        "{md}"
    );
    assert!(!md.contains("Per-pass"), "{md}");
    let csv = to_csv(&rows);
    let line = csv.lines().nth(1).unwrap();
    assert!(
        line.contains("256 bits)\",,,,"),
        "time columns are empty: {line}"
    );
}

#[test]
fn non_finite_pixels_are_listed_with_their_position() {
    let mut img = gradient();
    img[W as usize * 2 + 3][0] = f32::NAN;
    img[W as usize * 5 + 1][2] = f32::INFINITY;
    img[W as usize * 7 + 15] = [f32::NAN, f32::INFINITY, 0.0, 1.0];
    let (counts, first) = non_finite_pixels(&img, W, 2);
    assert_eq!(
        counts,
        NonFinite {
            nan_pixels: 2,
            inf_pixels: 1
        }
    );
    assert_eq!(first.len(), 2, "only the first two are listed");
    assert_eq!((first[0].x, first[0].y, first[0].kind()), (3, 2, "NaN"));
    assert_eq!((first[1].x, first[1].y, first[1].kind()), (1, 5, "Inf"));
    let row = BenchRow {
        scene: "s".into(),
        technique: "t".into(),
        non_finite_examples: first,
        ..Default::default()
    };
    let csv = non_finite_csv(&[row]);
    assert_eq!(
        csv.lines().nth(1).unwrap(),
        "s,t,,0,0,0,NaN,3,2,NaN,0.25,0.21875"
    );
    assert_eq!(
        csv.lines().nth(2).unwrap(),
        "s,t,,0,0,0,Inf,1,5,0.0625,0.625,inf"
    );
}

#[test]
fn relative_error_uses_the_pixel_or_a_floor_of_the_peak() {
    let a = vec![[4.0, 0.0, 1.0, 1.0], [0.0, 0.0, 0.0, 1.0]];
    // Bright channel off by 1e-3 relative; a black pixel off by 1e-3 (absolute).
    let b = vec![[4.004, 0.0, 1.0, 1.0], [0.001, 0.0, 0.0, 1.0]];
    let m = compare(&a, &b, 2, 1, &no_flip()).unwrap();
    assert!(
        (m.max_rel_floor - 4e-3).abs() < 1e-12,
        "{}",
        m.max_rel_floor
    );
    // The black pixel's error against the floor (1e-3 / 4e-3) dominates.
    assert!((m.max_rel - 0.25).abs() < 1e-6, "{}", m.max_rel);
    let m = compare(&a, &a, 2, 1, &no_flip()).unwrap();
    assert_eq!(m.max_rel, 0.0);
}

#[test]
fn set_metrics_fills_error_columns() {
    let a = gradient();
    let m = compare(&a, &a, W, H, &CompareOptions::default()).unwrap();
    let mut row = BenchRow::default();
    row.set_metrics(&m);
    assert_eq!(row.rmse, Some(0.0));
    assert!(row.flip_mean.unwrap() < 1e-6);
    assert_eq!(row.nan_pixels, Some(0));
}

#[test]
fn compare_exr_files() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b, small) = (
        dir.path().join("a.exr"),
        dir.path().join("b.exr"),
        dir.path().join("s.exr"),
    );
    let img = gradient();
    let shifted: Vec<[f32; 4]> = img
        .iter()
        .map(|p| [p[0] + 0.25, p[1] + 0.25, p[2] + 0.25, 1.0])
        .collect();
    write_exr(&a, &img, W, H).unwrap();
    write_exr(&b, &shifted, W, H).unwrap();
    write_exr(&small, &img[..(W * (H - 1)) as usize], W, H - 1).unwrap();
    let m = compare_files(&a, &b, &CompareOptions::default()).unwrap();
    assert!((m.rmse - 0.25).abs() < 1e-6);
    let text = m.to_string();
    assert!(
        text.contains("RMSE") && text.contains("FLIP mean"),
        "{text}"
    );
    let err = compare_files(&a, &small, &CompareOptions::default()).unwrap_err();
    assert!(err.to_string().contains("s.exr is 16x7"), "{err}");
    let err =
        compare_files(&a, dir.path().join("nope.exr"), &CompareOptions::default()).unwrap_err();
    assert!(err.to_string().contains("nope.exr"), "{err}");
}

/// `gradient()` with `offset(pixel, channel)` added to every channel.
fn offset_gradient(offset: impl Fn(usize, usize) -> f32) -> Vec<[f32; 4]> {
    gradient()
        .iter()
        .enumerate()
        .map(|(i, p)| {
            [
                p[0] + offset(i, 0),
                p[1] + offset(i, 1),
                p[2] + offset(i, 2),
                p[3],
            ]
        })
        .collect()
}

/// The mean over the reference's channels of `f(channel) / (ref² + 0.01)`, in f64: rel_mse's
/// weighting, written out here.
fn rel_mean(reference: &[[f32; 4]], f: impl Fn(usize, usize) -> f64) -> f64 {
    let mut sum = 0.0;
    for (i, p) in reference.iter().enumerate() {
        for (c, &r) in p[..3].iter().enumerate() {
            sum += f(i, c) / (f64::from(r).powi(2) + 0.01);
        }
    }
    sum / (reference.len() * 3) as f64
}

/// Four seeds at ref + b + a·(+1, −1, +1, −1), a and b varying by pixel and channel:
/// their mean is ref + b and their sample variance (divided by S − 1 = 3) exactly 4a²/3,
/// so the variance column is the mean of 4a²/3 and the bias² column (the squared error
/// of the mean less the sample variance over S) the mean of b² − a²/3, both weighted as
/// rel_mse weighs a squared error. Tolerance 1e-5 relative: the images are f32, whose
/// rounding of ref + b ± a (ulp 6e-8 near 1) moves a² by about 1e-6 of itself.
#[test]
fn seed_spread_of_known_deviations() {
    let reference = gradient();
    let a = |i: usize, c: usize| 0.02 + 0.01 * ((i + c) % 5) as f32;
    let b = |i: usize, c: usize| 0.03 * ((i * 3 + c) % 4) as f32;
    let images: Vec<Vec<[f32; 4]>> = [1.0f32, -1.0, 1.0, -1.0]
        .iter()
        .map(|&sign| offset_gradient(|i, c| b(i, c) + sign * a(i, c)))
        .collect();
    let s = seed_spread(&reference, &images, W, H).unwrap();
    let a2 = |i, c| f64::from(a(i, c)).powi(2);
    let variance = rel_mean(&reference, |i, c| 4.0 * a2(i, c) / 3.0);
    let bias2 = rel_mean(&reference, |i, c| {
        f64::from(b(i, c)).powi(2) - a2(i, c) / 3.0
    });
    assert_eq!((s.seeds, s.compared_pixels), (4, (W * H) as usize));
    assert!(
        (s.rel_variance - variance).abs() <= 1e-5 * variance,
        "variance {} against {variance}",
        s.rel_variance
    );
    assert!(
        (s.rel_bias2 - bias2).abs() <= 1e-5 * bias2.abs(),
        "bias² {} against {bias2}",
        s.rel_bias2
    );
    // The two parts add up to rel_mse averaged over the seeds: the mean over seeds of
    // (x − ref)² is (m − ref)² + s²(S − 1)/S, and bias² + variance is (m − ref)² − s²/S + s².
    // The same f32 images on both sides: only f64 summation order differs.
    let mean_rel_mse = images
        .iter()
        .map(|image| {
            compare(&reference, image, W, H, &no_flip())
                .unwrap()
                .rel_mse
        })
        .sum::<f64>()
        / images.len() as f64;
    assert!(
        (s.rel_bias2 + s.rel_variance - mean_rel_mse).abs() <= 1e-12 * mean_rel_mse,
        "bias² + variance {} against the seeds' mean rel_mse {mean_rel_mse}",
        s.rel_bias2 + s.rel_variance
    );
}

/// Random seeds with a known spread: 16 images of independent uniform noise of variance
/// σ² = 0.02² around a grey reference of 0.5 plus a bias β = 0.05, 64×64 pixels. The
/// variance column estimates σ² w and the bias² column β² w, w = 1 / (0.5² + 0.01). A
/// channel's sample variance has a relative standard deviation of √(2/15 − 1.2/16) ≈ 0.24
/// (uniform noise: excess kurtosis −1.2), so their mean over 12,288 channels one of 0.22%;
/// a channel's bias² estimate, (β + e)² − s²/16 with e the mean's noise (σ/4), one of
/// 2β(σ/4)/β² = 20%, so their mean one of 0.18%. 1.5% is over 6σ of either.
#[test]
fn seed_spread_of_random_noise() {
    const SIDE: u32 = 64;
    let (sigma, beta, grey) = (0.02f64, 0.05f64, 0.5f32);
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let half_width = sigma * 3f64.sqrt();
    let reference = vec![[grey, grey, grey, 1.0]; (SIDE * SIDE) as usize];
    let images: Vec<Vec<[f32; 4]>> = (0..16)
        .map(|_| {
            let mut channel =
                || (f64::from(grey) + beta + (2.0 * uniform() - 1.0) * half_width) as f32;
            (0..SIDE * SIDE)
                .map(|_| [channel(), channel(), channel(), 1.0])
                .collect()
        })
        .collect();
    let s = seed_spread(&reference, &images, SIDE, SIDE).unwrap();
    let w = 1.0 / (f64::from(grey).powi(2) + 0.01);
    let (variance, bias2) = (sigma * sigma * w, beta * beta * w);
    assert!(
        (s.rel_variance / variance - 1.0).abs() < 0.015,
        "variance {} against {variance}",
        s.rel_variance
    );
    assert!(
        (s.rel_bias2 / bias2 - 1.0).abs() < 0.015,
        "bias² {} against {bias2}",
        s.rel_bias2
    );
}

#[test]
fn seed_spread_skips_non_finite_pixels_and_needs_two_images() {
    let reference = gradient();
    let mut noisy = offset_gradient(|i, _| if i % 2 == 0 { 0.1 } else { 0.0 });
    noisy[5][1] = f32::NAN;
    let mut bright_reference = reference.clone();
    bright_reference[9][0] = f32::INFINITY;
    let s = seed_spread(&bright_reference, &[reference.clone(), noisy.clone()], W, H).unwrap();
    assert_eq!(s.compared_pixels, (W * H) as usize - 2);
    assert!(s.rel_variance.is_finite() && s.rel_variance > 0.0);
    // The same frame every seed: no variance, and the bias² is the frame's rel_mse (over
    // the same pixels: compare leaves the NaN pixel out too).
    let same = seed_spread(
        &reference,
        &[noisy.clone(), noisy.clone(), noisy.clone()],
        W,
        H,
    );
    let same = same.unwrap();
    let rel_mse = compare(&reference, &noisy, W, H, &no_flip())
        .unwrap()
        .rel_mse;
    assert_eq!(same.rel_variance, 0.0);
    assert!(
        (same.rel_bias2 - rel_mse).abs() <= 1e-12 * rel_mse,
        "{same:?} against {rel_mse}"
    );
    let e = seed_spread(&reference, std::slice::from_ref(&reference), W, H).unwrap_err();
    assert_eq!(e, MetricsError::TooFewImages { images: 1 });
    assert!(e.to_string().contains("at least 2 images"), "{e}");
    let e = seed_spread(
        &reference,
        &[reference.clone(), reference[1..].to_vec()],
        W,
        H,
    );
    assert!(matches!(
        e,
        Err(MetricsError::SizeMismatch { test: 127, .. })
    ));
}
