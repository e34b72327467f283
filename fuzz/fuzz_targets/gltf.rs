//! glTF import of .gltf JSON or .glb bytes, with the default limits; relative URIs resolve
//! under a folder that does not exist (data URIs and the GLB chunk are read).
#![no_main]
use libfuzzer_sys::fuzz_target;
use lightgraph::scene::gltf_import::{import_gltf_slice, ImportLimits};
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let base = Path::new("/nonexistent-lightgraph-fuzz");
    if let Ok(loaded) =
        import_gltf_slice(data, base, Path::new("fuzz.glb"), &ImportLimits::default())
    {
        let _ = loaded.scene.check_gpu_ranges(Path::new("fuzz.glb"));
    }
});
