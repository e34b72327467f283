//! WGSL handling without a GPU: composing files (includes, defines), validating with
//! naga (errors mapped back to the original file and line), reflecting bindings; and
//! where the project's files are found ([`assets`]: a root folder, then built-in copies).

pub mod assets;
mod compose;
pub(crate) mod limits;
mod reflect;

pub use compose::{Composed, ShaderError, ShaderLibrary};
pub use reflect::{reflect_bindings, struct_layout, BindingKind, ReflectedBinding};
