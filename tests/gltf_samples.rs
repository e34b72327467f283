//! Real and written glTF files that use core glTF 2.0 features: the Khronos Box,
//! BoxTextured and BoxVertexColors (tests/assets/khronos/, CC BY 4.0), a non-indexed triangle (as Khronos'
//! TriangleWithoutIndices), morph targets at their default weights (as SimpleMorph),
//! sparse accessors and the model's own cameras. Light-less models render lit by the
//! headlight.

mod common;
use common::*;
use glam::{Vec3, Vec4Swizzles};
use lightgraph::scene::gltf_import::base64_encode;
use lightgraph::scene::{self, Scene};
use std::path::{Path, PathBuf};

const W: u32 = 96;
const H: u32 = 72;

fn khronos(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/assets/khronos/{name}/{name}.gltf"))
}

/// Pixels whose centre lies at least 1.5 pixels inside some triangle's projection: surely
/// the object's, whichever way the rasterizer decides edges.
fn covered(scene: &Scene, w: u32, h: u32) -> Vec<bool> {
    let vp = scene.camera.projection(w as f32 / h as f32) * scene.camera.view();
    let mut tris = Vec::new();
    for m in &scene.meshes {
        let px: Vec<Option<glam::Vec2>> = m
            .positions
            .iter()
            .map(|p| {
                let c = vp * p.extend(1.0);
                (c.w > 0.0).then(|| {
                    let n = c.xy() / c.w;
                    glam::Vec2::new((n.x + 1.0) * 0.5 * w as f32, (1.0 - n.y) * 0.5 * h as f32)
                })
            })
            .collect();
        for t in m.indices.chunks_exact(3) {
            if let (Some(a), Some(b), Some(c)) =
                (px[t[0] as usize], px[t[1] as usize], px[t[2] as usize])
            {
                tris.push([a, b, c]);
            }
        }
    }
    let inside = |p: glam::Vec2, [a, b, c]: [glam::Vec2; 3]| {
        let area = (b - a).perp_dot(c - a);
        if area.abs() < 1e-6 {
            return false;
        }
        // Signed distances to the three edges, positive inside for either winding.
        [(a, b), (b, c), (c, a)].iter().all(|&(u, v)| {
            let d = (v - u).perp_dot(p - u) * area.signum() / (v - u).length();
            d >= 1.5
        })
    };
    (0..w * h)
        .map(|i| {
            let p = glam::Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            tris.iter().any(|&t| inside(p, t))
        })
        .collect()
}

/// (object pixels, lit object pixels): lit means brighter than 2% of the brightest one.
fn lit_pixels(scene: &Scene) -> (usize, usize) {
    let image = render_file(&mut renderer(), "forward_plus.ron", scene, W, H).image;
    assert_eq!(image.len(), (W * H) as usize, "image size");
    let object = covered(scene, W, H);
    let luma = |p: &[f32; 4]| p[0].max(p[1]).max(p[2]);
    let peak = image
        .iter()
        .zip(&object)
        .filter(|(_, &o)| o)
        .map(|(p, _)| luma(p))
        .fold(0.0f32, f32::max);
    let total = object.iter().filter(|&&o| o).count();
    if peak < 1e-3 {
        return (total, 0);
    }
    let lit = image
        .iter()
        .zip(&object)
        .filter(|(p, &o)| o && luma(p) > 0.02 * peak)
        .count();
    (total, lit)
}

/// Loads a light-less file, adds the headlight and checks that most of it is lit.
fn assert_renders_lit(path: &Path) -> Scene {
    let loaded = scene::load(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut s = loaded.scene;
    assert!(
        s.lights.is_empty(),
        "{}: the file has no lights",
        path.display()
    );
    let light = s.add_headlight_if_unlit().expect("a headlight");
    assert_eq!(light.position, s.camera.eye);
    let (total, lit) = lit_pixels(&s);
    assert!(
        total > 200,
        "{}: only {total} object pixels",
        path.display()
    );
    assert!(
        lit as f64 >= 0.95 * total as f64,
        "{}: {lit} of {total} object pixels lit",
        path.display()
    );
    s
}

#[test]
fn khronos_box_renders_lit() {
    let s = assert_renders_lit(&khronos("Box"));
    assert_eq!(s.meshes[0].indices.len(), 36);
}

#[test]
fn khronos_box_textured_renders_lit() {
    let s = assert_renders_lit(&khronos("BoxTextured"));
    assert_eq!(s.materials.len(), 1);
    assert!(
        s.materials[0].base_color_texture.is_some(),
        "the logo texture"
    );
}

/// Khronos's BoxVertexColors: its COLOR_0 (float VEC4) is imported as the gltf crate's
/// own reader decodes it, and multiplies the grey base colour, so under the white
/// headlight the box shows saturated hues (a grey material alone shows none), the same
/// in forward shading and the compute-first default frame.
#[test]
fn khronos_box_vertex_colors_shows_its_vertex_colours() {
    let path = khronos("BoxVertexColors");
    let s = assert_renders_lit(&path);
    let (doc, buffers, _) = gltf::import(&path).unwrap();
    let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
    let expected: Vec<[f32; 4]> = prim
        .reader(|b| Some(&buffers[b.index()]))
        .read_colors(0)
        .expect("COLOR_0")
        .into_rgba_f32()
        .collect();
    let got: Vec<[f32; 4]> = s.meshes[0].colors.iter().map(|c| c.to_array()).collect();
    assert_eq!(got, expected);
    assert!(s.materials[0].vertex_color);

    let object = covered(&s, W, H);
    let mut r = renderer();
    let forward = render_file(&mut r, "forward_plus.ron", &s, W, H).image;
    let fast = render_file(&mut r, "default.ron", &s, W, H).image;
    assert_eq!(
        (forward.len(), fast.len()),
        ((W * H) as usize, (W * H) as usize)
    );
    let mut grey = s.clone();
    grey.meshes[0].colors.clear();
    let plain = render_file(&mut r, "forward_plus.ron", &grey, W, H).image;
    // Saturation (max − min) / max of the object's pixels.
    let saturation = |p: &[f32; 4]| {
        let hi = p[0].max(p[1]).max(p[2]);
        let lo = p[0].min(p[1]).min(p[2]);
        if hi > 0.0 {
            (hi - lo) / hi
        } else {
            0.0
        }
    };
    let most = |img: &[[f32; 4]]| {
        img.iter()
            .zip(&object)
            .filter(|(_, &o)| o)
            .map(|(p, _)| saturation(p))
            .fold(0.0f32, f32::max)
    };
    let (coloured, uncoloured) = (most(&forward), most(&plain));
    println!("most saturated object pixel: {coloured:.3} with COLOR_0, {uncoloured:.3} without");
    // The file's colours run from pure red, green and blue corners to grey: the most
    // saturated pixel is nearly pure. Grey × white light is grey (float rounding only).
    assert!(coloured > 0.9 && uncoloured < 1e-3);
    let mut worst = 0.0f32;
    for ((a, b), &o) in forward.iter().zip(&fast).zip(&object) {
        if o {
            for c in 0..3 {
                worst = worst.max((a[c] - b[c]).abs() / a[c].abs().max(1e-3));
            }
        }
    }
    println!("forward against default.ron: worst relative difference {worst:.2e}");
    // The two paths interpolate the same attributes in another order (the rasterizer's
    // against barycentrics rebuilt from the triangle): f32 rounding, 2.2e-6 relative
    // measured on lavapipe, so 1e-5.
    assert!(worst < 1e-5, "forward and default.ron differ by {worst}");
}

// --- written files ---

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// Writes `json` (with `BUFFER` replaced by `bin` as a data URI) to a fresh folder.
fn write_gltf(name: &str, json: &str, bin: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64_encode(bin)
    );
    let json = json
        .replace("BUFFER", &uri)
        .replace("BYTES", &bin.len().to_string());
    std::fs::write(&path, json).unwrap();
    (dir, path)
}

#[test]
fn non_indexed_triangle_imports_and_renders_lit() {
    // Khronos' TriangleWithoutIndices: three vertices, no indices, normals or material.
    let bin = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let (_d, path) = write_gltf(
        "TriangleWithoutIndices.gltf",
        r#"{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
            "buffers": [{"uri": "BUFFER", "byteLength": BYTES}],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36, "target": 34962}],
            "accessors": [{"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 3,
                           "type": "VEC3", "max": [1, 1, 0], "min": [0, 0, 0]}]}"#,
        &bin,
    );
    let s = assert_renders_lit(&path);
    assert_eq!(s.meshes.len(), 1);
    assert_eq!(s.meshes[0].indices, vec![0, 1, 2]);
    assert!(s.meshes[0]
        .normals
        .iter()
        .all(|n| (*n - Vec3::Z).length() < 1e-6));
}

/// A triangle with two morph targets (as Khronos' SimpleMorph): target 0 is a sparse
/// accessor without a bufferView (moves vertex 2 up by 1), target 1 a dense one (moves
/// vertices 0 and 1 apart by 1). Mesh weights (0.5, 0.25); the second node overrides them
/// with (1, 0) and sits at x = 3. An animation on the weights is ignored.
fn morph_file() -> (tempfile::TempDir, PathBuf) {
    let mut bin = f32_bytes(&[-1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]); // 0: base, 36 B
    bin.extend(f32_bytes(&[-1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0])); // 36: target 1
    bin.extend([2u8, 0, 0, 0]); // 72: sparse index (u8 + padding)
    bin.extend(f32_bytes(&[0.0, 1.0, 0.0])); // 76: sparse value
    bin.extend(f32_bytes(&[0.0, 1.0])); // 88: animation times
    bin.extend(f32_bytes(&[0.0, 0.0, 1.0, 1.0])); // 96: animation weights, 112 B in all
    write_gltf(
        "SimpleMorph.gltf",
        r#"{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1]}],
            "nodes": [{"mesh": 0}, {"mesh": 0, "weights": [1, 0], "translation": [3, 0, 0]}],
            "meshes": [{"weights": [0.5, 0.25], "primitives": [{"attributes": {"POSITION": 0},
                "targets": [{"POSITION": 2}, {"POSITION": 1}]}]}],
            "animations": [{"samplers": [{"input": 3, "output": 4}],
                            "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}]}],
            "buffers": [{"uri": "BUFFER", "byteLength": BYTES}],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                            {"buffer": 0, "byteOffset": 36, "byteLength": 36},
                            {"buffer": 0, "byteOffset": 72, "byteLength": 1},
                            {"buffer": 0, "byteOffset": 76, "byteLength": 12},
                            {"buffer": 0, "byteOffset": 88, "byteLength": 8},
                            {"buffer": 0, "byteOffset": 96, "byteLength": 16}],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [-1, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [-1, 0, 0], "max": [1, 0, 0]},
                {"componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [0, 1, 0],
                 "sparse": {"count": 1, "indices": {"bufferView": 2, "componentType": 5121},
                            "values": {"bufferView": 3}}},
                {"bufferView": 4, "componentType": 5126, "count": 2, "type": "SCALAR",
                 "min": [0], "max": [1]},
                {"bufferView": 5, "componentType": 5126, "count": 4, "type": "SCALAR"}]}"#,
        &bin,
    )
}

#[test]
fn morph_targets_import_at_their_default_weights_and_render_lit() {
    let (_d, path) = morph_file();
    let s = assert_renders_lit(&path);
    assert_eq!(s.meshes.len(), 2);
    let close = |a: &[Vec3], b: &[Vec3]| a.iter().zip(b).all(|(x, y)| (*x - *y).length() < 1e-6);
    // Mesh weights: 0.5 of target 0, 0.25 of target 1.
    let mesh_weights = [
        Vec3::new(-1.25, 0.0, 0.0),
        Vec3::new(1.25, 0.0, 0.0),
        Vec3::new(0.0, 1.5, 0.0),
    ];
    assert!(
        close(&s.meshes[0].positions, &mesh_weights),
        "{:?}",
        s.meshes[0].positions
    );
    // Node weights (1, 0), translated by 3.
    let node_weights = [
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(4.0, 0.0, 0.0),
        Vec3::new(3.0, 2.0, 0.0),
    ];
    assert!(
        close(&s.meshes[1].positions, &node_weights),
        "{:?}",
        s.meshes[1].positions
    );
}

#[test]
fn sparse_accessor_overrides_its_base_view() {
    // POSITION: the base view holds a flat triangle; the sparse part lifts vertex 2 to y = 2.
    let mut bin = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    bin.extend([2u8, 0, 0, 0, 0, 0, 0, 0]); // u16 index 2, then padding
    bin.extend(f32_bytes(&[0.0, 2.0, 0.0]));
    let (_d, path) = write_gltf(
        "sparse.gltf",
        r#"{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
            "buffers": [{"uri": "BUFFER", "byteLength": BYTES}],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                            {"buffer": 0, "byteOffset": 36, "byteLength": 20}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 2, 0],
                           "sparse": {"count": 1,
                                      "indices": {"bufferView": 1, "componentType": 5123},
                                      "values": {"bufferView": 1, "byteOffset": 8}}}]}"#,
        &bin,
    );
    let s = assert_renders_lit(&path);
    assert_eq!(
        s.meshes[0].positions,
        vec![Vec3::ZERO, Vec3::X, Vec3::new(0.0, 2.0, 0.0)]
    );
}

/// A triangle seen by two perspective cameras, the first at z = 4 in a parent node
/// translated by x = 1, the second at z = 9.
fn cameras_file() -> (tempfile::TempDir, PathBuf) {
    let bin = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    write_gltf(
        "cameras.gltf",
        r#"{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1, 3]}],
            "nodes": [{"mesh": 0}, {"translation": [1, 0, 0], "children": [2]},
                      {"camera": 0, "translation": [0, 0, 4]},
                      {"camera": 1, "translation": [0, 0, 9]}],
            "cameras": [{"type": "perspective", "perspective": {"yfov": 0.6, "znear": 0.1}},
                        {"type": "perspective",
                         "perspective": {"yfov": 0.9, "znear": 0.5, "zfar": 50}}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
            "buffers": [{"uri": "BUFFER", "byteLength": BYTES}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]}]}"#,
        &bin,
    )
}

#[test]
fn the_models_first_camera_is_used() {
    let (dir, path) = cameras_file();
    let loaded = scene::load(&path).unwrap();
    assert!(
        !loaded.warnings.iter().any(|w| w.contains("fitted")),
        "{:?}",
        loaded.warnings
    );
    let c = loaded.scene.camera;
    assert_eq!(c.eye, Vec3::new(1.0, 0.0, 4.0));
    assert_eq!(c.target, Vec3::new(1.0, 0.0, 3.0), "looking down -Z");
    assert_eq!((c.fov_y, c.near), (0.6, 0.1));
    // A scene file that names no camera takes the model's; one that names one keeps it.
    let ron = dir.path().join("scene.ron");
    std::fs::write(&ron, r#"Scene(models: [(path: "cameras.gltf")])"#).unwrap();
    let from_ron = scene::load(&ron).unwrap().scene.camera;
    assert_eq!(from_ron.eye, c.eye);
    assert_eq!(from_ron.fov_y, c.fov_y);
    std::fs::write(
        &ron,
        r#"Scene(models: [(path: "cameras.gltf")], camera: FitBounds)"#,
    )
    .unwrap();
    assert_ne!(scene::load(&ron).unwrap().scene.camera.eye, c.eye);
    // It renders lit from there: the headlight sits at the model's camera.
    assert_renders_lit(&path);
}

#[test]
fn zero_length_normals_are_replaced_with_a_warning() {
    // Vertex 1's normal is (0, 0, 0): it takes the triangle's own normal, +Z, not +Y.
    let mut bin = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    bin.extend(f32_bytes(&[0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]));
    let (_d, path) = write_gltf(
        "zero_normal.gltf",
        r#"{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}}]}],
            "buffers": [{"uri": "BUFFER", "byteLength": BYTES}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 36}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]},
                          {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"}]}"#,
        &bin,
    );
    let loaded = scene::load(&path).unwrap();
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains("1 zero-length normals (the first at vertex 1)")),
        "{:?}",
        loaded.warnings
    );
    assert_eq!(loaded.scene.meshes[0].normals, vec![Vec3::Z; 3]);
}
