//! Scene-file parse and build (built-in scenes, lights, light sets, cameras); model paths
//! resolve under a folder that does not exist, so only the error paths of model loading run.
#![no_main]
use libfuzzer_sys::fuzz_target;
use lightgraph::scene::scene_file::{build_scene, parse_scene_file};

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let file = std::path::Path::new("/nonexistent-lightgraph-fuzz/scene.ron");
    if let Ok(spec) = parse_scene_file(&text, file) {
        if let Ok(loaded) = build_scene(&spec, file) {
            let _ = loaded.scene.check_gpu_ranges(file);
        }
    }
});
