//! The broken glTF corpus in tests/bad/gltf/ (regenerate with make_corpus.py there): each file
//! either fails with an error naming the file and element, or loads with a warning. None
//! panics.

use lightgraph::scene;
use std::path::Path;

enum Expect {
    /// `load` fails; the message contains every fragment.
    Error(&'static [&'static str]),
    /// `load` succeeds; some warning contains every fragment.
    Warning(&'static [&'static str]),
}
use Expect::*;

const CORPUS: &[(&str, Expect)] = &[
    (
        "missing_buffer.gltf",
        Error(&["buffer 0", "cannot read", "nope.bin"]),
    ),
    (
        "accessor_out_of_bounds.gltf",
        Error(&[
            "mesh 0 (\"tri\") primitive 0 POSITION accessor 0",
            "out of bounds",
            "100 elements",
        ]),
    ),
    (
        "buffer_view_out_of_bounds.gltf",
        Error(&[
            "mesh 0 (\"tri\") primitive 0 POSITION accessor 0",
            "bufferView 0",
            "out of bounds of buffer 0",
        ]),
    ),
    (
        "index_past_vertex_count.gltf",
        Error(&[
            // Semantic errors carry the JSON line and column of the element they name.
            "index_past_vertex_count.gltf:39:3: mesh 0 (\"tri\") primitive 0 indices accessor 1",
            "index 2 is 7, past the vertex count 3",
        ]),
    ),
    (
        "index_past_vertex_count_u32.gltf",
        Error(&["indices accessor 1", "index 5 is 70000"]),
    ),
    (
        "nan_position.gltf",
        Error(&["POSITION accessor 0", "vertex 1", "not finite"]),
    ),
    (
        "inf_position.gltf",
        Error(&["POSITION accessor 0", "vertex 2", "not finite"]),
    ),
    (
        "lines_primitive.gltf",
        Warning(&["mesh 0 (\"tri\") primitive 1", "Lines", "skipped"]),
    ),
    ("points_only.gltf", Warning(&["Points", "skipped"])),
    (
        "unsupported_required_extension.gltf",
        Error(&["extensionsRequired[0]", "KHR_draco_mesh_compression"]),
    ),
    (
        "absurd_accessor_count.gltf",
        Error(&[
            "POSITION accessor 0",
            "accessor count 4000000000 exceeds the limit",
        ]),
    ),
    (
        "absurd_buffer_length.gltf",
        Error(&["buffer 0", "byteLength 1000000000000000 exceeds the limit"]),
    ),
    (
        "dangling_accessor_reference.gltf",
        Error(&[
            "dangling_accessor_reference.gltf:26:7: glTF validation",
            "meshes[0].primitives[0].attributes",
        ]),
    ),
    (
        "node_cycle.gltf",
        Error(&["node_cycle.gltf:20:3: node 1", "cycle"]),
    ),
    (
        "node_instance_explosion.gltf",
        Error(&["node instance count", "exceeds the limit"]),
    ),
    (
        "inf_node_transform.gltf",
        Error(&["node 0 (\"tri_node\")", "transform is not finite"]),
    ),
    (
        "light_negative_range.gltf",
        Error(&[
            "light_negative_range.gltf:70:6: light 0 (\"lamp\")",
            "range",
        ]),
    ),
    (
        "light_infinite_intensity.gltf",
        Error(&["light 0 (\"sun\")", "intensity"]),
    ),
    (
        "missing_texture.gltf",
        Warning(&[
            "material 0 (\"painted\") baseColorTexture",
            "no_such_image.png",
            "neutral",
        ]),
    ),
    ("bad_base64.gltf", Error(&["buffer 0", "base64"])),
    (
        "buffer_shorter_than_declared.gltf",
        Error(&["buffer 0", "byteLength says 1000"]),
    ),
    (
        "sparse_accessor.gltf",
        Error(&[
            "POSITION accessor 0",
            "sparse index 0 is 1065353216",
            "past the accessor's count 3",
        ]),
    ),
    (
        "position_wrong_type.gltf",
        Error(&["POSITION accessor 0", "Vec3"]),
    ),
    ("bad_json.gltf", Error(&["bad_json.gltf:3:"])),
    (
        "glb_without_bin_chunk.glb",
        Error(&["buffer 0", "binary chunk"]),
    ),
    ("truncated.glb", Error(&["truncated.glb", "GLB"])),
];

#[test]
fn broken_gltf_corpus() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad/gltf");
    let mut failures = Vec::new();
    for (file, expect) in CORPUS {
        let path = dir.join(file);
        assert!(path.exists(), "{} missing", path.display());
        let result = std::panic::catch_unwind(|| scene::load(&path));
        let Ok(result) = result else {
            failures.push(format!("{file}: PANICKED"));
            continue;
        };
        match (expect, result) {
            (Error(frags), Err(e)) => {
                let msg = e.to_string();
                eprintln!("{msg}");
                if !msg.contains(*file) || !frags.iter().all(|f| msg.contains(f)) {
                    failures.push(format!("{file}: error lacks {frags:?}:\n    {msg}"));
                }
            }
            (Error(frags), Ok(l)) => failures.push(format!(
                "{file}: loaded, expected error {frags:?}; warnings {:?}",
                l.warnings
            )),
            (Warning(frags), Ok(l)) => {
                eprintln!("{:?}", l.warnings);
                if !l
                    .warnings
                    .iter()
                    .any(|w| w.contains(*file) && frags.iter().all(|f| w.contains(f)))
                {
                    failures.push(format!(
                        "{file}: no warning with {frags:?}: {:?}",
                        l.warnings
                    ));
                }
            }
            (Warning(frags), Err(e)) => failures.push(format!(
                "{file}: expected a warning {frags:?}, got error:\n    {e}"
            )),
        }
    }
    // Every file of the corpus is in the table.
    for e in std::fs::read_dir(&dir).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        if (name.ends_with(".gltf") || name.ends_with(".glb"))
            && !CORPUS.iter().any(|(f, _)| *f == name)
        {
            failures.push(format!("{name}: not in the table"));
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}
