//! CPU versions of the culling tests in `shaders/cull/light_culling.wgsl`, line for line, for
//! property tests (a light that reaches any point of a tile's depth range is never
//! culled) and for tools that want to reason about lists without a GPU. (The shader
//! computes a light's view-space sphere once a frame in its `bounds` dispatch and tests
//! it per tile in `light_touches_tile`; the arithmetic is the same as here in one piece.)

use glam::{Mat4, Vec2, Vec3};

/// A light as culling sees it, in view space.
#[derive(Clone, Copy, Debug)]
pub struct ViewLight {
    /// Centre in view space (the camera looks down -z).
    pub position: Vec3,
    /// Distance (world units) at which the light's falloff reaches zero.
    pub range: f32,
    /// Unit axis for spots; ignored when `cos_outer <= -1` (point light).
    pub direction: Vec3,
    /// Cosine of the spot cone's outer half-angle; -1 for point lights.
    pub cos_outer: f32,
}

/// The four side planes of a tile (through the eye, normals inward) and its corner rays.
#[derive(Clone, Copy, Debug)]
pub struct TileFrustum {
    /// Inward unit normals of the four side planes, each through the eye and two consecutive
    /// corner rays.
    pub planes: [Vec3; 4],
    /// View-space rays through the tile's corners (top-left, top-right, bottom-right,
    /// bottom-left), reaching the far plane.
    pub rays: [Vec3; 4],
}

/// View-space point on the far plane through framebuffer position `pixel`.
pub fn view_ray(inv_proj: Mat4, size: Vec2, pixel: Vec2) -> Vec3 {
    let ndc = Vec2::new(pixel.x / size.x * 2.0 - 1.0, 1.0 - pixel.y / size.y * 2.0);
    let p = inv_proj * ndc.extend(1.0).extend(1.0);
    p.truncate() / p.w
}

/// The frustum of the tile spanning pixels [x0, x1) × [y0, y1).
pub fn tile_frustum(inv_proj: Mat4, size: Vec2, x0: f32, y0: f32, x1: f32, y1: f32) -> TileFrustum {
    let c00 = view_ray(inv_proj, size, Vec2::new(x0, y0));
    let c10 = view_ray(inv_proj, size, Vec2::new(x1, y0));
    let c11 = view_ray(inv_proj, size, Vec2::new(x1, y1));
    let c01 = view_ray(inv_proj, size, Vec2::new(x0, y1));
    TileFrustum {
        planes: [
            c00.cross(c10).normalize(),
            c10.cross(c11).normalize(),
            c11.cross(c01).normalize(),
            c01.cross(c00).normalize(),
        ],
        rays: [c00, c10, c11, c01],
    }
}

/// Bounding sphere of the tile's frustum between view depths lo and hi.
pub fn tile_sphere(t: &TileFrustum, lo: f32, hi: f32) -> (Vec3, f32) {
    let mut corners = [Vec3::ZERO; 8];
    let mut center = Vec3::ZERO;
    for i in 0..4 {
        corners[i] = t.rays[i] * (lo / -t.rays[i].z);
        corners[i + 4] = t.rays[i] * (hi / -t.rays[i].z);
        center += corners[i] + corners[i + 4];
    }
    center /= 8.0;
    let radius = corners
        .iter()
        .map(|c| center.distance(*c))
        .fold(0.0, f32::max);
    (center, radius)
}

/// Bounding sphere of a light's volume: the range sphere, or for a spot the tighter
/// sphere around its cone and spherical cap.
pub fn light_sphere(l: &ViewLight) -> (Vec3, f32) {
    if l.cos_outer <= -1.0 {
        return (l.position, l.range);
    }
    let c = l.cos_outer.max(0.0);
    let s = (1.0 - c * c).max(0.0).sqrt();
    if c < std::f32::consts::FRAC_1_SQRT_2 {
        (l.position + l.direction * (l.range * c), l.range * s)
    } else {
        let r = l.range / (2.0 * c);
        (l.position + l.direction * r, r)
    }
}

/// Depth cell of z among 32 equal cells of [lo, hi] (the 2.5D mask).
pub fn cell_of(z: f32, lo: f32, hi: f32) -> u32 {
    let t = (z - lo) / (hi - lo).max(1e-30);
    (t * 32.0).clamp(0.0, 31.0) as u32
}

/// Bits a..=b set.
pub fn cells_between(a: u32, b: u32) -> u32 {
    let width = b - a + 1;
    let ones = if width >= 32 {
        u32::MAX
    } else {
        (1u32 << width) - 1
    };
    ones << a
}

/// The culling decision: false only if the light cannot reach any point of the tile
/// between view depths lo and hi (and, with a mask, any occupied depth cell).
pub fn light_touches_tile(
    l: &ViewLight,
    t: &TileFrustum,
    lo: f32,
    hi: f32,
    depth_mask: Option<(u32, f32, f32)>,
) -> bool {
    let (center, radius) = light_sphere(l);
    let radius = radius * 1.0001 + 1e-5;
    let z = -center.z;
    if z + radius < lo || z - radius > hi {
        return false;
    }
    if t.planes.iter().any(|p| p.dot(center) < -radius) {
        return false;
    }
    if let Some((mask, tile_min, tile_max)) = depth_mask {
        let a = cell_of(z - radius, tile_min, tile_max);
        let b = cell_of(z + radius, tile_min, tile_max);
        if cells_between(a, b) & mask == 0 {
            return false;
        }
    }
    if l.cos_outer > -1.0 {
        let (tc, tr) = tile_sphere(t, lo, hi);
        let v = tc - l.position;
        let v1 = v.dot(l.direction);
        let c = l.cos_outer;
        let s = (1.0 - c * c).max(0.0).sqrt();
        let closest = c * (v.length_squared() - v1 * v1).max(0.0).sqrt() - v1 * s;
        let r = tr * 1.0001 + 1e-5;
        if closest > r || v1 > r + l.range || v1 < -r {
            return false;
        }
    }
    true
}

/// Whether the light's attenuation is non-zero at view-space point `p` (range window
/// and outer cone), the shading side of the contract.
pub fn reaches(l: &ViewLight, p: Vec3) -> bool {
    let d = l.position - p;
    let dist_sq = d.length_squared();
    if dist_sq >= l.range * l.range {
        return false;
    }
    if l.cos_outer <= -1.0 {
        return true;
    }
    let dir = -d.normalize_or_zero();
    dir.dot(l.direction) > l.cos_outer
}
