mod common;
use common::*;

#[test]
fn smoke_forward_plus_matches_brute_force() {
    let mut r = renderer();
    let scene = random_scene(64, 1);
    let reference = render_file(&mut r, "brute_force.ron", &scene, 160, 90);
    let culled = render_file(&mut r, "forward_plus.ron", &scene, 160, 90);
    let lit = reference.image.iter().filter(|p| p[0] > 0.0).count();
    assert!(lit > 1000, "scene is lit: {lit}");
    let (d, at) = max_rel_diff(&culled.image, &reference.image);
    println!(
        "{:?} {:?}",
        culled.light_stats, culled.culling[0].longest_list
    );
    assert!(d < 1e-5, "max rel diff {d} at pixel {at}");
}
