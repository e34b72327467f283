//! What each declared resource is to a pass: built-in kinds fill their slot tables
//! (`kinds/`), generic kinds bind by shader binding name. No GPU here.

use super::error::GraphError;
use super::location::SourceText;
use super::model::{Name, PassDesc, PassKind, ResourceDesc, SceneResource};
use crate::shader::{BindingKind, ReflectedBinding};
use rustc_hash::FxHashMap;
use std::collections::BTreeMap;

/// Binding names every generic shader may use without declaring them.
pub const BUILTIN_BINDINGS: [&str; 3] = ["frame", "linear_sampler", "nearest_sampler"];

/// How a pass uses its resources, resolved and checked.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PassRoles {
    /// Built-in kinds: slot name (from the kind's table) -> resource name.
    pub slots: BTreeMap<&'static str, Name>,
    /// Generic kinds: reflected binding -> resource name (or a built-in binding name).
    pub bindings: Vec<(ReflectedBinding, Name)>,
    /// Fullscreen: the colour target it renders into.
    pub target: Option<Name>,
}

impl PassRoles {
    /// The resource filling `slot` of a built-in kind, if the pass filled it.
    pub fn slot(&self, slot: &str) -> Option<&str> {
        self.slots.get(slot).map(Name::as_str)
    }
    /// The slot `resource` fills, if any.
    pub(crate) fn slot_of(&self, resource: &str) -> Option<&'static str> {
        self.slots
            .iter()
            .find(|(_, r)| *r == resource)
            .map(|(s, _)| *s)
    }
}

pub(crate) struct RoleCtx<'a> {
    pub source: &'a SourceText,
    pub resources: &'a FxHashMap<&'a str, &'a ResourceDesc>,
}

impl RoleCtx<'_> {
    pub(crate) fn mismatch(
        &self,
        pass: &PassDesc,
        resource: &str,
        problem: impl Into<String>,
    ) -> GraphError {
        GraphError::Mismatch {
            at: self.source.in_pass(&pass.name, resource),
            pass: pass.name.to_string(),
            resource: resource.to_string(),
            problem: problem.into(),
        }
    }
    pub(crate) fn bad(&self, pass: &PassDesc, problem: impl Into<String>) -> GraphError {
        GraphError::BadPass {
            at: self.source.of_declaration(&pass.name),
            pass: pass.name.to_string(),
            problem: problem.into(),
        }
    }

    fn color_texture(&self, name: &str) -> Option<u32> {
        match self.resources.get(name) {
            Some(ResourceDesc::Texture {
                format, samples, ..
            }) if !format.is_depth() => Some(*samples),
            _ => None,
        }
    }

    /// Resolves the slots of a built-in pass (see [`super::kinds::resolve`]).
    pub fn builtin(&self, pass: &PassDesc) -> Result<PassRoles, Vec<GraphError>> {
        let specs = super::kinds::slots(&pass.kind).expect("a built-in kind");
        super::kinds::resolve(self, pass, specs)
    }

    /// Matches a generic pass's reflected shader bindings against its declaration.
    pub fn generic(
        &self,
        pass: &PassDesc,
        shader: &str,
        bindings: &[ReflectedBinding],
    ) -> Result<PassRoles, Vec<GraphError>> {
        let mut roles = PassRoles::default();
        let mut errors = Vec::new();
        if matches!(pass.kind, PassKind::Fullscreen { .. }) {
            let targets: Vec<&Name> = pass
                .writes
                .iter()
                .filter(|w| {
                    self.color_texture(w).is_some()
                        && !bindings.iter().any(|b| b.name == w.as_str())
                })
                .collect();
            match targets.as_slice() {
                // A multisampled target takes the shader's colour in every sample it
                // covers (once per pixel, unless the shader reads its sample index).
                [one] => roles.target = Some((*one).clone()),
                [] => errors.push(self.bad(pass, "a Fullscreen pass needs one colour texture in writes that is not a shader binding (its render target)")),
                many => errors.push(self.bad(pass, format!("a Fullscreen pass has one render target, found {}", many.len()))),
            }
        }
        for b in bindings {
            if b.group != 0 {
                errors.push(self.bad(
                    pass,
                    format!(
                        "shader {shader} binding '{}' is in group {}; generic passes use group 0",
                        b.name, b.group
                    ),
                ));
                continue;
            }
            let declared_read = pass.reads.iter().any(|r| r == &b.name);
            let declared_write = pass.writes.iter().any(|w| w == &b.name);
            if !declared_read && !declared_write {
                if BUILTIN_BINDINGS.contains(&b.name.as_str()) {
                    roles
                        .bindings
                        .push((b.clone(), Name::from(b.name.as_str())));
                } else {
                    errors.push(GraphError::UndeclaredBinding {
                        at: self.source.in_pass(&pass.name, shader),
                        pass: pass.name.to_string(),
                        shader: shader.to_string(),
                        binding: b.name.clone(),
                    });
                }
                continue;
            }
            if let Some(problem) = self.binding_problem(b, declared_write) {
                errors.push(self.mismatch(pass, &b.name, problem));
            }
            roles
                .bindings
                .push((b.clone(), Name::from(b.name.as_str())));
        }
        for name in pass.reads.iter().chain(&pass.writes) {
            let bound = bindings.iter().any(|b| b.name == name.as_str());
            if !bound && roles.target.as_deref() != Some(name.as_str()) {
                errors.push(GraphError::UnboundResource {
                    at: self.source.in_pass(&pass.name, name),
                    pass: pass.name.to_string(),
                    shader: shader.to_string(),
                    resource: name.to_string(),
                });
            }
        }
        if errors.is_empty() {
            Ok(roles)
        } else {
            Err(errors)
        }
    }

    /// Whether a shader binding can bind the declared resource of the same name.
    fn binding_problem(&self, b: &ReflectedBinding, written: bool) -> Option<String> {
        let res = self.resources.get(b.name.as_str())?;
        match (&b.kind, res) {
            (BindingKind::Storage { writable }, ResourceDesc::Buffer { .. }) => match (
                writable, written,
            ) {
                (false, true) => {
                    Some("the pass writes it but the shader binds it var<storage, read>".into())
                }
                (true, false) => Some(
                    "the shader binds it read_write but the pass only reads it; add it to writes"
                        .into(),
                ),
                _ => None,
            },
            (BindingKind::Storage { writable }, ResourceDesc::Import { from, .. }) => {
                if *writable {
                    Some("scene imports are read-only; the shader binds it read_write".into())
                } else if *from == SceneResource::Geometry {
                    Some("scene geometry cannot be bound to a generic pass".into())
                } else {
                    None
                }
            }
            (BindingKind::Uniform, ResourceDesc::Buffer { .. }) => None,
            (
                BindingKind::SampledTexture { multisampled, .. },
                ResourceDesc::Texture {
                    format, samples, ..
                },
            ) => {
                if format.is_depth() {
                    Some("samples a depth format as float; bind it as texture_depth_2d".into())
                } else if *multisampled != (*samples > 1) {
                    Some(format!("shader multisampled = {multisampled} but the texture has {samples} sample(s)"))
                } else if written {
                    Some("a sampled texture is read-only; the pass lists it in writes".into())
                } else {
                    None
                }
            }
            (
                BindingKind::DepthTexture { multisampled },
                ResourceDesc::Texture {
                    format, samples, ..
                },
            ) => {
                if !format.is_depth() {
                    Some(format!(
                        "texture_depth_2d needs a depth format, '{}' is {format:?}",
                        b.name
                    ))
                } else if *multisampled != (*samples > 1) {
                    Some(format!("shader multisampled = {multisampled} but the texture has {samples} sample(s)"))
                } else if written {
                    Some("a depth texture cannot be written by a shader binding".into())
                } else {
                    None
                }
            }
            (
                BindingKind::StorageTexture {
                    format, writable, ..
                },
                ResourceDesc::Texture {
                    format: declared,
                    samples,
                    ..
                },
            ) => {
                let expected = storage_format(declared.to_wgpu());
                if declared.is_depth() {
                    Some("a depth format cannot be a storage texture".into())
                } else if *samples > 1 {
                    Some("a multisampled texture cannot be a storage texture".into())
                } else if expected != Some(*format) {
                    Some(format!(
                        "shader storage format {format:?} differs from the declared {declared:?}"
                    ))
                } else if *writable && !written {
                    Some("the shader writes this storage texture but the pass only reads it; add it to writes".into())
                } else if !*writable && written {
                    Some("the pass writes it but the shader binds it read-only".into())
                } else {
                    None
                }
            }
            (kind, res) => Some(format!(
                "shader binding {kind:?} cannot bind a {}",
                match res {
                    ResourceDesc::Texture { .. } => "texture",
                    ResourceDesc::Buffer { .. } => "buffer",
                    ResourceDesc::Import { .. } => "scene import",
                }
            )),
        }
    }
}

fn storage_format(f: wgpu::TextureFormat) -> Option<naga::StorageFormat> {
    use naga::StorageFormat as S;
    use wgpu::TextureFormat as W;
    Some(match f {
        W::Rgba8Unorm => S::Rgba8Unorm,
        W::Rgba16Float => S::Rgba16Float,
        W::Rgba32Float => S::Rgba32Float,
        W::R32Float => S::R32Float,
        W::Rg32Float => S::Rg32Float,
        W::R32Uint => S::R32Uint,
        _ => return None,
    })
}
