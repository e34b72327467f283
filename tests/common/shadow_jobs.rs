//! Reading back ray-cast shadow jobs and checking them on the CPU: each pixel's jobs and
//! mask bits, the surface a visibility-buffer pixel shows rebuilt in f64, and every bit
//! against the CPU twin's ray (`ShadowBvh::occluded`).

use glam::{DMat4, DVec3, DVec4};
use lightgraph::render::{PreparedFrame, Renderer, SceneGpu};
use lightgraph::scene::Scene;
use lightgraph::shadow::reference::near_edge;
use lightgraph::shadow::{scene_triangles_f64, shadow_ray, ShadowBvh, Triangle64};
use std::collections::BTreeMap;

/// Each pixel's jobs as light -> hidden, from the job buffer and the mask of a frame of
/// `pixels` pixels.
pub fn pixel_jobs(r: &Renderer, prepared: &PreparedFrame, pixels: u32) -> Vec<BTreeMap<u32, bool>> {
    let words = |name: &str| -> Vec<u32> {
        bytemuck::cast_slice(&prepared.read_buffer(r, name).unwrap()).to_vec()
    };
    let (jobs, mask) = (words("shadow_jobs"), words("shadow_mask"));
    assert_eq!(mask.len(), (pixels * 4) as usize);
    let count = jobs[0] as usize;
    assert!(count <= (jobs.len() - 8) / 2, "jobs dropped");
    let mut out = vec![BTreeMap::new(); pixels as usize];
    for j in 0..count {
        let (pixel, packed) = (jobs[8 + 2 * j], jobs[8 + 2 * j + 1]);
        let (light, c) = (packed & 0xff_ffff, packed >> 24);
        let hidden = mask[(pixel * 4 + c / 32) as usize] & (1 << (c % 32)) != 0;
        assert!(
            out[pixel as usize].insert(light, hidden).is_none(),
            "two jobs for light {light} at pixel {pixel}"
        );
    }
    out
}

/// The surface a visibility-buffer pixel shows, rebuilt on the CPU in f64 from its
/// triangle: the camera ray through the pixel centre met with the triangle's plane, and
/// the triangle's normal facing the eye.
pub struct Surfaces {
    /// Per merged triangle id: its three world positions.
    triangles: Vec<[DVec3; 3]>,
    inverse_view_proj: DMat4,
    eye: DVec3,
    width: u32,
    height: u32,
}

impl Surfaces {
    pub fn new(r: &Renderer, scene: &Scene, width: u32, height: u32) -> Self {
        let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, scene).unwrap();
        let mut triangles = Vec::new();
        // Triangle ids in draw order (src/render/visibility_geometry.rs).
        for mesh in gpu.opaque_draws() {
            let gm = &gpu.meshes[mesh];
            assert_eq!(gm.first_triangle as usize, triangles.len());
            let m = &scene.meshes[gm.scene_mesh];
            triangles.extend(
                m.indices
                    .chunks_exact(3)
                    .map(|t| [0, 1, 2].map(|k| m.positions[t[k] as usize].as_dvec3())),
            );
        }
        let aspect = width as f32 / height as f32;
        let vp = (scene.camera.projection(aspect) * scene.camera.view()).as_dmat4();
        Self {
            triangles,
            inverse_view_proj: vp.inverse(),
            eye: scene.camera.eye.as_dvec3(),
            width,
            height,
        }
    }

    /// The point and the eye-facing geometric normal of `pixel`, showing triangle `id`.
    pub fn at(&self, pixel: u32, id: u32) -> (DVec3, DVec3) {
        let [a, b, c] = self.triangles[id as usize];
        let (w, h) = (self.width, self.height);
        let (x, y) = (pixel % w, pixel / w);
        let ndc = DVec4::new(
            (x as f64 + 0.5) / w as f64 * 2.0 - 1.0,
            1.0 - (y as f64 + 0.5) / h as f64 * 2.0,
            0.5,
            1.0,
        );
        let q = self.inverse_view_proj * ndc;
        let dir = q.truncate() / q.w - self.eye;
        let n = (b - a).cross(c - a).normalize();
        let p = self.eye + dir * (n.dot(a - self.eye) / n.dot(dir));
        (p, if n.dot(self.eye - p) < 0.0 { -n } else { n })
    }
}

/// Every mask bit of a visibility-buffer frame against the CPU twin's ray from the
/// surface rebuilt on the CPU (origin offset `offset`): (agreeing, grazing an edge
/// within 1e-4, failures).
pub fn compare_with_cpu_twin(
    scene: &Scene,
    surfaces: &Surfaces,
    ids: &[u32],
    vis: &[BTreeMap<u32, bool>],
    offset: f32,
) -> (usize, usize, Vec<String>) {
    let bvh = ShadowBvh::build(scene).unwrap();
    let tris: Vec<Triangle64> = scene_triangles_f64(scene);
    let (mut agree, mut grazing, mut failures) = (0, 0, Vec::new());
    for (pixel, jobs) in vis.iter().enumerate() {
        if jobs.is_empty() {
            continue;
        }
        let (p, ng) = surfaces.at(pixel as u32, ids[pixel]);
        for (&light, &hidden) in jobs {
            let lp = scene.lights[light as usize].position;
            let (o, dir, t_max) = shadow_ray(p.as_vec3(), ng.as_vec3(), lp, offset);
            if bvh.occluded(o, dir, t_max) == hidden {
                agree += 1;
            } else if near_edge(&tris, o.as_dvec3(), dir.as_dvec3(), t_max as f64, 1e-4) {
                grazing += 1;
            } else {
                failures.push(format!("pixel {pixel} light {light}: GPU hidden {hidden}"));
            }
        }
    }
    (agree, grazing, failures)
}

/// raycast_shadows.ron without its shading pass, the G-buffer as the output and the
/// casting pass kept as a side effect, so its positions, normals, jobs and mask can be
/// read back (in the full graph the frame's colour texture reuses the G-buffer's).
pub fn raycast_inspection_graph() -> String {
    let text = super::graph_text("raycast_shadows.ron");
    let start = text
        .find("        Pass(\n            name: \"forward_shading\"")
        .expect("shading pass");
    let end = start + text[start..].find("        ),\n").unwrap() + "        ),\n".len();
    format!("{}{}", &text[..start], &text[end..]).replace(
        "output: \"hdr\",",
        "output: \"g_position\",\n    side_effects: [\"shadow_ray_cast\"],",
    )
}
