//! Structure-aware: the parameters of the pass kinds added since the graph target was
//! written (visibility buffer and shading, compute raster, shadow atlas, reflective shadow
//! maps and VPL spawn, light linked lists, ray-cast shadows), resource sizes, `when:`
//! conditions, the scene's features and the frame size, drawn by `arbitrary` and written
//! into a graph as the RON text a user writes; then every step before the GPU: parse,
//! validate, compile (specialise, order, plan), the memory report, the coverage warnings
//! and the Graphviz output.
//!
//! The input is a graph's text, then optionally a NUL byte and the bytes `arbitrary` draws
//! from. A graph file as it is (no NUL) runs unchanged at a 64×36 frame: the seeds are the
//! shipped graphs and tests/bad/graphs.
#![no_main]
use libfuzzer_sys::arbitrary::{self, Arbitrary, Unstructured};
use libfuzzer_sys::fuzz_target;
use lightgraph::graph::{self, FrameSize, GraphDesc, PassKind};
use lightgraph::scene::SceneFeatures;

/// A number written over one in the text: how it reads depends on whether the number it
/// replaces is an integer or a float.
#[derive(Arbitrary, Debug)]
enum Number {
    Small(u8),
    Int(u32),
    Wide(u64),
    Float(f32),
    Special(u8),
}

impl Number {
    fn as_int(&self) -> String {
        const SPECIAL: [u64; 12] = [
            0,
            1,
            3,
            65_535,
            65_536,
            16_384,
            16_385,
            1 << 31,
            u32::MAX as u64,
            1 << 32,
            1 << 40,
            u64::MAX,
        ];
        match *self {
            Number::Small(n) => n.to_string(),
            Number::Int(n) => n.to_string(),
            Number::Wide(n) => n.to_string(),
            Number::Float(f) => (f.abs() as u64).to_string(),
            Number::Special(i) => SPECIAL[i as usize % SPECIAL.len()].to_string(),
        }
    }

    fn as_float(&self) -> String {
        const SPECIAL: [f32; 11] = [
            0.0,
            -0.0,
            1e-45,
            f32::MIN_POSITIVE,
            1e-7,
            0.5,
            -1.0,
            1e7,
            f32::MAX,
            f32::INFINITY,
            f32::NAN,
        ];
        let f = match *self {
            Number::Small(n) => n as f32 / 16.0,
            Number::Int(n) => n as f32,
            Number::Wide(n) => n as f32,
            Number::Float(f) => f,
            Number::Special(i) => SPECIAL[i as usize % SPECIAL.len()],
        };
        // ron's own spelling, so NaN and the infinities read back.
        ron::to_string(&f).unwrap_or_else(|_| "0.0".into())
    }
}

/// The kinds a pass can be turned into, each with its defaults.
const KINDS: &[&str] = &[
    "VisibilityBuffer",
    "ComputeRaster",
    "VisibilityShading()",
    "VisibilityShading(lights: Culled)",
    "ShadowAtlas()",
    "LightLinkedList(scale: 1)",
    "LightLinkedList(scale: 4)",
    "ReflectiveShadowMaps()",
    "VplSpawn()",
    "ShadowRayJobs()",
    "ShadowRayCast()",
    "ShadowCompare",
    "DepthPrepass",
    "GBuffer",
    "LightCulling()",
    "ForwardShading(lights: Culled)",
    "DeferredShading(lights: Culled)",
    "TransparentDepth",
    "TransparentShading()",
];

const FEATURES: &[&str] = &[
    "Transparent",
    "AlphaMask",
    "ShadowCasters",
    "IndirectLights",
    "SpotLights",
    "Lights",
    "Msaa",
];

#[derive(Arbitrary, Debug)]
enum Edit {
    /// The numbers of a pass's kind, in order of writing, replaced.
    PassNumbers { pass: u8, values: Vec<Number> },
    /// The `n`th `None` of a pass's kind made `Some(value)`.
    PassSome { pass: u8, n: u8, value: Number },
    /// A pass's kind replaced by one of [`KINDS`].
    Kind { pass: u8, kind: u8 },
    /// The numbers of a resource (its size, sample count) replaced.
    ResourceNumbers { resource: u8, values: Vec<Number> },
    /// A pass's `when:` condition set or removed.
    When { pass: u8, feature: Option<u8> },
    /// A resource read by a pass, by name or into a named slot of another entry's.
    Read {
        pass: u8,
        resource: u8,
        slot_of: Option<u8>,
    },
    /// A read or written resource replaced by another.
    Swap {
        pass: u8,
        write: bool,
        entry: u8,
        resource: u8,
    },
}

#[derive(Arbitrary, Debug)]
struct Scenario {
    edits: Vec<Edit>,
    features: [bool; 10],
    width: u16,
    height: u16,
    lights: u32,
}

fn options() -> ron::Options {
    // What graph files use: kinds wrap their parameters without a second pair of brackets.
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES)
}

/// `text` with its numbers outside strings replaced by `values`, in order.
fn replace_numbers(text: &str, values: &[Number]) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let (mut i, mut k) = (0, 0);
    while i < b.len() {
        let c = b[i];
        if c == b'"' {
            let start = i;
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i = (i + 1).min(b.len());
            out.push_str(&text[start..i]);
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let start = i;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            let word = &text[start..i];
            match (word, values.get(k)) {
                ("NaN" | "inf", Some(v)) => {
                    out.push_str(&v.as_float());
                    k += 1;
                }
                _ => out.push_str(word),
            }
        } else if c.is_ascii_digit()
            || (c == b'-' && b.get(i + 1).is_some_and(|d| d.is_ascii_digit()))
        {
            let start = i;
            i += 1;
            while i < b.len()
                && (b[i].is_ascii_alphanumeric()
                    || b[i] == b'.'
                    || ((b[i] == b'-' || b[i] == b'+') && matches!(b[i - 1], b'e' | b'E')))
            {
                i += 1;
            }
            let literal = &text[start..i];
            match values.get(k) {
                Some(v) => {
                    let float = literal.contains(['.', 'e', 'E']);
                    out.push_str(&if float { v.as_float() } else { v.as_int() });
                    k += 1;
                }
                None => out.push_str(literal),
            }
        } else {
            let ch = text[i..].chars().next().unwrap();
            out.push(ch);
            i += ch.len_utf8();
        }
    }
    out
}

fn pick<T>(list: &mut [T], i: u8) -> Option<&mut T> {
    let n = list.len();
    (n > 0).then(|| &mut list[i as usize % n])
}

fn apply(desc: &mut GraphDesc, edit: &Edit) {
    let ser = |v: &dyn erased::Ser| v.to_ron();
    let names: Vec<String> = desc
        .resources
        .iter()
        .map(|r| r.name().to_string())
        .collect();
    let name = |i: u8| (!names.is_empty()).then(|| names[i as usize % names.len()].clone());
    match edit {
        Edit::PassNumbers { pass, values } => {
            if let Some(p) = pick(&mut desc.passes, *pass) {
                let text = replace_numbers(&ser(&p.kind), values);
                if let Ok(kind) = options().from_str::<PassKind>(&text) {
                    p.kind = kind;
                }
            }
        }
        Edit::PassSome { pass, n, value } => {
            if let Some(p) = pick(&mut desc.passes, *pass) {
                let text = ser(&p.kind);
                if let Some((at, _)) = text.match_indices("None").nth(*n as usize) {
                    let value = value.as_int();
                    let text = format!("{}Some({value}){}", &text[..at], &text[at + 4..]);
                    if let Ok(kind) = options().from_str::<PassKind>(&text) {
                        p.kind = kind;
                    }
                }
            }
        }
        Edit::Kind { pass, kind } => {
            if let Some(p) = pick(&mut desc.passes, *pass) {
                let text = KINDS[*kind as usize % KINDS.len()];
                if let Ok(kind) = options().from_str::<PassKind>(text) {
                    p.kind = kind;
                }
            }
        }
        Edit::ResourceNumbers { resource, values } => {
            if let Some(r) = pick(&mut desc.resources, *resource) {
                let text = replace_numbers(&ser(r), values);
                if let Ok(new) = options().from_str(&text) {
                    *r = new;
                }
            }
        }
        Edit::When { pass, feature } => {
            if let Some(p) = pick(&mut desc.passes, *pass) {
                p.when = feature.and_then(|f| {
                    let text = FEATURES[f as usize % FEATURES.len()];
                    options().from_str(text).ok()
                });
            }
        }
        Edit::Read {
            pass,
            resource,
            slot_of,
        } => {
            let Some(r) = name(*resource) else { return };
            if let Some(p) = pick(&mut desc.passes, *pass) {
                let entry = match slot_of.and_then(|s| {
                    let slots = graph::kinds::slots(&p.kind)?;
                    (!slots.is_empty()).then(|| slots[s as usize % slots.len()].name)
                }) {
                    Some(slot) => format!("{slot}={r}"),
                    None => r,
                };
                p.reads.push(entry.as_str().into());
            }
        }
        Edit::Swap {
            pass,
            write,
            entry,
            resource,
        } => {
            let Some(r) = name(*resource) else { return };
            if let Some(p) = pick(&mut desc.passes, *pass) {
                let list = if *write { &mut p.writes } else { &mut p.reads };
                if let Some(e) = pick(list, *entry) {
                    // Keep a `slot=` prefix: the same slot, another resource.
                    let slot = e.split_once('=').map(|(s, _)| s.to_string());
                    let new = match slot {
                        Some(s) => format!("{s}={r}"),
                        None => r,
                    };
                    *e = new.as_str().into();
                }
            }
        }
    }
}

mod erased {
    /// Serialises any of the graph's parts as graph-file RON.
    pub trait Ser {
        fn to_ron(&self) -> String;
    }
    impl<T: serde::Serialize> Ser for T {
        fn to_ron(&self) -> String {
            super::options()
                .to_string_pretty(self, ron::ser::PrettyConfig::new().struct_names(true))
                .unwrap_or_default()
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let (text, tail) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], Some(&data[i + 1..])),
        None => (data, None),
    };
    let mut text = String::from_utf8_lossy(text).into_owned();
    let mut u = Unstructured::new(tail.unwrap_or(&[]));
    let scenario = if tail.is_some() {
        Scenario::arbitrary(&mut u).ok()
    } else {
        None
    };
    if let Some(s) = &scenario {
        // Parsed as serde reads it (named slots still `slot=resource`), edited, written back.
        if let Ok(mut desc) = options().from_str::<GraphDesc>(&text) {
            for e in &s.edits {
                apply(&mut desc, e);
            }
            use erased::Ser;
            text = desc.to_ron();
        }
    }
    if std::env::var_os("LIGHTGRAPH_FUZZ_SHOW").is_some() {
        // To see what an input becomes: the graph text the steps below read.
        eprintln!("{text}");
    }
    let shaders = lightgraph::shader::ShaderLibrary::builtin();
    let checked = graph::check_text(std::path::Path::new("fuzz.ron"), &text, &shaders);
    if std::env::var_os("LIGHTGRAPH_FUZZ_SHOW").is_some() {
        eprintln!("{:?}", checked.as_ref().err().map(|e| e.to_string()));
    }
    let Ok(checked) = checked else {
        return;
    };
    let (features, frame) = match &scenario {
        Some(s) => {
            let f = s.features;
            (
                SceneFeatures {
                    has_transparent: f[0],
                    has_alpha_mask: f[1],
                    has_shadow_casters: f[2],
                    has_indirect_lights: f[3],
                    has_spot_lights: f[4],
                    has_lights: f[5],
                    has_point_lights: f[6],
                    has_double_sided: f[7],
                    has_emissive: f[8],
                    has_material_masks: f[9],
                },
                // What the CLI and scene files allow: sides up to 16384, a scene's lights
                // up to 2^20 plus the VPLs' room.
                FrameSize {
                    width: (s.width as u32 % 16384) + 1,
                    height: (s.height as u32 % 16384) + 1,
                    lights: s.lights % ((1 << 20) + (1 << 16) + 1),
                },
            )
        }
        None => (
            SceneFeatures {
                has_lights: true,
                has_point_lights: true,
                has_shadow_casters: true,
                ..Default::default()
            },
            FrameSize {
                width: 64,
                height: 36,
                lights: 16,
            },
        ),
    };
    let compiled = graph::compile(checked, &features, frame);
    let _ = graph::memory::by_technique(&compiled);
    let _ = graph::memory::total_bytes(&compiled);
    let _ = graph::coverage::undrawn(&compiled, &features);
    let _ = compiled.to_dot();
});
