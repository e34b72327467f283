//! Layered BRDF materials (RON model, WGSL generation, f64 reference).
