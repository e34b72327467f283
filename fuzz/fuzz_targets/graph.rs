//! Graph parse + validate (with the built-in shaders, so generic passes compose and
//! validate real WGSL).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let shaders = lightgraph::shader::ShaderLibrary::builtin();
    let _ = lightgraph::graph::check_text(std::path::Path::new("fuzz.ron"), &text, &shaders);
});
