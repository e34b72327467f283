//! glTF import of files the project writes itself (scene::gltf_writer): external and embedded
//! buffers, .glb, textures, lights, cameras, node hierarchy, indexed and non-indexed meshes.

use glam::{Quat, Vec2, Vec3, Vec4};
use lightgraph::scene::gltf_writer::{
    encode_png, BufferStorage, GltfWriter, ImageStorage, MaterialDesc, NodeDesc, PrimitiveDesc,
};
use lightgraph::scene::{self, AlphaMode, LightShape};
use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "lightgraph_scene_gltf_{}_{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn checker(w: u32, a: [u8; 4], b: [u8; 4]) -> image::RgbaImage {
    image::RgbaImage::from_fn(w, w, |x, y| {
        image::Rgba(if (x + y) % 2 == 0 { a } else { b })
    })
}

/// A unit quad in XY facing +Z, 4 vertices, 2 triangles.
fn quad() -> (Vec<Vec3>, Vec<Vec3>, Vec<Vec2>, Vec<u32>) {
    (
        vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ],
        vec![Vec3::Z; 4],
        vec![
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 0.0),
        ],
        vec![0, 1, 2, 0, 2, 3],
    )
}

/// The full-featured document used by several tests.
fn full_document(images: ImageStorage, jpeg_emissive: bool) -> GltfWriter {
    let mut w = GltfWriter::new();
    let file = |n: &str| match &images {
        ImageStorage::File(_) => ImageStorage::File(n.to_string()),
        s => s.clone(),
    };
    let base_tex = w.add_texture_png(
        "base",
        &checker(4, [255, 0, 0, 255], [0, 0, 255, 255]),
        file("base.png"),
    );
    let mr_tex = w.add_texture_png(
        "mr",
        &checker(2, [0, 128, 255, 255], [0, 64, 0, 255]),
        file("mr.png"),
    );
    let emissive_tex = if jpeg_emissive {
        let img = image::RgbImage::from_pixel(8, 8, image::Rgb([200, 100, 50]));
        let mut bytes = Vec::new();
        img.write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Jpeg,
        )
        .unwrap();
        w.add_texture_bytes("emissive", bytes, file("emissive.jpg"))
    } else {
        w.add_texture_png(
            "emissive",
            &checker(2, [255; 4], [0, 0, 0, 255]),
            file("emissive.png"),
        )
    };
    let textured = w.add_material(&MaterialDesc {
        name: "textured".into(),
        base_color: Vec4::new(1.0, 0.5, 0.25, 1.0),
        metallic: 0.25,
        roughness: 0.75,
        emissive: Vec3::new(0.5, 0.5, 0.5),
        base_color_texture: Some(base_tex),
        metallic_roughness_texture: Some(mr_tex),
        normal_texture: Some(mr_tex),
        emissive_texture: Some(emissive_tex),
        ..Default::default()
    });
    let masked = w.add_material(&MaterialDesc {
        name: "masked".into(),
        alpha_mode: "MASK",
        alpha_cutoff: Some(0.3),
        double_sided: true,
        ..Default::default()
    });
    let blended = w.add_material(&MaterialDesc {
        name: "glass".into(),
        base_color: Vec4::new(1.0, 1.0, 1.0, 0.5),
        alpha_mode: "BLEND",
        ..Default::default()
    });
    let (p, n, uv, idx) = quad();
    // Indexed, with normals and UVs (tangents generated).
    let m0 = w.add_simple_mesh(
        "indexed",
        &p,
        Some(&n),
        Some(&uv),
        Some(&idx),
        Some(textured),
    );
    // Non-indexed, no normals (generated), no UVs.
    let flat: Vec<Vec3> = idx.iter().map(|&i| p[i as usize]).collect();
    let m1 = w.add_simple_mesh("non_indexed", &flat, None, None, None, Some(masked));
    // Two primitives: a blended triangle and a strip.
    let pa = w.add_positions(&p[..3]);
    let pb = w.add_positions(&p);
    let strip = w.add_indices(&[0, 1, 3, 2]);
    let m2 = w.add_mesh(
        "two_prims",
        &[
            PrimitiveDesc {
                positions: pa,
                material: Some(blended),
                ..Default::default()
            },
            PrimitiveDesc {
                positions: pb,
                indices: Some(strip),
                mode: Some(5),
                ..Default::default()
            },
        ],
    );
    let cam = w.add_camera(0.8, 0.05, Some(50.0));
    let point = w.add_light("bulb", Vec3::new(1.0, 0.9, 0.8), 5.0, Some(3.0), None);
    let spot = w.add_light("spot", Vec3::ONE, 20.0, None, Some((0.2, 0.5)));

    // Hierarchy: root (translate +10 x) -> child (scale 2) -> mesh 0; root -> child rotated 90° about Y -> mesh 1.
    let leaf0 = w.add_node(&NodeDesc {
        name: Some("leaf0".into()),
        mesh: Some(m0),
        scale: Some(Vec3::splat(2.0)),
        ..Default::default()
    });
    let leaf1 = w.add_node(&NodeDesc {
        name: Some("leaf1".into()),
        mesh: Some(m1),
        rotation: Some(Quat::from_rotation_y(std::f32::consts::FRAC_PI_2)),
        ..Default::default()
    });
    let light_node = w.add_node(&NodeDesc {
        name: Some("light".into()),
        light: Some(point),
        translation: Some(Vec3::new(0.0, 2.0, 0.0)),
        ..Default::default()
    });
    let spot_node = w.add_node(&NodeDesc {
        name: Some("spot".into()),
        light: Some(spot),
        // -Z rotated to point down (-Y): rotate -90° about X.
        rotation: Some(Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2)),
        translation: Some(Vec3::new(0.0, 3.0, 0.0)),
        ..Default::default()
    });
    let root = w.add_node(&NodeDesc {
        name: Some("root".into()),
        translation: Some(Vec3::new(10.0, 0.0, 0.0)),
        children: vec![leaf0, leaf1, light_node, spot_node],
        ..Default::default()
    });
    let cam_node = w.add_node(&NodeDesc {
        name: Some("cam".into()),
        camera: Some(cam),
        translation: Some(Vec3::new(0.0, 1.0, 5.0)),
        ..Default::default()
    });
    let other = w.add_node(&NodeDesc {
        mesh: Some(m2),
        translation: Some(Vec3::new(0.0, 0.0, -3.0)),
        ..Default::default()
    });
    w.add_root(root);
    w.add_root(cam_node);
    w.add_root(other);
    w
}

fn check_full(loaded: &scene::Loaded, expect_textures: bool) {
    let s = &loaded.scene;
    // 4 meshes: indexed, non-indexed, and two primitives.
    assert_eq!(
        s.meshes.len(),
        4,
        "{:?}",
        s.meshes.iter().map(|m| &m.name).collect::<Vec<_>>()
    );
    let m0 = s.meshes.iter().find(|m| m.name == "indexed").unwrap();
    // World space: scale 2 then translate +10 x.
    assert_eq!(m0.positions[2], Vec3::new(12.0, 2.0, 0.0));
    assert_eq!(m0.indices, vec![0, 1, 2, 0, 2, 3]);
    assert_eq!(m0.tangents.len(), 4);
    // U runs along +x: tangent +x.
    assert!(
        (m0.tangents[0].truncate() - Vec3::X).length() < 1e-4,
        "{:?}",
        m0.tangents[0]
    );
    let m1 = s.meshes.iter().find(|m| m.name == "non_indexed").unwrap();
    assert_eq!(m1.indices, (0..6).collect::<Vec<u32>>());
    // Normal generated (+Z) then rotated 90° about Y: +X.
    assert!(
        (m1.normals[0] - Vec3::X).length() < 1e-5,
        "{:?}",
        m1.normals[0]
    );
    assert!(m1.uvs.is_empty());
    assert_eq!(m1.tangents.len(), 6);
    let strip = s.meshes.iter().find(|m| m.name == "two_prims/1").unwrap();
    assert_eq!(strip.indices, vec![0, 1, 3, 1, 2, 3]); // strip 0 1 3 2 → (0,1,3) (1,2,3)... winding kept
    assert_eq!(
        s.meshes
            .iter()
            .find(|m| m.name == "two_prims/0")
            .unwrap()
            .positions[0],
        Vec3::new(0.0, 0.0, -3.0)
    );

    let mat = |n: &str| {
        &s.materials[s
            .material_index(n)
            .unwrap_or_else(|| panic!("material {n}"))]
    };
    let t = mat("textured");
    assert_eq!(t.base_color, Vec4::new(1.0, 0.5, 0.25, 1.0));
    assert_eq!((t.metallic, t.roughness), (0.25, 0.75));
    assert_eq!(t.emissive, Vec3::splat(0.5));
    if expect_textures {
        let b = t.base_color_texture.as_ref().expect("base colour texture");
        assert!(b.srgb);
        assert_eq!((b.width, b.height), (4, 4));
        assert_eq!(&b.rgba8[..4], &[255, 0, 0, 255]);
        let mr = t.metallic_roughness_texture.as_ref().unwrap();
        assert!(!mr.srgb);
        assert_eq!(&mr.rgba8[..4], &[0, 128, 255, 255]);
        assert!(!t.normal_texture.as_ref().unwrap().srgb);
        assert!(t.emissive_texture.as_ref().unwrap().srgb);
    }
    assert_eq!(mat("masked").alpha_mode, AlphaMode::Mask(0.3));
    assert!(mat("masked").double_sided);
    assert_eq!(mat("glass").alpha_mode, AlphaMode::Blend);
    assert_eq!(
        s.meshes
            .iter()
            .find(|m| m.name == "two_prims/1")
            .map(|m| &s.materials[m.material].name)
            .unwrap(),
        "default"
    );

    // Lights: world positions, spot direction, infinite range replaced and warned about.
    assert_eq!(s.lights.len(), 2);
    let p = s
        .lights
        .iter()
        .find(|l| l.shape == LightShape::Point)
        .unwrap();
    assert_eq!(p.position, Vec3::new(10.0, 2.0, 0.0));
    assert_eq!((p.range, p.intensity), (3.0, 5.0));
    let sp = s
        .lights
        .iter()
        .find(|l| l.shape != LightShape::Point)
        .unwrap();
    match sp.shape {
        LightShape::Spot {
            direction,
            inner_angle,
            outer_angle,
        } => {
            assert!((direction - Vec3::NEG_Y).length() < 1e-5, "{direction}");
            assert_eq!((inner_angle, outer_angle), (0.2, 0.5));
        }
        _ => unreachable!(),
    }
    assert!(sp.range.is_finite() && sp.range > 0.0);
    assert!(
        loaded.warnings.iter().any(|w| w.contains("no range")),
        "{:?}",
        loaded.warnings
    );

    // Camera from the camera node.
    assert_eq!(s.camera.eye, Vec3::new(0.0, 1.0, 5.0));
    assert!((s.camera.target - Vec3::new(0.0, 1.0, 4.0)).length() < 1e-6);
    assert_eq!(
        (s.camera.fov_y, s.camera.near, s.camera.far),
        (0.8, 0.05, 50.0)
    );

    let f = s.features();
    assert!(
        f.has_transparent
            && f.has_alpha_mask
            && f.has_spot_lights
            && f.has_point_lights
            && f.has_double_sided
            && f.has_emissive
    );
    assert!(!f.has_shadow_casters);
}

#[test]
fn gltf_external_buffer_and_image_files() {
    let d = tmp("external");
    let w = full_document(ImageStorage::File(String::new()), true);
    let path = d.join("model.gltf");
    w.write_gltf(&path, &BufferStorage::External("model data.bin".into()))
        .unwrap();
    let loaded = scene::load(&path).unwrap();
    check_full(&loaded, true);
    assert_eq!(
        loaded.scene.materials[0]
            .base_color_texture
            .as_ref()
            .unwrap()
            .name,
        "base"
    );
    // The scene still loads when the whole folder is moved elsewhere (relative URIs).
    let moved = tmp("external_moved");
    for f in std::fs::read_dir(&d).unwrap() {
        let f = f.unwrap().path();
        std::fs::copy(&f, moved.join(f.file_name().unwrap())).unwrap();
    }
    std::fs::remove_dir_all(&d).unwrap();
    check_full(&scene::load(&moved.join("model.gltf")).unwrap(), true);
}

#[test]
fn gltf_embedded_data_uris() {
    let d = tmp("embedded");
    let w = full_document(ImageStorage::DataUri, false);
    let path = d.join("model.gltf");
    w.write_gltf(&path, &BufferStorage::Embedded).unwrap();
    assert_eq!(
        std::fs::read_dir(&d).unwrap().count(),
        1,
        "only the .gltf is written"
    );
    check_full(&scene::load(&path).unwrap(), true);
}

#[test]
fn glb_with_images_in_buffer_views() {
    let d = tmp("glb");
    let w = full_document(ImageStorage::BufferView, false);
    let path = d.join("model.glb");
    w.write_glb(&path).unwrap();
    let loaded = scene::load(&path).unwrap();
    check_full(&loaded, true);
    assert_eq!(loaded.scene.name, "model");
}

#[test]
fn missing_texture_is_a_warning_not_an_error() {
    let d = tmp("missing_tex");
    let w = full_document(ImageStorage::File(String::new()), false);
    let path = d.join("model.gltf");
    w.write_gltf(&path, &BufferStorage::External("model.bin".into()))
        .unwrap();
    std::fs::remove_file(d.join("base.png")).unwrap();
    std::fs::write(d.join("mr.png"), b"not a png").unwrap();
    let loaded = scene::load(&path).unwrap();
    let t = &loaded.scene.materials[loaded.scene.material_index("textured").unwrap()];
    assert!(t.base_color_texture.is_none());
    assert!(t.metallic_roughness_texture.is_none());
    assert!(t.emissive_texture.is_some());
    let w = loaded.warnings.join("\n");
    assert!(
        w.contains("baseColorTexture") && w.contains("base.png"),
        "{w}"
    );
    assert!(
        w.contains("metallicRoughnessTexture") && w.contains("cannot decode"),
        "{w}"
    );
    check_full(&loaded, false);
}

#[test]
fn mirrored_node_keeps_front_faces_and_bounds() {
    let d = tmp("mirror");
    let mut w = GltfWriter::new();
    let (p, n, uv, idx) = quad();
    let m = w.add_simple_mesh("q", &p, Some(&n), Some(&uv), Some(&idx), None);
    let node = w.add_node(&NodeDesc {
        mesh: Some(m),
        scale: Some(Vec3::new(-1.0, 1.0, 1.0)),
        ..Default::default()
    });
    w.add_root(node);
    let path = d.join("m.gltf");
    w.write_gltf(&path, &BufferStorage::Embedded).unwrap();
    let l = scene::load(&path).unwrap();
    let mesh = &l.scene.meshes[0];
    assert_eq!(mesh.indices, vec![0, 2, 1, 0, 3, 2]);
    // Geometric normal from the new winding agrees with the stored normal.
    let (a, b, c) = (mesh.positions[0], mesh.positions[2], mesh.positions[1]);
    let geo = (b - a).cross(c - a).normalize();
    assert!(
        geo.dot(mesh.normals[0]) > 0.99,
        "{geo} vs {}",
        mesh.normals[0]
    );
    assert_eq!(
        l.scene.bounds().unwrap(),
        (Vec3::new(-1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0))
    );
    // No camera in the file: fitted, with a warning.
    assert!(l
        .warnings
        .iter()
        .any(|w| w.contains("no perspective camera")));
}

#[test]
fn big_generated_grid_glb() {
    let d = tmp("grid");
    let path = d.join("grid.glb");
    lightgraph::scene::gltf_writer::write_grid_glb(&path, 20_000).unwrap();
    let l = scene::load(&path).unwrap();
    assert!(l.scene.triangle_count() >= 20_000);
    assert!(l.warnings.iter().all(|w| !w.contains("error")));
    let _ = encode_png; // re-exported helper used by other tests
}

/// Khronos's 2CylinderEngine gives its camera znear 0.05 and zfar 1e6, a range f32 depth
/// cannot resolve (over 2^24): the far plane is pulled in to the scene's farthest point,
/// with a warning, instead of refusing a real model.
#[test]
fn a_far_plane_past_depth_precision_is_pulled_in_to_the_scene() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/assets/khronos/2CylinderEngine/2CylinderEngine.gltf");
    let loaded = scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let cam = loaded.scene.camera;
    assert!(
        cam.far / cam.near <= lightgraph::scene::MAX_FAR_OVER_NEAR,
        "near {} far {}",
        cam.near,
        cam.far
    );
    assert!(cam.far < 1e6 && cam.far > 1000.0, "far {}", cam.far);
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains("zfar 1000000") && w.contains("pulled in")),
        "{:?}",
        loaded.warnings
    );
}

/// Vertex colours (COLOR_0) are read per vertex, and mark the material that takes them
/// (here glTF's default one) as multiplied by them; values outside 0..=1 are clamped
/// into it with a warning naming the accessor.
#[test]
fn vertex_colours_are_read_and_mark_their_material() {
    let (p, n, uv, idx) = quad();
    let mut w = GltfWriter::new();
    let positions = w.add_positions(&p);
    let normals = w.add_vec3(&n);
    let uvs = w.add_vec2(&uv);
    let given = [
        Vec4::new(1.0, 0.0, 0.0, 1.0),
        Vec4::new(0.25, 0.5, 0.75, 0.5),
        Vec4::new(1.5, -0.25, 0.5, 1.0),
        Vec4::new(0.0, 0.0, 1.0, 0.0),
    ];
    let colors = w.add_vec4(&given);
    let indices = w.add_indices(&idx);
    let mesh = w.add_mesh(
        "coloured",
        &[PrimitiveDesc {
            positions,
            normals: Some(normals),
            uvs: Some(uvs),
            colors: Some(colors),
            indices: Some(indices),
            ..Default::default()
        }],
    );
    let node = w.add_node(&NodeDesc {
        mesh: Some(mesh),
        ..Default::default()
    });
    w.add_root(node);
    let path = tmp("vertex_colours").join("coloured.glb");
    w.write_glb(&path).unwrap();
    let loaded = scene::load(&path).unwrap();
    assert_eq!(loaded.scene.triangle_count(), 2);
    let m = &loaded.scene.meshes[0];
    let clamped = given.map(|c| c.clamp(Vec4::ZERO, Vec4::ONE));
    assert_eq!(m.colors, clamped);
    assert!(loaded.scene.materials[m.material].vertex_color);
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains("COLOR_0") && w.contains("1 vertex colours outside")),
        "{:?}",
        loaded.warnings
    );
}
