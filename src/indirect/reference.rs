//! The one-bounce image VPLs approximate, path-traced on the CPU with no reflective
//! shadow map: from each pixel's first hit, bounce rays (cosine-weighted, and drawn from
//! the receiver's specular lobes) find the surfaces that light it; each such surface
//! reflects (diffusely, its diffuse lobes' colour) the direct light of every indirect
//! light that sees it (shadow ray through the scene BVH). Same light falloff as
//! `shaders/common/lighting.wgsl`, same receiver BRDF as the shading pass
//! (`material::reference::eval`), the VPL controls' intensity scale and receiver mask
//! applied; no range window or distance clamp (those are the VPLs' approximations).

use crate::graph::kinds::shadow_ray_cast::DEFAULT_NORMAL_OFFSET;
use crate::material::model::Lobe;
use crate::material::reference::{self as brdf, Surface};
use crate::material::Material;
use crate::scene::{light_flags, Light, LightShape, Scene};
use crate::shadow::{shadow_ray, ShadowBvh};
use glam::{Mat4, Vec3, Vec4};

/// What went wrong building the reference.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    /// The scene's BVH (used for the reference's rays) could not be built.
    #[error("the reference's BVH could not be built: {0}")]
    Bvh(#[from] crate::shadow::ShadowError),
}

struct Receiver {
    material: Material,
    diffuse: Vec3,
    type_bit: u32,
}

/// A scene ready to trace.
pub struct OneBounce<'a> {
    scene: &'a Scene,
    bvh: ShadowBvh,
    /// Per BVH triangle id: (mesh, first index of the triangle).
    triangles: Vec<(u32, u32)>,
    materials: Vec<Receiver>,
    lights: Vec<(usize, Light)>,
}

/// A camera ray's first hit: position, shading normal and geometric normal (both facing
/// the camera), the direction to the eye, and the scene's material index.
#[derive(Clone, Copy, Debug)]
pub struct Primary {
    /// Hit position, world space.
    pub x: Vec3,
    /// Shading normal (unit, facing the camera).
    pub n: Vec3,
    /// Geometric normal (unit, facing the camera).
    pub ng: Vec3,
    /// Unit direction from the hit to the eye.
    pub v: Vec3,
    pub(crate) m: usize,
}

struct Hit {
    t: f32,
    id: u32,
    u: f32,
    v: f32,
}

impl<'a> OneBounce<'a> {
    /// Prepares `scene` for tracing: builds its BVH and maps each material to its receiver
    /// BRDF.
    pub fn new(scene: &'a Scene) -> Result<Self, ReferenceError> {
        let bvh = ShadowBvh::build(scene)?;
        let mut triangles = Vec::new();
        for (m, mesh) in scene.meshes.iter().enumerate() {
            for t in 0..mesh.indices.len() / 3 {
                triangles.push((m as u32, 3 * t as u32));
            }
        }
        let materials = scene
            .materials
            .iter()
            .map(|s| {
                let material = Material::from_surface(s);
                let at = Surface::new([0.0, 0.0, 1.0]);
                let mut diffuse = Vec3::ZERO;
                for layer in &material.desc().layers {
                    for lobe in &layer.lobes {
                        if let Lobe::Lambert { color, weight }
                        | Lobe::OrenNayar { color, weight, .. } = lobe
                        {
                            let c = brdf::color(color, &at);
                            diffuse += Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) * *weight;
                        }
                    }
                }
                Receiver {
                    type_bit: material.type_bit(),
                    material,
                    diffuse,
                }
            })
            .collect();
        let lights = scene
            .lights
            .iter()
            .enumerate()
            .filter(|(_, l)| l.flags & light_flags::INDIRECT != 0)
            .map(|(i, l)| (i, *l))
            .collect();
        Ok(Self {
            scene,
            bvh,
            triangles,
            materials,
            lights,
        })
    }

    /// The nearest hit along `origin + t dir`, `0 < t < t_max`.
    fn closest(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<Hit> {
        let nodes = &self.bvh.nodes;
        if nodes.is_empty() {
            return None;
        }
        let inv = Vec3::ONE / dir;
        let slab = |i: u32| -> Option<f32> {
            let n = nodes[i as usize];
            let t0 = (Vec3::from(n.min) - origin) * inv;
            let t1 = (Vec3::from(n.max) - origin) * inv;
            let lo = t0.min(t1).max_element().max(0.0);
            let hi = t0.max(t1).min_element();
            (lo <= hi * 1.000_001).then_some(lo)
        };
        let mut best: Option<Hit> = None;
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            let Some(t_node) = slab(i) else { continue };
            if t_node > best.as_ref().map_or(t_max, |h| h.t) {
                continue;
            }
            let n = nodes[i as usize];
            if n.is_leaf() {
                for tri in &self.bvh.triangles[n.a as usize..(n.a + n.count()) as usize] {
                    let (e1, e2) = (Vec3::from(tri.e1), Vec3::from(tri.e2));
                    let p = dir.cross(e2);
                    let det = e1.dot(p);
                    if det.abs() < 1e-20 {
                        continue;
                    }
                    let s = origin - Vec3::from(tri.v0);
                    let u = s.dot(p) / det;
                    let q = s.cross(e1);
                    let v = dir.dot(q) / det;
                    let t = e2.dot(q) / det;
                    if u >= 0.0
                        && v >= 0.0
                        && u + v <= 1.0
                        && t > 0.0
                        && t < best.as_ref().map_or(t_max, |h| h.t)
                    {
                        best = Some(Hit {
                            t,
                            id: tri.id,
                            u,
                            v,
                        });
                    }
                }
            } else {
                stack.push(n.a);
                stack.push(i + 1);
            }
        }
        best
    }

    /// (position, shading normal facing `from`, geometric normal facing it, material).
    fn surface(&self, origin: Vec3, dir: Vec3, h: &Hit) -> (Vec3, Vec3, Vec3, usize) {
        let (m, first) = self.triangles[h.id as usize];
        let mesh = &self.scene.meshes[m as usize];
        let idx = |k: u32| mesh.indices[(first + k) as usize] as usize;
        let (a, b, c) = (idx(0), idx(1), idx(2));
        let p = origin + dir * h.t;
        let ng = (mesh.positions[b] - mesh.positions[a])
            .cross(mesh.positions[c] - mesh.positions[a])
            .normalize_or_zero();
        let ng = if ng.dot(dir) > 0.0 { -ng } else { ng };
        let n = match (
            mesh.normals.get(a),
            mesh.normals.get(b),
            mesh.normals.get(c),
        ) {
            (Some(&na), Some(&nb), Some(&nc)) => {
                (na * (1.0 - h.u - h.v) + nb * h.u + nc * h.v).normalize_or(ng)
            }
            _ => ng,
        };
        let n = if n.dot(ng) < 0.0 { -n } else { n };
        (
            p,
            n,
            ng,
            mesh.material.min(self.materials.len().saturating_sub(1)),
        )
    }

    /// Direct light of indirect light `l` reflected diffusely at y, as radiance.
    fn reflected(&self, l: &Light, y: Vec3, n: Vec3, ng: Vec3, mat: &Receiver) -> Vec3 {
        if l.material_mask & mat.type_bit == 0 {
            return Vec3::ZERO;
        }
        let d = l.position - y;
        let dist_sq = d.length_squared();
        let dir = d / dist_sq.sqrt().max(1e-15);
        let cos = n.dot(dir);
        if cos <= 0.0 || ng.dot(dir) <= 0.0 {
            return Vec3::ZERO;
        }
        let r = dist_sq / (l.range * l.range);
        let window = (1.0 - r * r).clamp(0.0, 1.0);
        if window <= 0.0 {
            return Vec3::ZERO;
        }
        let spot = match l.shape {
            LightShape::Point => 1.0,
            LightShape::Spot {
                direction,
                inner_angle,
                outer_angle,
            } => {
                let (co, ci) = (outer_angle.cos(), inner_angle.min(outer_angle).cos());
                let cd = direction.normalize_or_zero().dot(-dir);
                let a = ((cd - co) / (ci - co).max(0.001)).clamp(0.0, 1.0);
                a * a
            }
        };
        if spot <= 0.0 {
            return Vec3::ZERO;
        }
        // The shadow ray every tracer casts: off the surface at its start, short of the
        // light at its end by the light's own precision, so a light lying on a surface is
        // not hidden by it.
        let (origin, to_light, t_max) = shadow_ray(y, ng, l.position, DEFAULT_NORMAL_OFFSET);
        if self.bvh.occluded(origin, to_light, t_max) {
            return Vec3::ZERO;
        }
        let radiance = l.color * l.intensity * (window * spot / dist_sq.max(1e-4));
        mat.diffuse / std::f32::consts::PI * radiance * cos
    }

    /// The camera ray's first hit at pixel (px, py) of a `width`×`height` frame.
    pub fn primary(&self, px: u32, py: u32, width: u32, height: u32) -> Option<Primary> {
        let cam = &self.scene.camera;
        let inv: Mat4 = (cam.projection(width as f32 / height as f32) * cam.view()).inverse();
        let ndc = glam::Vec2::new(
            (px as f32 + 0.5) / width as f32 * 2.0 - 1.0,
            1.0 - (py as f32 + 0.5) / height as f32 * 2.0,
        );
        let far = inv * Vec4::new(ndc.x, ndc.y, 1.0, 1.0);
        let dir = (far.truncate() / far.w - cam.eye).normalize();
        let h = self.closest(cam.eye, dir, f32::MAX)?;
        let (x, n, ng, m) = self.surface(cam.eye, dir, &h);
        Some(Primary {
            x,
            n,
            ng,
            v: -dir,
            m,
        })
    }

    /// Indirect radiance towards the camera at pixel (px, py) of a `width`×`height`
    /// frame, with `samples` bounce rays: cosine-weighted, and on a receiver with
    /// specular lobes shared equally with rays drawn from each lobe (multiple importance
    /// sampling, `LobeSampler`). Cosine rays alone rarely hit a narrow lobe: on the
    /// atrium's bronze crates (α 0.09) their 1,024-ray estimates scattered from 0.42 to
    /// 1.8 times the converged value.
    pub fn pixel(&self, px: u32, py: u32, width: u32, height: u32, samples: u32) -> Vec3 {
        self.pixel_seeded(px, py, width, height, samples, 0)
    }

    /// [`Self::pixel`] with its random numbers drawn from `seed`'s sequence.
    pub fn pixel_seeded(
        &self,
        px: u32,
        py: u32,
        width: u32,
        height: u32,
        samples: u32,
        seed: u64,
    ) -> Vec3 {
        let Some(Primary { x, n, ng, v, m }) = self.primary(px, py, width, height) else {
            return Vec3::ZERO;
        };
        let receiver = &self.materials[m];
        let to64 = |a: Vec3| [a.x as f64, a.y as f64, a.z as f64];
        // The cosine proposal in the frame (t, b, n) the tracer has always used.
        let (t, b) = n.any_orthonormal_pair();
        let mut at = Surface::new(to64(n));
        at.tangent = [
            t.x as f64,
            t.y as f64,
            t.z as f64,
            n.cross(t).dot(b).signum() as f64,
        ];
        let sampler = brdf::LobeSampler::new(&receiver.material, &at);
        let v64 = to64(v);
        let eps = 1e-4 * x.abs().max_element().max(1.0);
        let mut rng = ((px as u64) << 32 ^ py as u64 ^ 0x9e37_79b9_7f4a_7c15)
            .wrapping_add(seed.wrapping_mul(0xd1b5_4a32_d192_ed03));
        let mut sum = Vec3::ZERO;
        // Each proposal takes its share of the rays, stratified on its own grid; a ray
        // counts f / (samples × the mixture's density), the balance heuristic.
        let proposals = sampler.proposals();
        for which in 0..proposals {
            let count = samples / proposals as u32
                + if which == 0 {
                    samples % proposals as u32
                } else {
                    0
                };
            // Stratified on the largest full side×side grid, jittered; the rays past it
            // uniform (a partly filled grid would leave cells unsampled: biased).
            let side = ((count as f64).sqrt() as u32).max(1);
            for k in 0..count {
                let (mut u1, mut u2) = (next(&mut rng), next(&mut rng));
                if k < side * side {
                    u1 = ((k % side) as f32 + u1) / side as f32;
                    u2 = ((k / side) as f32 + u2) / side as f32;
                }
                let Some(l) = sampler.sample(which, v64, u1 as f64, u2 as f64) else {
                    continue;
                };
                let pdf = sampler.pdf(v64, l) as f32;
                let l = Vec3::new(l[0] as f32, l[1] as f32, l[2] as f32).normalize();
                if n.dot(l) <= 1e-6 || ng.dot(l) <= 0.0 || pdf.is_nan() || pdf <= 0.0 {
                    continue;
                }
                let lo = self.bounced(x + ng * eps, l, receiver.type_bit);
                if lo == Vec3::ZERO {
                    continue;
                }
                let f = brdf::eval(&receiver.material, to64(n), v64, to64(l));
                let f = Vec3::new(f[0] as f32, f[1] as f32, f[2] as f32);
                sum += f * (1.0 / pdf) * lo;
            }
        }
        sum / samples as f32
    }

    /// Radiance reflected towards `origin` by the first surface along `l`: the direct
    /// light of every indirect light whose VPLs light a receiver of `type_bit`.
    fn bounced(&self, origin: Vec3, l: Vec3, type_bit: u32) -> Vec3 {
        let Some(hy) = self.closest(origin, l, f32::MAX) else {
            return Vec3::ZERO;
        };
        let (y, ny, ngy, my) = self.surface(origin, l, &hy);
        let mut lo = Vec3::ZERO;
        for (i, light) in &self.lights {
            if self.scene.vpl(*i).material_mask & type_bit == 0 {
                continue;
            }
            lo += self.scene.vpl(*i).intensity
                * self.reflected(light, y, ny, ngy, &self.materials[my]);
        }
        lo
    }

    /// The whole indirect image, row-major, rows shared among the machine's cores.
    pub fn image(&self, width: u32, height: u32, samples: u32) -> Vec<Vec3> {
        self.image_seeded(width, height, samples, 0)
    }

    /// [`Self::image`] with another random sequence: two seeds give independent estimates,
    /// whose difference measures the reference's own noise.
    pub fn image_seeded(&self, width: u32, height: u32, samples: u32, seed: u64) -> Vec<Vec3> {
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let mut out = vec![Vec3::ZERO; (width * height) as usize];
        let rows_each = (height as usize).div_ceil(threads).max(1);
        std::thread::scope(|s| {
            for (chunk, rows) in out.chunks_mut(rows_each * width as usize).enumerate() {
                s.spawn(move || {
                    for (k, p) in rows.iter_mut().enumerate() {
                        let y = (chunk * rows_each + k / width as usize) as u32;
                        *p = self.pixel_seeded(k as u32 % width, y, width, height, samples, seed);
                    }
                });
            }
        });
        out
    }
}

/// A uniform float in [0, 1) (SplitMix64).
fn next(state: &mut u64) -> f32 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_133f_11eb);
    ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
}

/// Σ (a − b)² / Σ b² over every pixel's RGB: the relative MSE of `a` against `b`.
pub fn relative_mse(a: &[Vec3], b: &[Vec3]) -> f64 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (x, y) in a.iter().zip(b) {
        num += (*x - *y).length_squared() as f64;
        den += y.length_squared() as f64;
    }
    num / den.max(1e-30)
}

/// Where `a`'s squared error against `b` sits: its worst pixel and that pixel's share of
/// Σ (a − b)², and how many of `a`'s pixels are not finite. One pixel holding most of the
/// error is a defect (a singularity), not the approximation's spread-out error.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WorstPixel {
    /// Index of the worst pixel, row-major.
    pub index: usize,
    /// Its value in `a`.
    pub value: Vec3,
    /// Its value in `b`, the reference.
    pub reference: Vec3,
    /// Its (a − b)² over Σ (a − b)²
    pub share: f64,
    /// Pixels of `a` with a NaN or infinite channel (left out of the sums).
    pub non_finite: usize,
}

/// The [`WorstPixel`] of image `a` against reference `b` (pixels row-major, same length).
pub fn worst_pixel(a: &[Vec3], b: &[Vec3]) -> WorstPixel {
    let mut w = WorstPixel::default();
    let (mut total, mut worst) = (0.0f64, -1.0f64);
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        if !x.is_finite() {
            w.non_finite += 1;
            continue;
        }
        let e = (*x - *y).length_squared() as f64;
        total += e;
        if e > worst {
            (worst, w.index, w.value, w.reference) = (e, i, *x, *y);
        }
    }
    w.share = worst.max(0.0) / total.max(1e-30);
    w
}

/// The indirect part of a VPL frame: it minus the same frame without VPLs.
pub fn indirect_part(with: &[[f32; 4]], without: &[[f32; 4]]) -> Vec<Vec3> {
    with.iter()
        .zip(without)
        .map(|(a, b)| Vec3::new(a[0] - b[0], a[1] - b[1], a[2] - b[2]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Indirect lights lying on a wall 30 km out, seen from a receiver at the origin: the
    /// wall is hit at t ≈ 1 either side of 1 by f32 rounding (2 mm there), so an end
    /// short of the light by the receiver's precision (0.2 mm) hid about half of them.
    #[test]
    fn a_light_on_a_far_wall_is_not_hidden_by_the_wall() {
        let z = -30_000.0;
        let mut wall = crate::scene::geometry::MeshBuilder::new("wall", 0);
        wall.quad(
            Vec3::new(-100.0, 0.0, z),
            Vec3::X * 200.0,
            Vec3::Y * 100.0,
            glam::Vec2::ONE,
        );
        let lights: Vec<Light> = (0..64)
            .map(|i| {
                let mut l = Light::point(
                    Vec3::new(-80.0 + 2.5 * i as f32, 10.0 + 0.37 * i as f32, z),
                    1e6,
                    Vec3::ONE,
                    1.0,
                );
                l.flags = light_flags::INDIRECT;
                l
            })
            .collect();
        let scene = Scene {
            meshes: vec![wall.build()],
            materials: vec![Default::default()],
            lights,
            ..Default::default()
        };
        let tracer = OneBounce::new(&scene).unwrap();
        let hidden = scene
            .lights
            .iter()
            .filter(|l| {
                let r = tracer.reflected(
                    l,
                    Vec3::ZERO,
                    Vec3::NEG_Z,
                    Vec3::NEG_Z,
                    &tracer.materials[0],
                );
                r == Vec3::ZERO
            })
            .count();
        assert_eq!(hidden, 0, "lights hidden by the wall they lie on");
    }

    #[test]
    fn worst_pixel_finds_the_pixel_holding_the_error_and_counts_non_finite_ones() {
        let b = vec![Vec3::ONE; 4];
        let a = vec![
            Vec3::ONE * 1.1,
            Vec3::ONE * 4.0,
            Vec3::splat(f32::NAN),
            Vec3::ONE,
        ];
        let w = worst_pixel(&a, &b);
        assert_eq!((w.index, w.non_finite), (1, 1));
        assert_eq!(w.value, Vec3::ONE * 4.0);
        // 27 of 27.03
        assert!((w.share - 27.0 / 27.03).abs() < 1e-6, "{}", w.share);
    }
}
