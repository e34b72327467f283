//! docs/format.md documents every file format field: every struct and enum under src/
//! that derives `Deserialize` has each of its serde names (named fields, struct-variant
//! fields and enum variants, after `rename`, `rename_all` and `skip`) written in the page as
//! inline code (`` `name` ``), unless the type is in [`EXCLUDED`] (not a file a user
//! writes).
//!
//! The sources are read with `syn`, not through the crate, so a type is found wherever it
//! lives (a pass kind's parameters may move between modules).

use std::collections::BTreeSet;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use syn::ext::IdentExt;
use syn::punctuated::Punctuated;
use syn::{Attribute, Expr, ExprLit, Fields, Item, Lit, Meta, Token};

/// Types deriving `Deserialize` that are not part of a file format users write, each with
/// the reason. Matched by type name.
const EXCLUDED: &[(&str, &str)] = &[
    (
        "BenchRow",
        "a benchmark result row the tools write and read back, not an input",
    ),
    (
        "TimingSummary",
        "median/p10/p90 inside a BenchRow result, not an input",
    ),
    (
        "ImageMetrics",
        "image comparison results inside a BenchRow, not an input",
    ),
    (
        "NonFinite",
        "NaN/Inf pixel counts inside ImageMetrics, not an input",
    ),
    (
        "NonFinitePixel",
        "a NaN/Inf pixel listed in a BenchRow, not an input",
    ),
    (
        "CompareOptions",
        "image comparison settings built in code and by CLI flags, no file",
    ),
    (
        "Tonemap",
        "tonemapper settings built in code (CompareOptions, PNG output), no file",
    ),
    (
        "ToneCurve",
        "the curve inside Tonemap, built in code, no file",
    ),
    ("HeatScale", "heat-map scaling chosen by CLI flags, no file"),
    (
        "Light",
        "the runtime light of a loaded scene; scene files write LightSpec and light sets",
    ),
    (
        "LightShape",
        "the runtime shape of a Light; scene files write LightSpec.spot",
    ),
    (
        "Camera",
        "the runtime camera of a loaded scene; scene files write CameraSpec",
    ),
];

const DOC: &str = "docs/format.md";

/// Where a serde name comes from.
#[derive(Debug)]
struct SerdeName {
    /// `Type.field`, `Type.Variant` or `Type.Variant.field` (Rust names).
    path: String,
    /// The name as it is written in a file.
    name: String,
    /// An enum variant (else a field).
    variant: bool,
    file: PathBuf,
}

/// One type deriving `Deserialize`.
#[derive(Debug)]
struct SerdeType {
    ident: String,
    file: PathBuf,
    names: Vec<SerdeName>,
}

/// The `#[serde(...)]` settings this test needs from one attribute list.
#[derive(Default)]
struct SerdeAttrs {
    rename: Option<String>,
    rename_all: Option<String>,
    rename_all_fields: Option<String>,
    skip: bool,
    untagged: bool,
    transparent: bool,
    flatten: bool,
    /// `from` / `try_from`: the type is read as another type.
    converted: bool,
}

fn lit_str(e: &Expr) -> Option<String> {
    match e {
        Expr::Lit(ExprLit {
            lit: Lit::Str(s), ..
        }) => Some(s.value()),
        _ => None,
    }
}

/// The deserialize side of `rename = "x"` or `rename(deserialize = "x", ...)`.
fn deserialize_value(meta: &Meta) -> Option<String> {
    match meta {
        Meta::NameValue(nv) => lit_str(&nv.value),
        Meta::List(list) => list
            .parse_args_with(Punctuated::<Meta, Token![,]>::parse_terminated)
            .ok()?
            .iter()
            .find(|m| m.path().is_ident("deserialize"))
            .and_then(deserialize_value),
        Meta::Path(_) => None,
    }
}

fn serde_attrs(attrs: &[Attribute], file: &Path) -> SerdeAttrs {
    let mut out = SerdeAttrs::default();
    for attr in attrs.iter().filter(|a| a.path().is_ident("serde")) {
        let metas = attr
            .parse_args_with(Punctuated::<Meta, Token![,]>::parse_terminated)
            .unwrap_or_else(|e| panic!("{}: cannot read #[serde(...)]: {e}", file.display()));
        for meta in &metas {
            let key = meta
                .path()
                .get_ident()
                .map(|i| i.to_string())
                .unwrap_or_default();
            match key.as_str() {
                "rename" => out.rename = deserialize_value(meta),
                "rename_all" => out.rename_all = deserialize_value(meta),
                "rename_all_fields" => out.rename_all_fields = deserialize_value(meta),
                "skip" | "skip_deserializing" => out.skip = true,
                "untagged" => out.untagged = true,
                "transparent" => out.transparent = true,
                "flatten" => out.flatten = true,
                "from" | "try_from" => out.converted = true,
                _ => {}
            }
        }
    }
    out
}

fn derives_deserialize(attrs: &[Attribute]) -> bool {
    attrs
        .iter()
        .filter(|a| a.path().is_ident("derive"))
        .filter_map(|a| {
            a.parse_args_with(Punctuated::<syn::Path, Token![,]>::parse_terminated)
                .ok()
        })
        .flatten()
        .any(|p| p.segments.last().is_some_and(|s| s.ident == "Deserialize"))
}

/// `#[cfg(test)]` items are not part of the library.
fn is_test_only(attrs: &[Attribute]) -> bool {
    attrs.iter().any(|a| {
        a.path().is_ident("cfg")
            && a.parse_args::<syn::Path>()
                .is_ok_and(|p| p.is_ident("test"))
    })
}

fn snake_to_words(s: &str) -> Vec<String> {
    s.split('_')
        .filter(|w| !w.is_empty())
        .map(str::to_string)
        .collect()
}

/// serde's `RenameRule::apply_to_field` (fields are snake_case in Rust).
fn rename_field(field: &str, rule: Option<&str>) -> String {
    let pascal = || {
        snake_to_words(field)
            .iter()
            .map(|w| {
                let mut c = w.chars();
                c.next()
                    .map(|f| f.to_ascii_uppercase().to_string() + c.as_str())
                    .unwrap_or_default()
            })
            .collect::<String>()
    };
    match rule {
        None | Some("lowercase") | Some("snake_case") => field.to_string(),
        Some("UPPERCASE") | Some("SCREAMING_SNAKE_CASE") => field.to_ascii_uppercase(),
        Some("PascalCase") => pascal(),
        Some("camelCase") => {
            let p = pascal();
            let mut c = p.chars();
            c.next()
                .map(|f| f.to_ascii_lowercase().to_string() + c.as_str())
                .unwrap_or_default()
        }
        Some("kebab-case") => field.replace('_', "-"),
        Some("SCREAMING-KEBAB-CASE") => field.to_ascii_uppercase().replace('_', "-"),
        Some(other) => panic!("unknown rename_all rule {other:?}"),
    }
}

/// serde's `RenameRule::apply_to_variant` (variants are PascalCase in Rust).
fn rename_variant(variant: &str, rule: Option<&str>) -> String {
    let snake = || {
        let mut s = String::new();
        for (i, ch) in variant.char_indices() {
            if i > 0 && ch.is_uppercase() {
                s.push('_');
            }
            s.push(ch.to_ascii_lowercase());
        }
        s
    };
    match rule {
        None | Some("PascalCase") => variant.to_string(),
        Some("lowercase") => variant.to_ascii_lowercase(),
        Some("UPPERCASE") => variant.to_ascii_uppercase(),
        Some("camelCase") => {
            let mut c = variant.chars();
            c.next()
                .map(|f| f.to_ascii_lowercase().to_string() + c.as_str())
                .unwrap_or_default()
        }
        Some("snake_case") => snake(),
        Some("SCREAMING_SNAKE_CASE") => snake().to_ascii_uppercase(),
        Some("kebab-case") => snake().replace('_', "-"),
        Some("SCREAMING-KEBAB-CASE") => snake().to_ascii_uppercase().replace('_', "-"),
        Some(other) => panic!("unknown rename_all rule {other:?}"),
    }
}

/// The serde names of a struct's or struct variant's named fields.
fn field_names(fields: &Fields, rule: Option<&str>, prefix: &str, file: &Path) -> Vec<SerdeName> {
    let Fields::Named(named) = fields else {
        return Vec::new();
    };
    named
        .named
        .iter()
        .filter_map(|f| {
            let a = serde_attrs(&f.attrs, file);
            if a.skip || a.flatten {
                return None;
            }
            let ident = f.ident.as_ref()?.unraw().to_string();
            let name = a.rename.unwrap_or_else(|| rename_field(&ident, rule));
            Some(SerdeName {
                path: format!("{prefix}.{ident}"),
                name,
                variant: false,
                file: file.to_path_buf(),
            })
        })
        .collect()
}

fn collect_items(items: &[Item], file: &Path, out: &mut Vec<SerdeType>) {
    for item in items {
        match item {
            Item::Struct(s) if derives_deserialize(&s.attrs) && !is_test_only(&s.attrs) => {
                let a = serde_attrs(&s.attrs, file);
                let ident = s.ident.to_string();
                let names = if a.transparent || a.converted {
                    Vec::new()
                } else {
                    field_names(&s.fields, a.rename_all.as_deref(), &ident, file)
                };
                out.push(SerdeType {
                    ident,
                    file: file.to_path_buf(),
                    names,
                });
            }
            Item::Enum(e) if derives_deserialize(&e.attrs) && !is_test_only(&e.attrs) => {
                let a = serde_attrs(&e.attrs, file);
                let ident = e.ident.to_string();
                let mut names = Vec::new();
                if !a.converted {
                    for v in &e.variants {
                        let va = serde_attrs(&v.attrs, file);
                        if va.skip {
                            continue;
                        }
                        let vident = v.ident.to_string();
                        let prefix = format!("{ident}.{vident}");
                        // An untagged enum's variant names never appear in a file.
                        if !a.untagged {
                            names.push(SerdeName {
                                path: prefix.clone(),
                                name: va.rename.clone().unwrap_or_else(|| {
                                    rename_variant(&vident, a.rename_all.as_deref())
                                }),
                                variant: true,
                                file: file.to_path_buf(),
                            });
                        }
                        let rule = va.rename_all.as_deref().or(a.rename_all_fields.as_deref());
                        names.extend(field_names(&v.fields, rule, &prefix, file));
                    }
                }
                out.push(SerdeType {
                    ident,
                    file: file.to_path_buf(),
                    names,
                });
            }
            Item::Mod(m) if !is_test_only(&m.attrs) => {
                if let Some((_, inner)) = &m.content {
                    collect_items(inner, file, out);
                }
            }
            _ => {}
        }
    }
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|x| x == "rs") {
            out.push(path);
        }
    }
}

/// Every type under src/ that derives `Deserialize`, with its serde names.
fn serde_types() -> Vec<SerdeType> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    files.sort();
    let mut types = Vec::new();
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        let rel = path.strip_prefix(root).unwrap_or(&path).to_path_buf();
        let ast = syn::parse_file(&text)
            .unwrap_or_else(|e| panic!("{}: not parsable by syn: {e}", rel.display()));
        collect_items(&ast.items, &rel, &mut types);
        if text.contains("macro_rules! built_in_kinds") {
            registry_pass_kind(&text, &rel, &mut types);
        }
    }
    types
}

/// `PassKind` is generated by the kind registry's macros (src/graph/kinds/mod.rs), which
/// syn does not expand: its generic variants come from the enum template in the macro (the
/// `$( .. )*` repetition dropped), its built-in ones from the registry lines
/// (`Name => module,` or `Name(params: Type) => module,`).
fn registry_pass_kind(text: &str, file: &Path, out: &mut Vec<SerdeType>) {
    let start = text
        .find("pub enum PassKind {")
        .expect("the registry's PassKind template");
    let derive = text[..start].rfind("#[derive(").expect("PassKind's derive");
    let mut depth = 0;
    let mut end = start;
    for (i, c) in text[start..].char_indices() {
        match c {
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if depth == 0 {
                    end = start + i + 1;
                    break;
                }
            }
            _ => {}
        }
    }
    let template: String = text[derive..end]
        .lines()
        .filter(|l| !l.contains("$("))
        .collect::<Vec<_>>()
        .join("\n");
    let item: Item = syn::parse_str(&template)
        .unwrap_or_else(|e| panic!("{}: PassKind's template: {e}", file.display()));
    collect_items(std::slice::from_ref(&item), file, out);
    let kind = out.last_mut().expect("PassKind collected");
    for line in text.lines().map(str::trim) {
        let Some((head, module)) = line.split_once(" => ") else {
            continue;
        };
        let name = head.split('(').next().unwrap_or("").trim();
        let is_row = module
            .trim_end_matches(',')
            .chars()
            .all(|c| c.is_ascii_lowercase() || c == '_')
            && !name.is_empty()
            && name.chars().all(|c| c.is_ascii_alphanumeric())
            && name.starts_with(|c: char| c.is_ascii_uppercase());
        if is_row {
            kind.names.push(SerdeName {
                path: format!("PassKind.{name}"),
                name: name.to_string(),
                variant: true,
                file: file.to_path_buf(),
            });
        }
    }
}

/// The inline-code spans of the page (`` `x` `` gives `x`).
fn inline_code(doc: &str) -> BTreeSet<String> {
    let mut spans = BTreeSet::new();
    let mut in_fence = false;
    for line in doc.lines() {
        if line.trim_start().starts_with("```") {
            in_fence = !in_fence;
            continue;
        }
        if in_fence {
            continue;
        }
        let mut parts = line.split('`');
        parts.next();
        while let (Some(code), Some(_)) = (parts.next(), parts.next()) {
            spans.insert(code.trim().to_string());
        }
    }
    spans
}

fn excluded(ident: &str) -> bool {
    EXCLUDED.iter().any(|(t, _)| *t == ident)
}

#[test]
fn every_serde_field_is_documented() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(root.join(DOC))
        .unwrap_or_else(|e| panic!("{DOC}: {e} (the format reference must exist)"));
    let code = inline_code(&doc);
    let types = serde_types();
    // The walk must see the formats at all, or the check would pass on nothing.
    for needle in [
        "GraphDesc",
        "PassKind",
        "SceneFile",
        "MaterialDesc",
        "Sweep",
    ] {
        assert!(
            types.iter().any(|t| t.ident == needle),
            "no Deserialize type {needle} found under src/: is the walk broken?"
        );
    }
    let mut missing = String::new();
    let (mut checked_types, mut fields, mut variants) = (0, 0, 0);
    for t in types.iter().filter(|t| !excluded(&t.ident)) {
        checked_types += 1;
        for n in &t.names {
            if n.variant {
                variants += 1;
            } else {
                fields += 1;
            }
            if !code.contains(&n.name) {
                writeln!(missing, "  {} (`{}`, {})", n.path, n.name, n.file.display()).unwrap();
            }
        }
    }
    println!(
        "{checked_types} types, {fields} fields and {variants} variants checked against {DOC}; \
         {} types excluded",
        EXCLUDED.len()
    );
    assert!(
        missing.is_empty(),
        "{DOC} does not mention these serde names as inline code (`name`); document them \
         (name, type, default, meaning) or, for a type no user writes, add it to EXCLUDED \
         in tests/docs_format.rs with a reason:\n{missing}"
    );
}

#[test]
fn exclusions_name_deserialize_types() {
    let types = serde_types();
    let stale: Vec<&str> = EXCLUDED
        .iter()
        .map(|(t, _)| *t)
        .filter(|t| !types.iter().any(|s| s.ident == *t))
        .collect();
    assert!(
        stale.is_empty(),
        "EXCLUDED in tests/docs_format.rs names types that no longer derive Deserialize \
         under src/: {stale:?}"
    );
    for (t, reason) in EXCLUDED {
        assert!(
            !reason.trim().is_empty(),
            "EXCLUDED entry {t} needs a reason"
        );
        // Exclusions go by name: a second type of that name would be skipped unseen.
        let files: Vec<String> = types
            .iter()
            .filter(|s| s.ident == *t)
            .map(|s| s.file.display().to_string())
            .collect();
        assert!(
            files.len() <= 1,
            "EXCLUDED names {t}, but {} Deserialize types have that name ({}): \
             rename one or make the exclusion say which",
            files.len(),
            files.join(", ")
        );
    }
}

#[test]
fn serde_names_follow_serde_rules() {
    assert_eq!(rename_field("fov_y_deg", Some("camelCase")), "fovYDeg");
    assert_eq!(rename_field("fov_y_deg", Some("PascalCase")), "FovYDeg");
    assert_eq!(rename_field("max_tile", Some("kebab-case")), "max-tile");
    assert_eq!(
        rename_field("max_tile", Some("SCREAMING_SNAKE_CASE")),
        "MAX_TILE"
    );
    assert_eq!(rename_variant("HalfZ", Some("snake_case")), "half_z");
    assert_eq!(
        rename_variant("DepthMask", Some("kebab-case")),
        "depth-mask"
    );
    assert_eq!(rename_variant("DepthMask", Some("camelCase")), "depthMask");
    assert_eq!(rename_variant("Pcf5x5", Some("lowercase")), "pcf5x5");

    let file: syn::File = syn::parse_quote! {
        #[derive(Deserialize)]
        #[serde(rename_all = "camelCase")]
        struct A {
            plain_name: u32,
            #[serde(rename = "other")]
            renamed: u32,
            #[serde(skip)]
            hidden: u32,
            #[serde(skip_deserializing)]
            hidden_too: u32,
            r#type: u32,
        }
        #[derive(Clone, serde::Deserialize)]
        #[serde(rename_all = "snake_case", rename_all_fields = "kebab-case")]
        enum B {
            FirstOne,
            #[serde(rename = "two")]
            Second { inner_field: u32 },
            #[serde(skip)]
            Gone,
        }
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum C { Val(f32), Named { x_y: f32 } }
        #[derive(Serialize)]
        struct NotRead { field: u32 }
        #[cfg(test)]
        mod tests {
            #[derive(Deserialize)]
            struct TestOnly { field: u32 }
        }
    };
    let mut out = Vec::new();
    collect_items(&file.items, Path::new("x.rs"), &mut out);
    let got: Vec<(String, Vec<String>)> = out
        .iter()
        .map(|t| {
            (
                t.ident.clone(),
                t.names.iter().map(|n| n.name.clone()).collect(),
            )
        })
        .collect();
    let own = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert_eq!(
        got,
        vec![
            ("A".into(), own(&["plainName", "other", "type"])),
            ("B".into(), own(&["first_one", "two", "inner-field"])),
            ("C".into(), own(&["x_y"])),
        ]
    );
}
