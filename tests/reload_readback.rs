//! What a reload waits for: with image readback (the default) it ends once the new frame
//! is read back into `ReloadSession::frame`; without it (the viewer, which presents the
//! output texture) it ends when the frame's GPU work is done. Either way `frame_ready`
//! is when the GPU finished the new frame, which the reload benchmark's headline uses.

mod common;
use common::*;
use lightgraph::reload::{Reload, ReloadSession, SceneSource};
use lightgraph::render::Renderer;
use lightgraph::shader::ShaderLibrary;
use std::path::Path;
use std::time::Duration;

const LINE: &str = "return clamp(1.0 - r * r, 0.0, 1.0);";

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

/// Writes `text` to `file` and waits (bounded) for the reload that handled it.
fn edit(s: &mut ReloadSession, file: &Path, text: &str) -> Reload {
    while s.poll().is_some() {}
    std::fs::write(file, text).unwrap();
    for _ in 0..20 {
        if let Some(r) = s.wait(Duration::from_secs(5)) {
            if r.changed
                .iter()
                .any(|c| c.ends_with(file.file_name().unwrap()))
            {
                return r;
            }
        }
    }
    panic!("no reload of {} within 100 s", file.display());
}

#[test]
fn without_readback_a_reload_ends_when_the_frame_is_on_the_gpu() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let shaders = dir.path().join("shaders");
    copy_dir(&root.join("shaders"), &shaders);
    let graph = dir.path().join("forward_plus.ron");
    std::fs::copy(root.join("graphs/forward_plus.ron"), &graph).unwrap();
    let renderer = Renderer::new(
        lightgraph::gpu::GpuContext::new_headless().unwrap(),
        ShaderLibrary::new(&shaders),
    );
    let mut s = ReloadSession::new(
        renderer,
        &graph,
        SceneSource::Fixed(Box::new(random_scene(24, 5))),
        64,
        36,
        &[],
    )
    .unwrap();
    assert!(s.frame.is_some(), "the first frame is read back");
    let file = shaders.join("common/lighting.wgsl");
    let original = std::fs::read_to_string(&file).unwrap();
    assert!(original.contains(LINE));
    let scaled =
        |k: &str| original.replace(LINE, &format!("return {k} * clamp(1.0 - r * r, 0.0, 1.0);"));

    // Read back: the image is there, and the frame was ready before the reload ended.
    let r = edit(&mut s, &file, &scaled("0.5"));
    assert!(r.outcome.is_ok(), "{:?}", r.outcome);
    let ready = r.frame_ready.expect("a frame rendered");
    assert!(ready <= r.finished);
    let t = r.timings.frame.expect("render timings");
    assert!(t.image_readback > Duration::ZERO);
    let image = s.frame.as_ref().expect("read back").image.clone();
    assert_eq!(image.len(), 64 * 36);

    // Not read back: the reload ends with the GPU's work, nothing is copied back, and the
    // frame to present is the new one.
    s.set_image_readback(false);
    let r = edit(&mut s, &file, &scaled("0.25"));
    assert!(r.outcome.is_ok(), "{:?}", r.outcome);
    assert!(r.frame_ready.is_some());
    let t = r.timings.frame.expect("render timings");
    assert_eq!(t.image_readback, Duration::ZERO);
    assert!(s.frame.is_none(), "nothing read back");
    assert!(s.prepared().is_some());
}
