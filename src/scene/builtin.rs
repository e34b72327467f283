//! Built-in procedural scenes.
use super::types::Scene;
pub const NAMES: &[&str] = &["atrium", "harada", "depth_discontinuity"];
pub fn by_name(_name: &str) -> Option<Scene> {
    None
}
