//! One-bounce indirect light: reflective shadow maps of the scene's indirect lights
//! (their views laid out in an atlas, [`rsm_views`]) become virtual point lights on the
//! GPU (`VplSpawn`); [`reference`](mod@reference) is the path-traced one-bounce image they approximate.

pub mod reference;
pub mod rsm_views;
