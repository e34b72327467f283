//! Shader compose (includes, #if/#else, defines) and naga validation: the input is the
//! `<material>` code the forward shader includes; its first line, if it starts with
//! `defines:`, lists `NAME=VALUE` defines.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::collections::BTreeMap;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let (defines, code) = match text.split_once('\n') {
        Some((first, rest)) if first.starts_with("defines:") => {
            let defines: BTreeMap<String, String> = first["defines:".len()..]
                .split_whitespace()
                .filter_map(|d| d.split_once('='))
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect();
            (defines, rest.to_string())
        }
        _ => (BTreeMap::new(), text.to_string()),
    };
    let shaders = lightgraph::shader::ShaderLibrary::builtin();
    let virtual_files = BTreeMap::from([("material".to_string(), code)]);
    if let Ok(c) = shaders.compose("forward/forward.wgsl", &defines, &virtual_files) {
        let _ = c.validate();
    }
});
