//! Glass over an opaque frame against a reference with the same blending order: the glass
//! must show, and add no error beyond the opaque layers' own difference.

/// A pale blue glass that lets half the light through (alpha-blended), as the shadow
/// tests put over their rooms.
pub fn pale_glass() -> lightgraph::scene::SurfaceMaterial {
    lightgraph::scene::SurfaceMaterial {
        name: "glass".into(),
        base_color: glam::Vec4::new(0.6, 0.8, 1.0, 0.5),
        alpha_mode: lightgraph::scene::AlphaMode::Blend,
        ..Default::default()
    }
}

/// Pixels that differ between two images of one size.
pub fn differing(a: &[[f32; 4]], b: &[[f32; 4]]) -> usize {
    assert_eq!(a.len(), b.len(), "images of different sizes");
    a.iter().zip(b).filter(|(x, y)| x != y).count()
}

/// The largest absolute difference of two images of one size, over colour channels.
pub fn max_abs_diff(a: &[[f32; 4]], b: &[[f32; 4]]) -> (f32, usize) {
    assert_eq!(a.len(), b.len(), "images of different sizes");
    let mut worst = (0.0f32, 0);
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        for c in 0..3 {
            let d = (x[c] - y[c]).abs();
            if d > worst.0 || d.is_nan() {
                worst = (d, i);
            }
        }
    }
    worst
}

/// A frame with glass and the same frame without it, and their references.
pub struct GlassLayers<'a> {
    pub frame: &'a [[f32; 4]],
    pub opaque: &'a [[f32; 4]],
    pub reference: &'a [[f32; 4]],
    pub opaque_reference: &'a [[f32; 4]],
}

/// Checks that the glass shows (it changes over a tenth of the `width`-wide frame's
/// pixels) and adds no error of its own: the composite differs from the reference by at
/// most the opaque layers' difference plus `tol` of the reference's peak (glass blends
/// over the opaque colour with weight 1 − α ≤ 1). Returns the opaque layers' difference
/// and the peak.
pub fn check_glass_layers(graph: &str, width: u32, tol: f32, l: &GlassLayers) -> (f32, f32) {
    let (opaque_err, _) = max_abs_diff(l.opaque, l.opaque_reference);
    let peak = l
        .reference
        .iter()
        .flat_map(|p| p[..3].iter().copied())
        .fold(0.0f32, f32::max);
    assert!(peak > 0.0, "a dark frame tests nothing");
    let changed = differing(l.frame, l.opaque);
    assert!(
        changed > l.frame.len() / 10,
        "only {changed} pixels show glass in {graph}"
    );
    let (err, at) = max_abs_diff(l.frame, l.reference);
    eprintln!("{graph}: opaque {opaque_err:e}, with glass {err:e}, peak {peak}");
    assert!(
        err <= opaque_err + tol * peak,
        "{graph}: error {err:e} (opaque layers alone {opaque_err:e}) at pixel ({}, {}): {:?} vs {:?}",
        at as u32 % width,
        at as u32 / width,
        l.frame[at],
        l.reference[at]
    );
    (opaque_err, peak)
}

/// graphs/default.ron with the glass's culling ranges ending at the farthest glass: its
/// rasterizer also writes `transparent_far`, which the transparent culling reads.
pub fn default_with_farthest_glass() -> String {
    let text = std::fs::read_to_string(super::graph_path("default.ron")).unwrap();
    let edits = [
        (
            r#"        Texture(name: "transparent_depth", format: R32Float, size: Output),"#,
            r#"        Texture(name: "transparent_depth", format: R32Float, size: Output),
        Texture(name: "transparent_far", format: R32Float, size: Output),"#,
        ),
        (
            r#"writes: ["depth", "visibility", "transparent_depth"]"#,
            r#"writes: ["depth", "visibility", "transparent_depth", "transparent_far"]"#,
        ),
        (
            r#"reads: ["depth", "transparent_depth", "light_geometry"]"#,
            r#"reads: ["depth", "transparent_depth", "transparent_far", "light_geometry"]"#,
        ),
    ];
    edits.iter().fold(text, |t, (from, to)| {
        assert_eq!(t.matches(from).count(), 1, "default.ron: {from}");
        t.replace(from, to)
    })
}
