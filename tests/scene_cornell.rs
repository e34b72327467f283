//! The Cornell box (scenes/cornell_box, from the shared assets) imports: mesh count, red and green walls, bounds.

use lightgraph::scene;
use std::path::Path;

#[test]
fn cornell_box_imports() {
    let path = &Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_box/scene.gltf");
    let loaded = scene::load(path).unwrap();
    let s = &loaded.scene;
    // One glTF mesh of 8 primitives (one per material) → 8 meshes.
    assert_eq!(s.meshes.len(), 8);
    assert_eq!(s.materials.len(), 8);
    let mat = |n: &str| &s.materials[s.material_index(n).unwrap_or_else(|| panic!("no {n}"))];
    let (left, right) = (mat("leftWall").base_color, mat("rightWall").base_color);
    // Classic Cornell box: red left wall, green right wall.
    assert!(
        left.x > 2.0 * left.y && left.x > 2.0 * left.z,
        "left wall {left}"
    );
    assert!(
        right.y > 2.0 * right.x && right.y > 2.0 * right.z,
        "right wall {right}"
    );
    let (lo, hi) = s.bounds().unwrap();
    let size = hi - lo;
    // About 2 units wide, deep and high; the node rotates Z-up to Y-up.
    for c in size.to_array() {
        assert!((1.9..2.1).contains(&c), "size {size}");
    }
    assert!(lo.y > -0.01 && lo.y < 0.01, "floor at y = 0: {lo}");
    assert!(s.triangle_count() > 20);
    for m in &s.meshes {
        assert_eq!(m.normals.len(), m.positions.len());
        assert_eq!(m.tangents.len(), m.positions.len());
        assert!(m.positions.iter().all(|p| p.is_finite()));
    }
    assert!(s.camera.eye.is_finite());
    eprintln!("warnings: {:?}", loaded.warnings);
}
