mod common;
use common::*;

#[test]
fn smoke_forward_plus_matches_brute_force() {
    let mut r = renderer();
    // Enough lights that most pixels see several (64 lit a fifth of the frame).
    let scene = random_scene(512, 1);
    let reference = render_file(&mut r, "brute_force.ron", &scene, 160, 90);
    let culled = render_file(&mut r, "forward_plus.ron", &scene, 160, 90);
    assert_eq!(culled.image.len(), 160 * 90);
    assert_eq!(reference.image.len(), 160 * 90);
    let lit = reference
        .image
        .iter()
        .filter(|p| p[..3].iter().any(|&c| c > 0.0))
        .count();
    assert!(lit > 160 * 90 / 2, "most of the frame is lit: {lit}");
    // Per pixel and channel, relative to the pixel itself with a floor of 1e-3 of the
    // peak (the measure of tests/culling_exact.rs): a dark pixel's error is not hidden
    // under the brightest one's.
    let peak = reference
        .image
        .iter()
        .flat_map(|p| p[..3].to_vec())
        .fold(0.0f32, f32::max);
    let mut worst = (0.0f32, 0usize);
    for (i, (a, b)) in culled.image.iter().zip(&reference.image).enumerate() {
        for c in 0..3 {
            let d = (a[c] - b[c]).abs() / b[c].abs().max(1e-3 * peak);
            if d.is_nan() || d > worst.0 {
                worst = (d, i);
            }
        }
    }
    assert!(
        worst.0 <= 2e-6,
        "relative error {:e} at pixel {}: {:?} vs {:?}",
        worst.0,
        worst.1,
        culled.image[worst.1],
        reference.image[worst.1]
    );
}
