//! Hot reload of materials, glTF models and graphs on the real adapter, with what each edit rebuilds:
//! a scene file in a temp dir overrides the harada boxes' material with a material file
//! beside it (outside any watched folder: the session watches it because the scene uses
//! it). Editing the albedo scales exactly those pixels; broken saves name file:line and
//! keep the frame bit for bit; a graph edit keeps every unchanged resource and pipeline;
//! switching graphs keeps the old one on error. Waits are bounded waits on the watcher.

mod common;
use common::max_rel_diff;
use lightgraph::reload::{Reload, ReloadSession, SceneSource};
use lightgraph::render::Renderer;
use lightgraph::shader::ShaderLibrary;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The material file; `{color}` is the Lambert albedo, on line 7.
fn material(color: &str) -> String {
    format!(
        "// The harada boxes' material in the hot-reload test.
(
    name: \"box\",
    layers: [
        (
            lobes: [
                Lambert(color: {color}),
            ],
        ),
    ],
)
"
    )
}

const SCENE: &str = r#"Scene(
    name: "material_reload",
    builtin: "harada",
    keep_model_lights: false,
    light_sets: [
        Random(count: 48, spot_fraction: 0.3, placement: Box(min: (-20, 0.1, -20), max: (20, 3, 20)),
               range: (4, 8), intensity: (1, 4), seed: 11),
    ],
    material_overrides: { "harada_box": "box.ron" },
    ambient: (0, 0, 0),
)
"#;

/// The reload that handled `file` (bounded wait).
fn reload_of(s: &mut ReloadSession, file: &Path) -> Reload {
    let deadline = Instant::now() + Duration::from_secs(100);
    while let Some(left) = deadline.checked_duration_since(Instant::now()) {
        if let Some(r) = s.wait(left) {
            if r.changed.iter().any(|c| c.file_name() == file.file_name()) {
                return r;
            }
        }
    }
    panic!("no reload of {} within 100 s", file.display());
}

fn image(s: &ReloadSession) -> Vec<[f32; 4]> {
    s.frame.as_ref().unwrap().image.clone()
}

fn built(s: &ReloadSession) -> Vec<String> {
    s.prepared().unwrap().stats().pipelines_built.clone()
}

struct Fixture {
    _dir: tempfile::TempDir,
    root: PathBuf,
    session: ReloadSession,
}

fn fixture() -> Fixture {
    let project = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().canonicalize().unwrap();
    for g in ["forward_plus.ron", "brute_force.ron"] {
        std::fs::copy(project.join("graphs").join(g), root.join(g)).unwrap();
    }
    std::fs::write(root.join("box.ron"), material("(0.4, 0.4, 0.4)")).unwrap();
    std::fs::write(root.join("scene.ron"), SCENE).unwrap();
    let renderer = Renderer::new(
        lightgraph::gpu::GpuContext::new_headless().unwrap(),
        ShaderLibrary::builtin(),
    );
    let session = ReloadSession::new(
        renderer,
        &root.join("forward_plus.ron"),
        SceneSource::File(root.join("scene.ron")),
        96,
        64,
        &[],
    )
    .unwrap();
    Fixture {
        _dir: dir,
        root,
        session,
    }
}

#[test]
fn material_edits_rebuild_only_that_material_and_errors_keep_the_frame() {
    let Fixture {
        _dir,
        root,
        session: mut s,
    } = fixture();
    let box_ron = root.join("box.ron");
    assert!(
        s.watched_files().contains(&box_ron),
        "the override file is watched: {:?}",
        s.watched_files()
    );
    assert!(s.poll().is_none(), "nothing changed yet");
    let first = image(&s);

    // 1. Albedo (0.4, 0.4, 0.4) -> (0.2, 0.4, 0.1): box pixels scale by (0.5, 1, 0.25)
    //    (Lambert is linear in its colour), every other pixel stays bit for bit.
    let edited = material("(0.2, 0.4, 0.1)");
    std::fs::write(&box_ron, &edited).unwrap();
    let r = reload_of(&mut s, &box_ron);
    r.outcome.as_ref().expect("the edited material loads");
    assert_eq!(r.rebuilt, vec!["material harada_box".to_string()]);
    let second = image(&s);
    let (mut scaled, mut same_lit) = (0, 0);
    for (a, b) in second.iter().zip(&first) {
        if a == b {
            same_lit += usize::from(b[0] > 0.0);
            continue;
        }
        for (c, ratio) in [0.5f32, 1.0, 0.25].into_iter().enumerate() {
            let want = ratio * b[c];
            assert!(
                (a[c] - want).abs() <= 1e-5 * want.abs().max(1e-3),
                "channel {c}: {a:?} vs {ratio} x {b:?}"
            );
        }
        scaled += 1;
    }
    let pixels = first.len();
    println!("material edit: {scaled} box pixels scaled, {same_lit} lit pixels unchanged of {pixels}; {r:?}");
    assert!(scaled > pixels / 20, "{scaled} box pixels");
    assert!(same_lit > pixels / 20, "{same_lit} floor pixels");
    // Only the box's shading pipeline was built: its depth prepass never ran the
    // material code, the floor's pipelines are cache hits; no resource was created.
    let stats = s.prepared().unwrap().stats().clone();
    assert_eq!(built(&s).len(), 1, "{:?}", built(&s));
    assert!(built(&s)[0].contains("material `box`"), "{:?}", built(&s));
    assert!(stats.pipeline_hits >= 3, "{stats:?}");
    assert_eq!((stats.resources_reused, stats.resources_created), (3, 0));

    // 2. A save that does not parse: the error names box.ron and the line, the frame
    //    and the prepared frame stay.
    let bad = edited.replace(
        "Lambert(color: (0.2, 0.4, 0.1)),",
        "Lambert(color: (0.2, 0.4, 0.1)) oops,",
    );
    assert_ne!(bad, edited);
    std::fs::write(&box_ron, &bad).unwrap();
    let err = reload_of(&mut s, &box_ron)
        .outcome
        .expect_err("a material that does not parse must not load");
    assert!(err.contains("box.ron:7:"), "{err}");
    assert_eq!(image(&s), second, "the last good frame stays");
    assert_eq!(s.error.as_deref(), Some(err.as_str()));

    // 3. A save that parses but fails validation (a layer without lobes).
    let invalid = material("(0.2, 0.4, 0.1)").replace(
        "lobes: [\n                Lambert(color: (0.2, 0.4, 0.1)),\n            ],",
        "lobes: [],",
    );
    assert!(invalid.contains("lobes: [],"));
    std::fs::write(&box_ron, &invalid).unwrap();
    let err = reload_of(&mut s, &box_ron)
        .outcome
        .expect_err("a material without lobes must not load");
    assert!(err.contains("box.ron:6:"), "{err}");
    assert_eq!(image(&s), second, "the last good frame stays");

    // 4. Fixing it brings the frame back bit for bit; so does the original albedo.
    std::fs::write(&box_ron, &edited).unwrap();
    reload_of(&mut s, &box_ron)
        .outcome
        .expect("the fixed material loads");
    assert_eq!(image(&s), second);
    assert!(s.error.is_none());
    std::fs::write(&box_ron, material("(0.4, 0.4, 0.4)")).unwrap();
    reload_of(&mut s, &box_ron)
        .outcome
        .expect("the original material loads");
    assert_eq!(image(&s), first);
}

#[test]
fn graph_edits_keep_unchanged_resources_and_pipelines() {
    let Fixture {
        _dir,
        root,
        session: mut s,
    } = fixture();
    let first = image(&s);
    let graph = root.join("forward_plus.ron");
    let text = std::fs::read_to_string(&graph).unwrap();

    // 1. One pass parameter: the compact lists' bound. The list buffer changes size;
    //    depth and hdr are the same textures as before; no pipeline is rebuilt (the
    //    bound is a uniform, not a define).
    let before = s.prepared().unwrap().graph.plan.physical.len();
    let bound = "lists: Compact(max_indices: 16777216)";
    assert_eq!(text.matches(bound).count(), 1);
    std::fs::write(
        &graph,
        text.replace(bound, "lists: Compact(max_indices: 65536)"),
    )
    .unwrap();
    let r = reload_of(&mut s, &graph);
    r.outcome.as_ref().expect("the edited graph compiles");
    let stats = s.prepared().unwrap().stats().clone();
    println!("graph edit: {stats:?}; {r:?}");
    assert_eq!(before, 3);
    assert_eq!((stats.resources_reused, stats.resources_created), (2, 1));
    assert!(stats.pipelines_built.is_empty(), "{stats:?}");
    assert!(stats.pipeline_hits >= 6, "{stats:?}");
    // 48 lights never fill 65,536 indices: the same image.
    assert_eq!(image(&s), first);

    // 1b. Fixed lists of 128: a define changes, so only the culling pass's three
    //     pipelines (its bounds, coarse and fine stages share the module) are built.
    std::fs::write(&graph, text.replace(bound, "capacity: 128")).unwrap();
    let r = reload_of(&mut s, &graph);
    r.outcome.as_ref().expect("the edited graph compiles");
    let stats = s.prepared().unwrap().stats().clone();
    assert_eq!((stats.resources_reused, stats.resources_created), (2, 1));
    assert_eq!(stats.pipelines_built.len(), 3, "{stats:?}");
    assert!(
        stats
            .pipelines_built
            .iter()
            .all(|p| p.starts_with("cull/light_culling.wgsl")),
        "{stats:?}"
    );
    // 48 lights never overflow 128 entries: the same lists, the same image.
    assert_eq!(image(&s), first);

    // 2. Back to the shipped graph: again only the list buffer is new.
    std::fs::write(&graph, &text).unwrap();
    reload_of(&mut s, &graph)
        .outcome
        .expect("the original graph");
    let stats = s.prepared().unwrap().stats().clone();
    assert_eq!((stats.resources_reused, stats.resources_created), (2, 1));
    assert_eq!(image(&s), first);

    // 3. Switching to a graph with an error keeps the old graph and frame.
    let broken = root.join("broken.ron");
    std::fs::write(&broken, text.replace("output: \"hdr\"", "output: \"nope\"")).unwrap();
    let line = std::fs::read_to_string(&broken)
        .unwrap()
        .lines()
        .position(|l| l.contains("\"nope\""))
        .unwrap()
        + 1;
    let err = s.set_graph(&broken).expect_err("a broken graph");
    assert!(err.contains(&format!("broken.ron:{line}:")), "{err}");
    assert_eq!(s.graph_path(), graph.as_path());
    assert_eq!(
        s.prepared().unwrap().graph.checked.desc.name,
        "forward_plus"
    );
    assert_eq!(image(&s), first);

    // 4. Switching to brute force: the same image (no list overflows), the colour target
    //    is taken over, the old graph file no longer triggers anything.
    let brute = root.join("brute_force.ron");
    s.set_graph(&brute).expect("brute force");
    assert_eq!(s.prepared().unwrap().graph.checked.desc.name, "brute_force");
    let stats = s.prepared().unwrap().stats().clone();
    assert!(stats.resources_reused >= 1, "{stats:?}");
    let (d, _) = max_rel_diff(&image(&s), &first);
    assert!(d < 1e-5, "{d}");
    std::fs::write(&graph, text.replace(bound, "capacity: 64")).unwrap();
    let r = reload_of(&mut s, &graph);
    assert!(r.rebuilt.is_empty(), "{r:?}");
    assert_eq!(s.prepared().unwrap().graph.checked.desc.name, "brute_force");
}

/// A scene file naming the Cornell box glTF beside it, with one light and a camera.
const CORNELL_SCENE: &str = r#"Scene(
    name: "model_reload",
    models: [(path: "cornell/scene.gltf")],
    camera: LookAt(eye: (0, 1, 3.5), target: (0, 1, 0), fov_y_deg: 50, near: 0.05, far: 20),
    lights: [(name: "key", position: (0, 1.5, 0.2), range: 4, intensity: 2, color: (1, 1, 1))],
    ambient: (0, 0, 0),
)
"#;

#[test]
fn model_edits_reload_the_scene_and_broken_models_keep_the_frame() {
    let project = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().canonicalize().unwrap();
    std::fs::create_dir(root.join("cornell")).unwrap();
    for f in ["scene.gltf", "scene.bin"] {
        std::fs::copy(
            project.join("scenes/cornell_box").join(f),
            root.join("cornell").join(f),
        )
        .unwrap();
    }
    std::fs::copy(
        project.join("graphs/forward_plus.ron"),
        root.join("forward_plus.ron"),
    )
    .unwrap();
    std::fs::write(root.join("scene.ron"), CORNELL_SCENE).unwrap();
    let renderer = Renderer::new(
        lightgraph::gpu::GpuContext::new_headless().unwrap(),
        ShaderLibrary::builtin(),
    );
    let mut s = ReloadSession::new(
        renderer,
        &root.join("forward_plus.ron"),
        SceneSource::File(root.join("scene.ron")),
        96,
        64,
        &[],
    )
    .unwrap();
    // The model and its buffer are watched because the scene file names the model.
    let watched = s.watched_files();
    for f in ["scene.gltf", "scene.bin"] {
        assert!(
            watched
                .iter()
                .any(|w| w.ends_with(Path::new("cornell").join(f))),
            "{f} is not watched: {watched:?}"
        );
    }
    let first = image(&s);
    let red_wall = first
        .iter()
        .filter(|p| p[0] > 4.0 * p[1] && p[0] > 0.0)
        .count();
    assert!(red_wall > 50, "the red wall is in view ({red_wall} px)");

    // 1. Halve the left wall's red albedo in the glTF. Its pixels' red is diffuse (scales
    //    with the albedo) plus the dielectric specular (does not), so it drops to between
    //    half and all of what it was; green, blue and every other pixel stay bit for bit.
    let gltf = root.join("cornell/scene.gltf");
    let original = std::fs::read_to_string(&gltf).unwrap();
    let edited = original.replacen("0.6299999952316284", "0.3149999976158142", 1);
    assert_ne!(edited, original);
    std::fs::write(&gltf, &edited).unwrap();
    reload_of(&mut s, &gltf)
        .outcome
        .expect("the edited model loads");
    let second = image(&s);
    let mut halved = 0;
    for (a, b) in second.iter().zip(&first) {
        assert_eq!((a[1], a[2]), (b[1], b[2]), "green and blue are unchanged");
        if a[0] != b[0] {
            assert!(
                a[0] < b[0] && a[0] >= 0.5 * b[0],
                "red {} -> {}: the diffuse half goes, the specular stays",
                b[0],
                a[0]
            );
            halved += 1;
        }
    }
    assert!(halved >= red_wall / 2, "{halved} red pixels halved");

    // 2. A model that no longer parses: the error names the file, the frame stays.
    std::fs::write(&gltf, "{ \"asset\": ").unwrap();
    let err = reload_of(&mut s, &gltf)
        .outcome
        .expect_err("a truncated glTF must not load");
    assert!(err.contains("scene.gltf"), "{err}");
    assert!(image(&s) == second, "the last good frame stays");

    // 3. The fix brings the edited model back, bit for bit.
    std::fs::write(&gltf, &edited).unwrap();
    reload_of(&mut s, &gltf)
        .outcome
        .expect("the fixed model loads");
    assert!(image(&s) == second);
}
