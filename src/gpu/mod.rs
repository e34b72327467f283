//! GPU side: device, GPU struct layouts, readback, timestamp queries.

mod context;
pub mod driver_limits;
pub mod pipeline_cache;
pub mod readback;
pub mod structs;
#[cfg(test)]
mod wgsl_constants;

pub use context::{ContextOptions, GpuContext, GpuError};
pub use driver_limits::DriverLimits;
