use naga::{AddressSpace, ImageClass, StorageAccess, TypeInner};

/// What a shader binding is, as far as matching it against a graph resource goes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BindingKind {
    /// A `var<uniform>` buffer.
    Uniform,
    /// A `var<storage>` buffer.
    Storage {
        /// `read_write` access (otherwise `read`).
        writable: bool,
    },
    /// `texture_2d<f32>` and friends; `multisampled` for `texture_multisampled_2d`.
    SampledTexture {
        /// Whether it is `texture_multisampled_2d`.
        multisampled: bool,
        /// `f32`, `u32` (visibility ids) or `i32` texels.
        kind: naga::ScalarKind,
    },
    /// A `texture_depth_2d` (or multisampled depth) texture.
    DepthTexture {
        /// Whether it is `texture_depth_multisampled_2d`.
        multisampled: bool,
    },
    /// A `texture_storage_2d`.
    StorageTexture {
        /// Its texel format.
        format: naga::StorageFormat,
        /// `write` or `read_write` access.
        writable: bool,
        /// `read_write` (with `writable`), or `read`.
        readable: bool,
    },
    /// A `sampler` or `sampler_comparison`.
    Sampler {
        /// Whether it is a `sampler_comparison`.
        comparison: bool,
    },
}

/// One `@group @binding` resource a shader declares, with its variable name (what generic
/// passes match resources by).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReflectedBinding {
    /// The WGSL variable name.
    pub name: String,
    /// Its `@group` index.
    pub group: u32,
    /// Its `@binding` index.
    pub binding: u32,
    /// What kind of resource it binds.
    pub kind: BindingKind,
}

/// Every resource binding a module declares, in (group, binding) order.
pub fn reflect_bindings(module: &naga::Module) -> Vec<ReflectedBinding> {
    let mut out: Vec<ReflectedBinding> = module
        .global_variables
        .iter()
        .filter_map(|(_, var)| {
            let rb = var.binding.as_ref()?;
            let kind = match var.space {
                AddressSpace::Uniform => BindingKind::Uniform,
                AddressSpace::Storage { access } => BindingKind::Storage {
                    writable: access.contains(StorageAccess::STORE),
                },
                AddressSpace::Handle => match &module.types[var.ty].inner {
                    TypeInner::Image { class, .. } => match *class {
                        ImageClass::Sampled { multi, kind } => BindingKind::SampledTexture {
                            multisampled: multi,
                            kind,
                        },
                        ImageClass::Depth { multi } => BindingKind::DepthTexture {
                            multisampled: multi,
                        },
                        ImageClass::Storage { format, access } => BindingKind::StorageTexture {
                            format,
                            writable: access.contains(StorageAccess::STORE),
                            readable: access.contains(StorageAccess::LOAD),
                        },
                        ImageClass::External => return None,
                    },
                    TypeInner::Sampler { comparison } => BindingKind::Sampler {
                        comparison: *comparison,
                    },
                    _ => return None,
                },
                _ => return None,
            };
            Some(ReflectedBinding {
                name: var.name.clone().unwrap_or_default(),
                group: rb.group,
                binding: rb.binding,
                kind,
            })
        })
        .collect();
    out.sort_by_key(|b| (b.group, b.binding));
    out
}

/// (member name, byte offset, byte size) of each member of a struct.
pub type MemberLayout = Vec<(String, u32, u32)>;

/// The members of a WGSL struct and its total size.
pub fn struct_layout(module: &naga::Module, name: &str) -> Option<(MemberLayout, u32)> {
    let (_, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))?;
    let TypeInner::Struct { members, span } = &ty.inner else {
        return None;
    };
    let gctx = module.to_ctx();
    let fields = members
        .iter()
        .map(|m| {
            (
                m.name.clone().unwrap_or_default(),
                m.offset,
                module.types[m.ty].inner.size(gctx),
            )
        })
        .collect();
    Some((fields, *span))
}
