//! Hostile input through the command line, as a user meets it: `lightgraph validate` must
//! refuse each bad file with its message (naming the file), `lightgraph render` at 64×36
//! must refuse it the same way, and neither may crash, take over 10 s or 1 GiB. Hostile
//! but valid files (a byte-order mark, a texture wider than the device allows) must pass
//! both. Inputs: every graph in tests/bad/graphs/, every file in tests/bad/hostile/ (made
//! by its make_hostile.py), and the large or special ones generated here into a temporary
//! folder: a 20,000-term WGSL expression, a 10,000-file include chain, a 20,000-layer
//! material, and /dev/zero, /dev/urandom and FIFOs in every place a file is read.
// Resource limits and special files (FIFOs, symlinks) through libc: Unix only.
#![cfg(unix)]

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const LIMIT: Duration = Duration::from_secs(10);
const MAX_RSS_KIB: i64 = 1 << 20;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

struct Outcome {
    code: Option<i32>,
    output: String,
}

/// Runs the CLI from the repository root with the output in files (no pipe to fill),
/// reaping it with wait4 for its peak memory; fails past the time or memory limit.
fn lightgraph(args: &[OsString]) -> Outcome {
    let dir = tempfile::tempdir().unwrap();
    let (out, err) = (dir.path().join("out"), dir.path().join("err"));
    // Reaped by wait4 below, which also gives its peak memory.
    #[allow(clippy::zombie_processes)]
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_lightgraph"))
        .args(args)
        .current_dir(root())
        .env(
            "XDG_RUNTIME_DIR",
            std::env::var_os("XDG_RUNTIME_DIR").unwrap_or("/tmp".into()),
        )
        .env("RUST_BACKTRACE", "0")
        .stdout(std::fs::File::create(&out).unwrap())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .unwrap();
    let pid = child.id() as libc::pid_t;
    let start = Instant::now();
    let (mut status, mut usage) = (0, unsafe { std::mem::zeroed::<libc::rusage>() });
    loop {
        // SAFETY: waits for our own child; `status` and `usage` outlive the call.
        let r = unsafe { libc::wait4(pid, &mut status, libc::WNOHANG, &mut usage) };
        if r == pid {
            break;
        }
        assert!(r == 0, "wait4: {}", std::io::Error::last_os_error());
        if start.elapsed() > LIMIT {
            unsafe { libc::kill(pid, libc::SIGKILL) };
            unsafe { libc::waitpid(pid, &mut status, 0) };
            panic!("lightgraph {args:?} ran past {LIMIT:?}");
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let output = std::fs::read_to_string(&out).unwrap() + &std::fs::read_to_string(&err).unwrap();
    assert!(
        libc::WIFEXITED(status),
        "lightgraph {args:?} was killed by signal {}:\n{output}",
        libc::WTERMSIG(status)
    );
    assert!(
        usage.ru_maxrss <= MAX_RSS_KIB,
        "lightgraph {args:?} peaked at {} MiB",
        usage.ru_maxrss / 1024
    );
    let secs = start.elapsed().as_secs_f64();
    eprintln!(
        "{secs:.2} s {:>4} MiB  lightgraph {}",
        usage.ru_maxrss / 1024,
        args.iter()
            .map(|a| a.to_string_lossy())
            .collect::<Vec<_>>()
            .join(" ")
    );
    Outcome {
        code: Some(libc::WEXITSTATUS(status)),
        output,
    }
}

fn os(args: &[&str], file: &Path) -> Vec<OsString> {
    let mut v: Vec<OsString> = args.iter().map(OsString::from).collect();
    v.push(file.into());
    v
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Input {
    Graph,
    Scene,
    /// Checked by `validate` only (materials, shaders: they render through a scene or graph).
    ValidateOnly,
    /// Checked by `validate` and `bench --sweep`.
    Sweep,
}

#[derive(Clone, Debug)]
enum Expect {
    /// Refused by validate and render; the message contains this and names the file.
    Error(String),
    /// Accepted by both; render's output contains this, if given.
    Accept(Option<String>),
}

/// Runs one input through validate and, for graphs and scenes, render at 64×36.
fn check(file: &Path, input: Input, expect: &Expect, failures: &mut Vec<String>) {
    let name = file.file_name().unwrap().to_string_lossy().into_owned();
    let mut runs = vec![("validate", lightgraph(&os(&["validate"], file)))];
    let size = ["--width", "64", "--height", "36"];
    match input {
        Input::Graph => runs.push((
            "render",
            lightgraph(&os(&[&["render"][..], &size, &["--graph"]].concat(), file)),
        )),
        Input::Scene => runs.push((
            "render",
            lightgraph(&os(&[&["render"][..], &size, &["--scene"]].concat(), file)),
        )),
        Input::Sweep => {
            let out = tempfile::tempdir().unwrap();
            let mut args = os(&["bench", "--out"], out.path());
            args.push("--sweep".into());
            args.push(file.into());
            runs.push(("bench", lightgraph(&args)));
        }
        Input::ValidateOnly => {}
    }
    for (command, o) in runs {
        let ok = match expect {
            Expect::Error(m) => {
                o.code == Some(1) && o.output.contains(m) && o.output.contains(&name)
            }
            Expect::Accept(m) => {
                o.code == Some(0)
                    && (command == "validate" || m.as_ref().is_none_or(|m| o.output.contains(m)))
            }
        };
        if !ok {
            failures.push(format!(
                "{} ({command}, exit {:?}): expected {expect:?}, got:\n{}",
                file.display(),
                o.code,
                o.output.lines().take(6).collect::<Vec<_>>().join("\n")
            ));
        }
    }
}

/// `// expect: MESSAGE` on the first line (after a byte-order mark), or `// accept: WHY`
/// with an optional `// warns: WARNING` on the second.
fn expectation(file: &Path) -> Expect {
    let text = std::fs::read_to_string(file).unwrap();
    let mut lines = text.trim_start_matches('\u{feff}').lines();
    let first = lines.next().unwrap_or("");
    if let Some(m) = first.strip_prefix("// expect: ") {
        Expect::Error(m.to_string())
    } else if first.starts_with("// accept: ") {
        let warns = lines.next().and_then(|l| l.strip_prefix("// warns: "));
        Expect::Accept(warns.map(str::to_string))
    } else {
        panic!(
            "{}: first line must be `// expect: ...` or `// accept: ...`",
            file.display()
        )
    }
}

fn files(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .collect();
    v.sort();
    v
}

#[test]
fn every_bad_graph_is_refused_by_validate_and_render() {
    let mut failures = Vec::new();
    let graphs = files(&root().join("tests/bad/graphs"), "ron");
    for g in &graphs {
        check(g, Input::Graph, &expectation(g), &mut failures);
    }
    assert!(graphs.len() >= 25, "only {} bad graphs", graphs.len());
    assert!(failures.is_empty(), "\n{}", failures.join("\n\n"));
}

/// Sweep files whose counts would allocate or loop without bound: refused at the line of
/// the field, before any GPU work.
#[test]
fn bad_sweeps_are_refused_by_validate_and_bench() {
    let mut failures = Vec::new();
    let sweeps = files(&root().join("tests/bad/sweeps"), "ron");
    for f in &sweeps {
        check(f, Input::Sweep, &expectation(f), &mut failures);
    }
    assert!(sweeps.len() >= 5, "only {} bad sweeps", sweeps.len());
    assert!(failures.is_empty(), "\n{}", failures.join("\n\n"));
}

/// What a glTF file of tests/bad/hostile/ must give.
enum Gltf {
    Refused(&'static str),
    /// Accepted; render's output contains this warning.
    Warns(&'static str),
}
use Gltf::*;

/// The glTF files of tests/bad/hostile/ (JSON has no comments to hold the expectation).
const HOSTILE_GLTF: &[(&str, Gltf)] = &[
    (
        "dag_triangles.gltf",
        Refused("meshes: triangle count after instancing 51200000 exceeds the limit of 8388608"),
    ),
    (
        "dag_primitives.gltf",
        Refused("meshes: mesh primitive count after instancing 65536 exceeds the limit of 32768"),
    ),
    (
        "node_scale_zero.gltf",
        Refused("node 0 (\"tri_node\"): transform is not invertible (a scale of 0 or an all-zero matrix)"),
    ),
    (
        "node_zero_matrix.gltf",
        Refused("node 0 (\"tri_node\"): transform is not invertible"),
    ),
    (
        "misaligned_accessor.gltf",
        Refused("POSITION accessor 0: byteOffset 2 is not a multiple of its component size 4"),
    ),
    (
        "vertex_3e38.gltf",
        Refused("mesh 0 (\"tri\") vertex 1: position Vec3(3e38, 0.0, 0.0) after the scene transform is not finite or beyond ±1e5 m"),
    ),
    (
        "light_3e38.gltf",
        Refused("light 0: intensity 3e38 × colour Vec3(1.0, 1.0, 1.0) is 3e38 cd, over the limit of 1e15"),
    ),
    (
        // Found by the gltf fuzz target: 40 levels of shared children closed into a
        // cycle took a million node visits to refuse; now a linear search names it.
        "dag_cycle.gltf",
        Refused("node hierarchy contains a cycle: its child node"),
    ),
    // Coverage lies in 0..=1: a cutoff outside keeps every fragment or none, and one that
    // is infinite as an f32 is no WGSL literal.
    (
        "alpha_cutoff_2.gltf",
        Refused("alpha_cutoff_2.gltf:50:4: material 0 (\"tri_mat\"): alphaCutoff 2 must be a finite number in 0..=1"),
    ),
    (
        "alpha_cutoff_neg1.gltf",
        Refused("alpha_cutoff_neg1.gltf:50:4: material 0 (\"tri_mat\"): alphaCutoff -1 must be a finite number in 0..=1"),
    ),
    (
        "alpha_cutoff_1e39.gltf",
        Refused("alpha_cutoff_1e39.gltf:50:4: material 0 (\"tri_mat\"): alphaCutoff inf must be a finite number in 0..=1"),
    ),
    (
        "uv_3e38.gltf",
        Refused("mesh 0 (\"tri\") vertex 1: texture coordinate Vec2(3e38, 0.0) is not finite or beyond ±4096"),
    ),
    ("wide_texture.gltf", Warns("is 40000×1, over the device's limit of")),
    ("bom.gltf", Warns("")),
];

#[test]
fn hostile_scenes_models_and_materials() {
    let dir = root().join("tests/bad/hostile");
    let mut failures = Vec::new();
    for f in files(&dir, "ron") {
        let text = std::fs::read_to_string(&f).unwrap();
        let input = match lightgraph::file_kind::top_level_name(&text) {
            Some("Graph") => Input::Graph,
            Some("Scene") => Input::Scene,
            _ => Input::ValidateOnly,
        };
        check(&f, input, &expectation(&f), &mut failures);
    }
    for (name, outcome) in HOSTILE_GLTF {
        let expect = match outcome {
            Refused(m) => Expect::Error(m.to_string()),
            Warns(m) => Expect::Accept(Some(m.to_string())),
        };
        check(&dir.join(name), Input::Scene, &expect, &mut failures);
    }
    for f in files(&dir, "gltf") {
        let name = f.file_name().unwrap().to_string_lossy();
        if !HOSTILE_GLTF.iter().any(|(n, _)| *n == name) {
            failures.push(format!("{name}: not in HOSTILE_GLTF"));
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n\n"));
}

fn write(path: &Path, text: &str) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, text).unwrap();
}

fn symlink(target: &str, link: &Path) {
    std::fs::create_dir_all(link.parent().unwrap()).unwrap();
    std::os::unix::fs::symlink(target, link).unwrap();
}

fn mkfifo(path: &Path) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    let c = std::ffi::CString::new(path.as_os_str().as_encoded_bytes()).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0);
}

/// A copy of graphs/light_throughput_probe.ron running `shader` (an absolute path).
fn probe_graph(shader: &Path) -> String {
    let text = std::fs::read_to_string(root().join("graphs/light_throughput_probe.ron")).unwrap();
    let probe = "examples/light_throughput_probe.wgsl";
    assert!(text.contains(probe));
    text.replace(probe, &shader.display().to_string())
}

/// The probe shader with `statement` before its entry point.
fn probe_shader(statement: &str) -> String {
    let text = std::fs::read_to_string(root().join("shaders/examples/light_throughput_probe.wgsl"))
        .unwrap();
    format!("{statement}\n{text}")
}

#[test]
fn generated_large_and_special_inputs() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let mut failures = Vec::new();
    let error = |m: &str| Expect::Error(m.to_string());

    // WGSL: 20,000 terms in one expression (a stack overflow in naga before).
    let long = t.join("long_expression.wgsl");
    write(
        &long,
        &probe_shader(&format!("const x = 1{};", " + 1".repeat(20_000))),
    );
    let long_graph = t.join("graphs/long_expression.ron");
    write(&long_graph, &probe_graph(&long));
    let over = "long_expression.wgsl:1:1: this statement has over 1024 operators";
    check(&long_graph, Input::Graph, &error(over), &mut failures);
    check(&long, Input::ValidateOnly, &error(over), &mut failures);

    // An include chain 10,000 files deep.
    let chain = t.join("chain");
    for i in 0..10_000 {
        write(
            &chain.join(format!("inc{i}.wgsl")),
            &format!(
                "#include \"{}\"\n",
                chain.join(format!("inc{}.wgsl", i + 1)).display()
            ),
        );
    }
    write(&chain.join("inc10000.wgsl"), "const deepest = 1;\n");
    let top = chain.join("top.wgsl");
    let first = chain.join("inc0.wgsl");
    write(
        &top,
        &probe_shader(&format!("#include \"{}\"", first.display())),
    );
    let chain_graph = t.join("graphs/include_chain.ron");
    write(&chain_graph, &probe_graph(&top));
    let deep = format!(
        "inc31.wgsl:1: #include \"{}\" is nested 33 deep, over the limit of 32",
        chain.join("inc32.wgsl").display()
    );
    check(&chain_graph, Input::Graph, &error(&deep), &mut failures);

    // A material of 20,000 layers (over 30 s to compile before).
    let layers = t.join("materials/layers.ron");
    let layer = "(lobes: [Lambert(color: (0.5, 0.5, 0.5))]),";
    write(
        &layers,
        &format!("(name: \"deep\", layers: [{}])", layer.repeat(20_000)),
    );
    let too_many = "layers.ron:1:16: layer count 20000 is over the limit of 32";
    check(
        &layers,
        Input::ValidateOnly,
        &error(too_many),
        &mut failures,
    );

    // Devices and FIFOs wherever a file is read: graph, scene, material, shader, model,
    // glTF buffer and image.
    let device = "not a regular file (a device)";
    let fifo = "not a regular file (a FIFO)";
    symlink("/dev/zero", &t.join("graphs/zero.ron"));
    check(
        &t.join("graphs/zero.ron"),
        Input::Graph,
        &error(device),
        &mut failures,
    );
    mkfifo(&t.join("scenes/fifo.ron"));
    check(
        &t.join("scenes/fifo.ron"),
        Input::Scene,
        &error(fifo),
        &mut failures,
    );
    symlink("/dev/urandom", &t.join("materials/urandom.ron"));
    check(
        &t.join("materials/urandom.ron"),
        Input::ValidateOnly,
        &error(device),
        &mut failures,
    );
    mkfifo(&t.join("fifo.wgsl"));
    let fifo_shader = t.join("graphs/fifo_shader.ron");
    write(&fifo_shader, &probe_graph(&t.join("fifo.wgsl")));
    check(&fifo_shader, Input::Graph, &error(fifo), &mut failures);
    symlink("/dev/zero", &t.join("zero.gltf"));
    let model = t.join("scenes/zero_model.ron");
    write(&model, "Scene(models: [(path: \"../zero.gltf\")])");
    check(&model, Input::Scene, &error(device), &mut failures);
    let tri = std::fs::read_to_string(root().join("tests/bad/hostile/models/tri.gltf")).unwrap();
    let data_uri = tri.find("data:application").unwrap();
    let uri_end = data_uri + tri[data_uri..].find('"').unwrap();
    symlink("/dev/zero", &t.join("zero.bin"));
    let zero_buffer = t.join("zero_buffer.gltf");
    write(
        &zero_buffer,
        &format!("{}zero.bin{}", &tri[..data_uri], &tri[uri_end..]),
    );
    check(&zero_buffer, Input::Scene, &error(device), &mut failures);
    // A texture that never ends costs a warning, as a missing one does.
    symlink("/dev/urandom", &t.join("urandom.png"));
    let image = t.join("urandom_image.gltf");
    let with_image = tri.replacen(
        "\"materials\": [",
        "\"images\": [{\"uri\": \"urandom.png\"}], \"textures\": [{\"source\": 0}], \"materials\": [",
        1,
    );
    let with_image = with_image.replacen(
        "\"name\": \"tri_mat\"",
        "\"name\": \"tri_mat\", \"pbrMetallicRoughness\": {\"baseColorTexture\": {\"index\": 0}}",
        1,
    );
    write(&image, &with_image);
    check(
        &image,
        Input::Scene,
        &Expect::Accept(Some(device.into())),
        &mut failures,
    );
    assert!(failures.is_empty(), "\n{}", failures.join("\n\n"));
}

/// What only the device can refuse, at prepare, named with the graph file:line and pass:
/// an output wider than its texture limit, a per-light dispatch over its workgroup limit.
#[test]
fn device_limits_are_checked_at_prepare() {
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    let mut failures = Vec::new();
    let mut expect = |args: Vec<OsString>, want: &str| {
        let o = lightgraph(&args);
        if o.code != Some(1) || !o.output.contains(want) {
            failures.push(format!("{args:?}: want {want:?}, got:\n{}", o.output));
        }
    };
    // Every side within the graph's own limits (16384 frames, Scaled up to 4), but the
    // scaled texture is 32,800 wide: over any device's limit (8192 to 32768).
    let scaled = t.join("scaled.ron");
    write(
        &scaled,
        r#"Graph(
    name: "scaled",
    resources: [
        Texture(name: "hdr", format: Rgba32Float),
        Texture(name: "big", format: Rgba8Unorm, size: Scaled(4.0)),
    ],
    passes: [
        Pass(name: "solid", kind: Fullscreen(shader: "examples/solid.wgsl"), writes: ["hdr"]),
        Pass(name: "wide", kind: Fullscreen(shader: "examples/solid.wgsl"), writes: ["big"]),
    ],
    output: "hdr",
    side_effects: ["wide"],
)"#,
    );
    let mut args = os(
        &["render", "--width", "8200", "--height", "4", "--graph"],
        &scaled,
    );
    args.push(OsString::from("--out"));
    args.push(t.join("x.png").into());
    expect(
        args,
        "scaled.ron:9:86: pass 'wide': resource 'big': texture of 32800×16 is over the device's limit of",
    );
    let graph = t.join("per_light.ron");
    write(
        &graph,
        r#"Graph(
    name: "per_light",
    resources: [
        Texture(name: "hdr", format: Rgba32Float),
        Buffer(name: "scratch", size: Bytes(64)),
    ],
    passes: [
        Pass(name: "count", kind: Compute(shader: "../tests/bad/shaders/per_light.wgsl", dispatch: PerLight(workgroup: 1)), writes: ["scratch"]),
        Pass(name: "solid", kind: Fullscreen(shader: "examples/solid.wgsl"), writes: ["hdr"]),
    ],
    output: "hdr",
    side_effects: ["count"],
)"#,
    );
    let scene = t.join("lights.ron");
    write(
        &scene,
        "Scene(builtin: \"atrium\", keep_model_lights: false, light_sets: [Random(count: 70000, spot_fraction: 0, placement: SceneBounds(margin: 0), range: (0.2, 0.6), intensity: (0.5, 2), seed: 7)])",
    );
    let mut args = os(
        &["render", "--width", "64", "--height", "36", "--graph"],
        &graph,
    );
    args.extend([OsString::from("--scene"), scene.into()]);
    expect(
        args,
        "per_light.ron:8:20: pass 'count': dispatch of [70000, 1, 1] workgroups is over the device's limit of 65535 per dimension",
    );
    assert!(failures.is_empty(), "\n{}", failures.join("\n\n"));
}

/// A light loop that may run longer than the adapter lets one loop run: llvmpipe leaves a
/// loop after 65,535 iterations without a word, and brute force over 70,000 lights lost
/// every light past the 65,535th (black where only those reach). Refused there, naming
/// the graph line and pass; rendered where the adapter has no such limit.
#[test]
fn light_loops_are_checked_against_the_adapter() {
    let ctx = lightgraph::render::Renderer::headless().unwrap().ctx;
    let info = ctx.adapter.get_info();
    // The driver's documented limit decides (`gpu::driver_limits`), as it does in prepare.
    let limited = ctx.driver_limits.loop_iterations == Some(65_535);
    // lavapipe (CI's adapter) must be known by its driver, or this test checks nothing.
    assert!(limited || !info.name.starts_with("llvmpipe"), "{info:?}");
    let tmp = tempfile::tempdir().unwrap();
    let scene = tmp.path().join("lights_70000.ron");
    write(
        &scene,
        "Scene(builtin: \"atrium\", keep_model_lights: false, light_sets: [Random(count: 70000, spot_fraction: 0, placement: SceneBounds(margin: 0), range: (0.2, 0.6), intensity: (0.5, 2), seed: 7)])",
    );
    let mut failures = Vec::new();
    for (graph, want) in [
        (
            "brute_force.ron",
            "brute_force.ron:15:19: pass 'forward_shading': its light loop may visit 70000 lights at one pixel (lights: AllLights), over this adapter's limit of 65535 iterations a loop",
        ),
        (
            "forward_plus.ron",
            "forward_plus.ron:31:19: pass 'forward_shading': its light loop may visit 70000 lights at one pixel ('light_lists': a tile's list may hold up to that many), over this adapter's limit of 65535 iterations a loop",
        ),
    ] {
        let mut args = os(
            &["render", "--width", "16", "--height", "9", "--graph"],
            &root().join("graphs").join(graph),
        );
        args.extend([OsString::from("--scene"), scene.clone().into()]);
        args.push(OsString::from("--out"));
        args.push(tmp.path().join("x.png").into());
        let o = lightgraph(&args);
        let ok = if limited {
            o.code == Some(1) && o.output.contains(want)
        } else {
            o.code == Some(0)
        };
        if !ok {
            failures.push(format!("{graph} on {}: want {want:?}, got:\n{}", info.name, o.output));
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n\n"));
}

/// The largest storage buffer binding this machine's default device allows.
fn storage_binding_limit() -> u64 {
    lightgraph::render::Renderer::headless()
        .unwrap()
        .ctx
        .device
        .limits()
        .max_storage_buffer_binding_size
}

/// A pass's own buffers (not planned by the graph) are checked against the device before
/// they are created: at 4100×4100 the culling's coarse lists of Forward+ and tiled deferred
/// are 138,461,700 bytes, over a 128 MiB storage binding (wgpu's raw
/// `max_*_buffer_binding_size` text before). Refused where the device's limit is lower,
/// rendered where it is not.
#[test]
fn internal_buffers_are_checked_against_the_device() {
    const COARSE_BYTES: u64 = 138_461_700;
    let limit = storage_binding_limit();
    let tmp = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    for (graph, at) in [
        ("forward_plus.ron", "forward_plus.ron:25:19"),
        ("tiled_deferred.ron", "tiled_deferred.ron:24:19"),
    ] {
        let mut args = os(
            &["render", "--width", "4100", "--height", "4100", "--graph"],
            &root().join("graphs").join(graph),
        );
        args.push(OsString::from("--out"));
        args.push(tmp.path().join("x.png").into());
        let o = lightgraph(&args);
        let want = format!(
            "{at}: pass 'light_culling': its buffer 'coarse light lists' of {COARSE_BYTES} bytes is over the device's limit of {limit} bytes for a storage buffer binding"
        );
        let ok = if COARSE_BYTES > limit {
            o.code == Some(1) && o.output.contains(&want) && !o.output.contains("wgpu")
        } else {
            o.code == Some(0)
        };
        if !ok {
            failures.push(format!(
                "{graph}: want {want:?} (limit {limit}), got:\n{}",
                o.output
            ));
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n\n"));
}

/// The default graph's ray-cast shadow jobs (16 a pixel: 315 MB at 1920×1080) on a device
/// whose storage buffers are smaller (lavapipe's 128 MiB): refused naming the graph line,
/// the pass and the resource, with the jobs_per_pixel that fits (checked where the
/// device's limit is under the buffer).
#[test]
fn the_job_buffer_error_says_what_fits() {
    const JOB_BYTES: u64 = 315_187_232;
    let limit = storage_binding_limit();
    if JOB_BYTES <= limit {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let mut args = os(
        &["render", "--width", "1920", "--height", "1080", "--scene"],
        &root().join("scenes/chairs.ron"),
    );
    args.push(OsString::from("--out"));
    args.push(tmp.path().join("x.png").into());
    let o = lightgraph(&args);
    let want = format!(
        "default.ron:107:22: pass 'shadow_ray_jobs': resource 'shadow_jobs': buffer of {JOB_BYTES} bytes is over the device's limit of {limit} bytes for a storage buffer: ShadowRayJobs' jobs_per_pixel "
    );
    assert!(
        o.code == Some(1) && o.output.contains(&want) && o.output.contains("or less fits"),
        "want {want:?}, got:\n{}",
        o.output
    );
}

/// The light-loop check reads the context's driver limits, not the adapter's name: with a
/// limit of 8 set on this adapter, whatever it is, brute force over 9 lights is refused
/// naming the pass, and over 8 it prepares (with the light statistics, whose exact count
/// is checked the same way).
#[test]
fn the_light_loop_limit_is_the_driver_limits_one() {
    use lightgraph::graph::{self, FrameSize};
    use lightgraph::render::{Renderer, SceneGpu};
    use lightgraph::scene::Light;
    let mut r = Renderer::headless().unwrap();
    r.ctx.driver_limits.loop_iterations = Some(8);
    let graph_file = root().join("graphs/brute_force.ron");
    let shaders = lightgraph::shader::ShaderLibrary::builtin();
    let prepare = |r: &mut Renderer, lights: usize, stats: bool| {
        let mut scene = lightgraph::scene::builtin::by_name("depth_discontinuity").unwrap();
        scene.lights = (0..lights)
            .map(|i| {
                Light::point(
                    glam::Vec3::new(i as f32, 2.0, 0.0),
                    5.0,
                    glam::Vec3::ONE,
                    1.0,
                )
            })
            .collect();
        let size = FrameSize {
            width: 16,
            height: 9,
            lights: lights as u32,
        };
        let checked = graph::check_file(&graph_file, &shaders).unwrap();
        let compiled = graph::compile(checked, &scene.features(), size);
        let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, &scene).unwrap();
        r.prepare(compiled, &scene, &gpu, size, stats).map(|_| ())
    };
    let want = "its light loop may visit 9 lights at one pixel (lights: AllLights), over this adapter's limit of 8 iterations a loop";
    match prepare(&mut r, 9, false) {
        Err(e) if e.to_string().contains(want) && e.to_string().contains("forward_shading") => {}
        other => panic!("want {want:?}, got {other:?}"),
    }
    prepare(&mut r, 8, true).expect("8 lights are within a limit of 8");
}

/// The warnings the library logs, kept for the test that reads them.
struct Captured;
static WARNINGS: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
impl log::Log for Captured {
    fn enabled(&self, m: &log::Metadata) -> bool {
        m.level() <= log::Level::Warn
    }
    fn log(&self, r: &log::Record) {
        if self.enabled(r.metadata()) {
            WARNINGS.lock().unwrap().push(r.args().to_string());
        }
    }
    fn flush(&self) {}
}

/// A material override whose texture is 9000×4, on a device opened with wgpu's default
/// limits (8192 a side, as an application embedding lightgraph may open it): the texture
/// is scaled down with a warning that names the material file and the texture file, and
/// the frame is what the same colour at 64×4 gives. Generated in a temporary folder.
#[test]
fn a_texture_wider_than_the_device_is_scaled_with_a_warning_naming_it() {
    use lightgraph::graph::{self, FrameSize};
    use lightgraph::render::{Renderer, SceneGpu};
    log::set_logger(&Captured).unwrap();
    log::set_max_level(log::LevelFilter::Warn);
    let tmp = tempfile::tempdir().unwrap();
    let t = tmp.path();
    std::fs::create_dir_all(t.join("models")).unwrap();
    std::fs::copy(
        root().join("tests/bad/hostile/models/tri.gltf"),
        t.join("models/tri.gltf"),
    )
    .unwrap();
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::VULKAN;
    let instance = wgpu::Instance::new(desc);
    let adapter = pollster::block_on(instance.request_adapter(&Default::default())).unwrap();
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_limits: wgpu::Limits::default(),
        ..Default::default()
    }))
    .unwrap();
    assert_eq!(device.limits().max_texture_dimension_2d, 8192);
    let mut r = Renderer::from_device(adapter, device, queue);
    let graph_file = root().join("graphs/forward_plus.ron");
    let mut render = |width: u32| {
        let png = t.join(format!("red_{width}.png"));
        image::RgbaImage::from_pixel(width, 4, image::Rgba([200, 40, 40, 255]))
            .save(&png)
            .unwrap();
        let material = t.join(format!("mat_{width}.ron"));
        std::fs::write(
            &material,
            format!("(name: \"red\", textures: {{ \"t\": (file: \"red_{width}.png\", srgb: true) }}, layers: [(lobes: [Lambert(color: Tex(texture: \"t\", scale: (1, 1, 1)))])])"),
        )
        .unwrap();
        let scene_file = t.join(format!("scene_{width}.ron"));
        std::fs::write(
            &scene_file,
            format!("Scene(models: [(path: \"models/tri.gltf\")], material_overrides: {{ \"tri_mat\": \"mat_{width}.ron\" }}, lights: [(position: (0.3, 0.3, 2), range: 20, color: (1, 1, 1), intensity: 5)], camera: LookAt(eye: (0.3, 0.3, 3), target: (0.3, 0.3, 0), fov_y_deg: 50, near: 0.1, far: 100))"),
        )
        .unwrap();
        let scene = lightgraph::scene::load(&scene_file).unwrap().scene;
        let size = FrameSize {
            width: 64,
            height: 36,
            lights: scene.lights.len() as u32,
        };
        let checked = graph::check_file(&graph_file, &r.shaders).unwrap();
        let compiled = graph::compile(checked, &scene.features(), size);
        let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, &scene).unwrap();
        let frame = r.prepare(compiled, &scene, &gpu, size, false).unwrap();
        frame.render(&r).unwrap().image
    };
    let narrow = render(64);
    assert!(WARNINGS.lock().unwrap().is_empty(), "{:?}", WARNINGS.lock());
    let wide = render(9000);
    let warnings = WARNINGS.lock().unwrap().join("\n");
    assert!(
        warnings.contains("mat_9000.ron")
            && warnings.contains("red_9000.png")
            && warnings.contains("9000×4, over the device's limit of 8192 per side"),
        "want a warning naming mat_9000.ron and red_9000.png, got: {warnings:?}"
    );
    // One colour at any size: the triangle's pixels are the same but for the scaled
    // texture's filtering and mip levels, which average the same texels (1/255 of a
    // channel, a linear value up to 1 here, so 0.01).
    assert_eq!(wide.len(), narrow.len());
    let lit = narrow.iter().filter(|p| p[0] > 0.01).count();
    // About 80 of 2,304 pixels at 64×36.
    assert!(lit > 40, "the triangle covers {lit} pixels");
    for (i, (a, b)) in wide.iter().zip(&narrow).enumerate() {
        let d = (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f32::max);
        assert!(d <= 0.01, "pixel {i}: {a:?} with 9000×4, {b:?} with 64×4");
    }
}
