//! Scenes: what gets rendered. Geometry in world space, lights, a camera.

mod types;

pub use types::*;
