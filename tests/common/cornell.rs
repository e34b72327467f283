//! Colour bleeding in the Cornell box: how red the floor looks beside each wall.

use glam::Vec3;
use lightgraph::scene::Scene;

/// Mean r/g of the pixels around where the floor points `at` project.
pub fn redness(image: &[[f32; 4]], scene: &Scene, w: u32, h: u32, at: &[Vec3]) -> f32 {
    let vp = scene.camera.projection(w as f32 / h as f32) * scene.camera.view();
    let (mut r, mut g) = (0.0, 0.0);
    for p in at {
        let c = vp * p.extend(1.0);
        let ndc = c.truncate() / c.w;
        let px = ((ndc.x + 1.0) * 0.5 * w as f32) as i32;
        let py = ((1.0 - ndc.y) * 0.5 * h as f32) as i32;
        for dy in -1..=1 {
            for dx in -1..=1 {
                let (x, y) = (
                    (px + dx).clamp(0, w as i32 - 1),
                    (py + dy).clamp(0, h as i32 - 1),
                );
                let v = image[(y as u32 * w + x as u32) as usize];
                r += v[0];
                g += v[1];
            }
        }
    }
    r / g.max(1e-12)
}

/// Floor points 0.12 from the red (x = -1) or the green (x = +1) wall, clear of the boxes.
pub fn floor_points(x: f32) -> Vec<Vec3> {
    [0.35, 0.55, 0.75]
        .iter()
        .map(|&z| Vec3::new(x, 0.0, z))
        .collect()
}
