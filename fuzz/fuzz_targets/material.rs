//! Material parse + sanitise + WGSL generation and its naga validation.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(m) = lightgraph::material::Material::parse(&text, "fuzz/material.ron") {
        let _ = m.wgsl();
    }
});
