//! What each declared resource is to a pass: the built-in kinds find their slots by the
//! resource's type, generic kinds by shader binding name. No GPU here.

use super::error::GraphError;
use super::location::SourceText;
use super::model::{LightSource, PassDesc, PassKind, ResourceDesc, SceneResource};
use crate::shader::{BindingKind, ReflectedBinding};
use std::collections::BTreeMap;

/// A slot of a built-in pass kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Slot {
    Depth,
    Color,
    LightGeometry,
    LightProperties,
    Geometry,
    LightLists,
    /// G-buffer world positions (material index in w).
    GPosition,
    /// G-buffer shading normals.
    GNormal,
}

/// Binding names every generic shader may use without declaring them.
pub const BUILTIN_BINDINGS: [&str; 3] = ["frame", "linear_sampler", "nearest_sampler"];

/// How a pass uses its resources, resolved and checked.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PassRoles {
    /// Built-in kinds: slot -> resource name.
    pub slots: BTreeMap<Slot, String>,
    /// Generic kinds: reflected binding -> resource name (or a built-in binding name).
    pub bindings: Vec<(ReflectedBinding, String)>,
    /// Fullscreen: the colour target it renders into.
    pub target: Option<String>,
}

impl PassRoles {
    pub fn slot(&self, slot: Slot) -> Option<&str> {
        self.slots.get(&slot).map(String::as_str)
    }
}

pub(crate) struct RoleCtx<'a> {
    pub source: &'a SourceText,
    pub resources: &'a BTreeMap<&'a str, &'a ResourceDesc>,
}

impl RoleCtx<'_> {
    fn mismatch(&self, pass: &PassDesc, resource: &str, problem: impl Into<String>) -> GraphError {
        GraphError::Mismatch {
            at: self.source.in_pass(&pass.name, resource),
            pass: pass.name.clone(),
            resource: resource.to_string(),
            problem: problem.into(),
        }
    }
    fn bad(&self, pass: &PassDesc, problem: impl Into<String>) -> GraphError {
        GraphError::BadPass {
            at: self.source.of_declaration(&pass.name),
            pass: pass.name.clone(),
            problem: problem.into(),
        }
    }

    fn import_of(&self, name: &str) -> Option<SceneResource> {
        match self.resources.get(name) {
            Some(ResourceDesc::Import { from, .. }) => Some(*from),
            _ => None,
        }
    }
    fn depth_texture(&self, name: &str) -> Option<u32> {
        match self.resources.get(name) {
            Some(ResourceDesc::Texture {
                format, samples, ..
            }) if format.is_depth() => Some(*samples),
            _ => None,
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
    fn is_rgba32f(&self, name: &str) -> bool {
        matches!(
            self.resources.get(name),
            Some(ResourceDesc::Texture {
                format: super::model::TextureFormat::Rgba32Float,
                ..
            })
        )
    }
    fn is_buffer(&self, name: &str) -> bool {
        matches!(self.resources.get(name), Some(ResourceDesc::Buffer { .. }))
    }

    /// Resolves the slots of a built-in pass; every declared resource must fill a slot.
    pub fn builtin(&self, pass: &PassDesc) -> Result<PassRoles, Vec<GraphError>> {
        let mut roles = PassRoles::default();
        let mut errors = Vec::new();
        let put = |roles: &mut PassRoles, slot: Slot, name: &str, errors: &mut Vec<GraphError>| {
            if let Some(prev) = roles.slots.insert(slot, name.to_string()) {
                errors.push(self.mismatch(
                    pass,
                    name,
                    format!("{:?} slot already filled by '{prev}'", slot),
                ));
            }
        };
        for name in &pass.reads {
            match (self.import_of(name), self.depth_texture(name)) {
                (Some(SceneResource::LightGeometry), _) => {
                    put(&mut roles, Slot::LightGeometry, name, &mut errors)
                }
                (Some(SceneResource::LightProperties), _) => {
                    put(&mut roles, Slot::LightProperties, name, &mut errors)
                }
                (Some(SceneResource::Geometry), _) => {
                    put(&mut roles, Slot::Geometry, name, &mut errors)
                }
                (None, Some(_)) => put(&mut roles, Slot::Depth, name, &mut errors),
                _ if self.is_buffer(name) => put(&mut roles, Slot::LightLists, name, &mut errors),
                _ if matches!(pass.kind, PassKind::DeferredShading { .. }) => {
                    let slot = if roles.slots.contains_key(&Slot::GPosition) {
                        Slot::GNormal
                    } else {
                        Slot::GPosition
                    };
                    put(&mut roles, slot, name, &mut errors)
                }
                _ => errors.push(self.mismatch(
                    pass,
                    name,
                    format!("a {} pass cannot read a colour texture", pass.kind.label()),
                )),
            }
        }
        for name in &pass.writes {
            if self.import_of(name).is_some() {
                continue; // reported as a write to a read-only import by validation
            }
            if self.depth_texture(name).is_some() {
                put(&mut roles, Slot::Depth, name, &mut errors);
            } else if self.color_texture(name).is_some() && matches!(pass.kind, PassKind::GBuffer) {
                let slot = if roles.slots.contains_key(&Slot::GPosition) {
                    Slot::GNormal
                } else {
                    Slot::GPosition
                };
                put(&mut roles, slot, name, &mut errors);
            } else if self.color_texture(name).is_some() {
                put(&mut roles, Slot::Color, name, &mut errors);
            } else {
                put(&mut roles, Slot::LightLists, name, &mut errors);
            }
        }
        let need = |roles: &PassRoles, slot: Slot, what: &str, errors: &mut Vec<GraphError>| {
            if !roles.slots.contains_key(&slot) {
                errors.push(self.bad(pass, format!("{} needs {what}", pass.kind.label())));
            }
        };
        match &pass.kind {
            PassKind::DepthPrepass => {
                need(
                    &roles,
                    Slot::Depth,
                    "a depth texture in writes",
                    &mut errors,
                );
                for slot in [
                    Slot::Color,
                    Slot::LightLists,
                    Slot::LightGeometry,
                    Slot::LightProperties,
                ] {
                    if let Some(name) = roles.slot(slot) {
                        errors.push(self.mismatch(
                            pass,
                            name,
                            "a depth prepass has no colour target and uses no lights",
                        ));
                    }
                }
                if let Some(name) = roles.slot(Slot::Depth) {
                    if !pass.writes.iter().any(|w| w == name) {
                        errors.push(self.mismatch(
                            pass,
                            name,
                            "the depth prepass must write its depth texture",
                        ));
                    }
                }
            }
            PassKind::LightCulling {
                tile,
                variant,
                capacity,
                coarse,
            } => {
                need(&roles, Slot::Depth, "a depth texture in reads", &mut errors);
                need(
                    &roles,
                    Slot::LightGeometry,
                    "an Import of LightGeometry in reads",
                    &mut errors,
                );
                need(
                    &roles,
                    Slot::LightLists,
                    "a buffer in writes for the light lists",
                    &mut errors,
                );
                if let Some(name) = roles.slot(Slot::LightLists) {
                    if !pass.writes.iter().any(|w| w == name) {
                        errors.push(self.mismatch(pass, name, "light lists must be in writes"));
                    }
                }
                if let Some(name) = roles.slot(Slot::Depth) {
                    if self.depth_texture(name).unwrap_or(1) > 1 {
                        errors.push(self.mismatch(
                            pass,
                            name,
                            "culling reads a single-sample depth texture; this one is multisampled",
                        ));
                    }
                    if pass.writes.iter().any(|w| w == name) {
                        errors.push(self.mismatch(pass, name, "culling only reads depth"));
                    }
                }
                if !matches!(tile, 8 | 16) {
                    errors.push(self.bad(pass, format!("tile size {tile} is not supported (8 or 16: one workgroup of tile×tile invocations)")));
                }
                if *capacity == 0 || *capacity > 4096 {
                    errors.push(self.bad(pass, format!("capacity {capacity} must be in 1..=4096")));
                }
                if *coarse > 16 {
                    errors.push(self.bad(pass, format!("coarse {coarse} must be in 0..=16 tiles per side (0 or 1: no coarse stage)")));
                }
                if let super::model::CullVariant::Clustered { slices } = variant {
                    if *slices == 0 || *slices > 64 {
                        errors.push(
                            self.bad(pass, format!("clustered slices {slices} must be in 1..=64")),
                        );
                    }
                }
            }
            PassKind::ForwardShading { lights } => {
                need(
                    &roles,
                    Slot::Color,
                    "a colour texture in writes",
                    &mut errors,
                );
                need(
                    &roles,
                    Slot::Depth,
                    "a depth texture in reads or writes",
                    &mut errors,
                );
                self.check_light_inputs(pass, *lights, &roles, &mut errors);
                if let (Some(c), Some(d)) = (roles.slot(Slot::Color), roles.slot(Slot::Depth)) {
                    let (cs, ds) = (
                        self.color_texture(c).unwrap_or(1),
                        self.depth_texture(d).unwrap_or(1),
                    );
                    if cs != ds {
                        errors.push(self.mismatch(pass, c, format!("colour target has {cs} sample(s) but depth '{d}' has {ds}: MSAA needs both multisampled")));
                    }
                }
            }
            PassKind::GBuffer => {
                need(
                    &roles,
                    Slot::Depth,
                    "a depth texture (in writes, or in reads after a depth prepass)",
                    &mut errors,
                );
                need(
                    &roles,
                    Slot::GPosition,
                    "one Rgba32Float texture in writes (packed: view depth, octahedral normal, material) or two (positions, normals)",
                    &mut errors,
                );
                for slot in [Slot::GPosition, Slot::GNormal] {
                    if let Some(name) = roles.slot(slot) {
                        if !self.is_rgba32f(name) || self.color_texture(name) != Some(1) {
                            errors.push(self.mismatch(
                                pass,
                                name,
                                "G-buffer textures are single-sample Rgba32Float",
                            ));
                        }
                    }
                }
                if let Some(name) = roles.slot(Slot::Depth) {
                    if self.depth_texture(name) != Some(1) {
                        errors.push(self.mismatch(pass, name, "the G-buffer is single-sample"));
                    }
                }
                for slot in [
                    Slot::Color,
                    Slot::LightLists,
                    Slot::LightGeometry,
                    Slot::LightProperties,
                ] {
                    if let Some(name) = roles.slot(slot) {
                        errors.push(self.mismatch(pass, name, "a G-buffer pass uses no lights and writes only depth and its one or two textures"));
                    }
                }
            }
            PassKind::DeferredShading { lights } => {
                need(
                    &roles,
                    Slot::GPosition,
                    "the G-buffer's texture(s) in reads (packed, or positions and normals)",
                    &mut errors,
                );
                need(
                    &roles,
                    Slot::Color,
                    "an Rgba32Float texture in writes",
                    &mut errors,
                );
                self.check_light_inputs(pass, *lights, &roles, &mut errors);
                if let Some(name) = roles.slot(Slot::Color) {
                    if !self.is_rgba32f(name) || self.color_texture(name) != Some(1) {
                        errors.push(self.mismatch(
                            pass,
                            name,
                            "deferred shading stores into a single-sample Rgba32Float texture",
                        ));
                    }
                }
                if let Some(name) = roles.slot(Slot::Depth) {
                    errors.push(self.mismatch(
                        pass,
                        name,
                        "deferred shading reads positions from the G-buffer, not depth",
                    ));
                }
            }
            PassKind::Compute { .. } | PassKind::Fullscreen { .. } => {
                unreachable!("generic kinds are matched by binding")
            }
        }
        if errors.is_empty() {
            Ok(roles)
        } else {
            Err(errors)
        }
    }

    /// What every shading pass (forward or deferred) needs to read its lights.
    fn check_light_inputs(
        &self,
        pass: &PassDesc,
        lights: LightSource,
        roles: &PassRoles,
        errors: &mut Vec<GraphError>,
    ) {
        let kind = pass.kind.label();
        for (slot, what) in [
            (Slot::LightGeometry, "an Import of LightGeometry in reads"),
            (
                Slot::LightProperties,
                "an Import of LightProperties in reads",
            ),
        ] {
            if !roles.slots.contains_key(&slot) {
                errors.push(self.bad(pass, format!("{kind} needs {what}")));
            }
        }
        match (lights, roles.slot(Slot::LightLists)) {
            (LightSource::Culled, None) => errors.push(self.bad(
                pass,
                "lights: Culled needs the culling pass's light-list buffer in reads",
            )),
            (LightSource::AllLights, Some(name)) => {
                errors.push(self.mismatch(pass, name, "lights: AllLights reads no light lists"))
            }
            _ => {}
        }
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
            let targets: Vec<&String> = pass
                .writes
                .iter()
                .filter(|w| {
                    self.color_texture(w).is_some() && !bindings.iter().any(|b| &b.name == *w)
                })
                .collect();
            match targets.as_slice() {
                [one] => {
                    if self.color_texture(one) != Some(1) {
                        errors.push(self.mismatch(pass, one, "a Fullscreen pass renders into a single-sample target; this one is multisampled"));
                    }
                    roles.target = Some((*one).clone());
                }
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
                    roles.bindings.push((b.clone(), b.name.clone()));
                } else {
                    errors.push(GraphError::UndeclaredBinding {
                        at: self.source.in_pass(&pass.name, shader),
                        pass: pass.name.clone(),
                        shader: shader.to_string(),
                        binding: b.name.clone(),
                    });
                }
                continue;
            }
            if let Some(problem) = self.binding_problem(b, declared_write) {
                errors.push(self.mismatch(pass, &b.name, problem));
            }
            roles.bindings.push((b.clone(), b.name.clone()));
        }
        for name in pass.reads.iter().chain(&pass.writes) {
            let bound = bindings.iter().any(|b| &b.name == name);
            if !bound && roles.target.as_deref() != Some(name.as_str()) {
                errors.push(GraphError::UnboundResource {
                    at: self.source.in_pass(&pass.name, name),
                    pass: pass.name.clone(),
                    shader: shader.to_string(),
                    resource: name.clone(),
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
                BindingKind::SampledTexture { multisampled },
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
                BindingKind::StorageTexture { format, writable },
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
