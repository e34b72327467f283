//! Meshes added to and removed from a prepared frame (`Renderer::add_mesh`,
//! `Renderer::remove_mesh`): the frame then renders as a fresh prepare of the edited
//! scene, through the visibility buffer (triangle ids and material ranges renumbered),
//! ray-cast shadows (the BVH rebuilt) and the shadow atlas (casters culled per view),
//! and no pipeline is built.

mod common;
use common::*;

use glam::Vec3;
use lightgraph::render::{MeshEditError, PreparedFrame, Renderer, SceneGpu};
use lightgraph::scene::{light_flags, Scene};

const W: u32 = 80;
const H: u32 = 48;

/// The same scene and graph rendered twice: the lights of a tile may be summed in
/// another order (culling appends them with atomics), nothing else differs; the bound
/// of tests/forward_plus.rs, relative to the peak.
const SAME_SCENE: f32 = 2e-6;

fn prepare(r: &mut Renderer, graph_file: &str, scene: &Scene) -> (PreparedFrame, SceneGpu) {
    prepare_file_with_gpu(r, graph_file, scene, W, H, 0)
}

fn fresh(r: &mut Renderer, graph_file: &str, scene: &Scene) -> Vec<[f32; 4]> {
    let (prepared, _) = prepare(r, graph_file, scene);
    prepared.render(r).unwrap().image
}

fn assert_same(a: &[[f32; 4]], b: &[[f32; 4]], what: &str) {
    assert_eq!(a.len(), (W * H) as usize, "{what}: image size");
    let (d, at) = max_rel_diff(a, b);
    assert!(
        d <= SAME_SCENE,
        "{what}: relative error {d:e} at pixel {at}"
    );
}

/// The random room with a few shadow-casting point lights over the boxes.
fn room() -> Scene {
    let mut s = random_scene(24, 7);
    for (i, l) in s.lights.iter_mut().enumerate().filter(|(i, _)| i % 4 == 0) {
        l.shape = lightgraph::scene::LightShape::Point;
        l.flags |= light_flags::CASTS_SHADOW;
        l.position = Vec3::new(-6.0 + i as f32 * 0.6, 5.0, -4.0 - i as f32 * 0.5);
        l.range = 14.0;
    }
    s
}

/// A grey block in front of the boxes: grey is material 0, drawn first, so every
/// orange triangle's visibility id moves up by its twelve.
fn block() -> lightgraph::scene::Mesh {
    cuboid(
        "block",
        Vec3::new(-2.5, 0.0, -7.0),
        Vec3::new(0.5, 3.5, -5.0),
        0,
        false,
    )
}

fn edit_and_compare(graph_file: &str) {
    let mut r = renderer();
    let mut scene = room();
    let (mut frame, mut gpu) = prepare(&mut r, graph_file, &scene);
    let without = frame.render(&r).unwrap().image;

    let index = r
        .add_mesh(&mut frame, &mut scene, &mut gpu, block())
        .unwrap();
    assert_eq!(index, scene.meshes.len() - 1);
    let stats = frame.stats();
    assert!(
        stats.pipelines_built.is_empty() && stats.pipeline_misses == 0,
        "{graph_file}: adding built {:?}",
        stats.pipelines_built
    );
    let added = frame.render(&r).unwrap().image;
    assert_same(
        &added,
        &fresh(&mut r, graph_file, &scene),
        &format!("{graph_file}: added"),
    );
    let (d, _) = max_rel_diff(&added, &without);
    assert!(d > 0.05, "{graph_file}: the block changed only {d:e}");

    // Remove a box of the original scene (and the block stays).
    let removed = r.remove_mesh(&mut frame, &mut scene, &mut gpu, 3).unwrap();
    assert_eq!(removed.name, "box1");
    assert!(frame.stats().pipelines_built.is_empty());
    let image = frame.render(&r).unwrap().image;
    assert_same(
        &image,
        &fresh(&mut r, graph_file, &scene),
        &format!("{graph_file}: removed"),
    );
}

#[test]
fn the_visibility_buffer_follows_added_and_removed_meshes() {
    edit_and_compare("default.ron");
}

#[test]
fn ray_cast_shadows_follow_added_and_removed_meshes() {
    edit_and_compare("raycast_shadows.ron");
}

#[test]
fn the_shadow_atlas_follows_added_and_removed_meshes() {
    edit_and_compare("shadow_atlas.ron");
}

#[test]
fn bad_edits_are_refused_and_leave_the_frame_as_it_was() {
    let mut r = renderer();
    let mut scene = room();
    let (mut frame, mut gpu) = prepare(&mut r, "forward_plus.ron", &scene);
    let meshes = scene.meshes.len();
    let mut bad = block();
    bad.indices.push(99);
    bad.indices.extend([0, 1]);
    let e = r
        .add_mesh(&mut frame, &mut scene, &mut gpu, bad)
        .unwrap_err();
    assert!(
        e.to_string()
            .contains("mesh \"block\": index 99 is past its 24 vertices"),
        "{e}"
    );
    let mut far = block();
    far.positions[0].x = 2e5;
    let e = r
        .add_mesh(&mut frame, &mut scene, &mut gpu, far)
        .unwrap_err();
    assert!(e.to_string().contains("vertex 0: position"), "{e}");
    let mut glass = block();
    glass.material = scene.materials.len();
    scene.materials.push(lightgraph::scene::SurfaceMaterial {
        alpha_mode: lightgraph::scene::AlphaMode::Blend,
        ..lambert("glass", Vec3::ONE)
    });
    let e = r
        .add_mesh(&mut frame, &mut scene, &mut gpu, glass)
        .unwrap_err();
    assert!(
        matches!(
            e,
            MeshEditError::NewFeature {
                feature: "blended meshes",
                ..
            }
        ),
        "{e}"
    );
    let e = r
        .remove_mesh(&mut frame, &mut scene, &mut gpu, meshes)
        .unwrap_err();
    assert!(
        e.to_string()
            .contains(&format!("no mesh {meshes} to remove")),
        "{e}"
    );
    assert_eq!(scene.meshes.len(), meshes);
    scene.materials.pop();
    assert_same(
        &frame.render(&r).unwrap().image,
        &fresh(&mut r, "forward_plus.ron", &scene),
        "after refusals",
    );
}

/// The build count the edits above assert to be zero does see builds: a material the
/// scene holds but no mesh drew has no pipelines yet, and a mesh of it builds them.
#[test]
fn a_mesh_of_a_material_no_mesh_drew_builds_its_pipelines() {
    let mut r = renderer();
    let mut scene = room();
    scene
        .materials
        .push(lambert("spare", Vec3::new(0.2, 0.6, 0.9)));
    let (mut frame, mut gpu) = prepare(&mut r, "default.ron", &scene);
    let mut mesh = block();
    mesh.material = 2;
    r.add_mesh(&mut frame, &mut scene, &mut gpu, mesh).unwrap();
    assert!(
        !frame.stats().pipelines_built.is_empty(),
        "a new material's pipelines were not counted"
    );
    let image = frame.render(&r).unwrap().image;
    assert_same(
        &image,
        &fresh(&mut r, "default.ron", &scene),
        "spare material",
    );
}
