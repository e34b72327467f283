//! Meshes added to and removed from a prepared frame's scene without compiling the
//! graph again: the mesh is uploaded (or forgotten) alone, the visibility ids are
//! numbered again, the shadow BVH and the merged visibility geometry (with its material
//! ranges) are rebuilt for the new geometry, and the frame's passes are prepared again
//! over the same physical resources with their pipelines from the cache (a mesh of a
//! material already drawn builds none: `PreparedFrame::stats`).

use super::PreparedFrame;
use crate::render::scene_gpu::SceneGpu;
use crate::render::{RenderError, Renderer};
use crate::scene::ranges::MAX_COORDINATE;
use crate::scene::{Mesh, Scene, SceneFeatures};

/// Why a mesh edit was refused; the scene, its upload and the frame are as before.
#[derive(Debug, thiserror::Error)]
pub enum MeshEditError {
    /// The added mesh fails the checks a scene file's meshes pass.
    #[error("mesh edit: mesh \"{name}\": {problem}")]
    BadMesh {
        /// The mesh's name.
        name: String,
        /// What is wrong with it.
        problem: String,
    },
    /// No mesh at the index to remove.
    #[error("mesh edit: no mesh {index} to remove: the scene has {count}")]
    NoMesh {
        /// The index asked for.
        index: usize,
        /// Meshes in the scene.
        count: usize,
    },
    /// The edit changes a scene feature the graph's `when:` conditions and shaders were
    /// compiled for.
    #[error("mesh edit: {what} \"{name}\" changes whether the scene has {feature}, which the graph was compiled for: compile and prepare again")]
    NewFeature {
        /// "adding" or "removing".
        what: &'static str,
        /// The mesh's name.
        name: String,
        /// The feature that changed.
        feature: &'static str,
    },
    /// The scene's lights no longer fit the upload's light buffers (the edit writes them
    /// again).
    #[error("mesh edit: the scene's {count} lights are over the light capacity of {capacity}")]
    Lights {
        /// Lights in the scene.
        count: usize,
        /// Room in the light buffers.
        capacity: u32,
    },
    /// Binding the passes to the new geometry failed.
    #[error("mesh edit: {0}")]
    Render(#[from] RenderError),
}

impl Renderer {
    /// Adds `mesh` at the end of `scene.meshes`, uploads it into `gpu` and binds `frame`
    /// (prepared from `scene` and `gpu`) to the new geometry without compiling the graph:
    /// the next frame draws it, casts its shadows (the BVH is rebuilt) and shades it
    /// through the visibility buffer (ids and material ranges follow). Returns its index.
    ///
    /// `mesh.material` must be one of the scene's materials; a mesh that would change a
    /// scene feature the graph was compiled for (the first blended, alpha-masked,
    /// double-sided or emissive mesh) is refused. Afterwards the frame renders `scene` as
    /// it is, its lights included (they are written into `gpu` again).
    pub fn add_mesh(
        &mut self,
        frame: &mut PreparedFrame,
        scene: &mut Scene,
        gpu: &mut SceneGpu,
        mesh: Mesh,
    ) -> Result<usize, MeshEditError> {
        check_mesh(&mesh, scene)?;
        let name = mesh.name.clone();
        let before = scene.features();
        scene.meshes.push(mesh);
        let index = scene.meshes.len() - 1;
        let undo = |scene: &mut Scene| drop(scene.meshes.pop());
        if let Some(feature) = changed_feature(&before, &scene.features()) {
            undo(scene);
            return Err(MeshEditError::NewFeature {
                what: "adding",
                name,
                feature,
            });
        }
        let kept = gpu.clone();
        gpu.add_mesh(&self.ctx.device, scene, index);
        match self.rebind(frame, scene, gpu) {
            Ok(()) => Ok(index),
            Err(e) => {
                undo(scene);
                *gpu = kept;
                Err(e)
            }
        }
    }

    /// Removes `scene.meshes[index]` (later meshes shift down by one), forgets its upload
    /// in `gpu` and binds `frame` to the remaining geometry, as [`add_mesh`](Self::add_mesh)
    /// does. Returns the mesh removed.
    pub fn remove_mesh(
        &mut self,
        frame: &mut PreparedFrame,
        scene: &mut Scene,
        gpu: &mut SceneGpu,
        index: usize,
    ) -> Result<Mesh, MeshEditError> {
        if index >= scene.meshes.len() {
            return Err(MeshEditError::NoMesh {
                index,
                count: scene.meshes.len(),
            });
        }
        let before = scene.features();
        let mesh = scene.meshes.remove(index);
        if let Some(feature) = changed_feature(&before, &scene.features()) {
            let name = mesh.name.clone();
            scene.meshes.insert(index, mesh);
            return Err(MeshEditError::NewFeature {
                what: "removing",
                name,
                feature,
            });
        }
        let kept = gpu.clone();
        gpu.remove_mesh(index);
        match self.rebind(frame, scene, gpu) {
            Ok(()) => Ok(mesh),
            Err(e) => {
                scene.meshes.insert(index, mesh);
                *gpu = kept;
                Err(e)
            }
        }
    }

    /// Prepares `frame`'s compiled graph again for `scene` and `gpu` over its own
    /// resources (pipelines from the cache), replacing it only if that succeeds.
    fn rebind(
        &mut self,
        frame: &mut PreparedFrame,
        scene: &Scene,
        gpu: &mut SceneGpu,
    ) -> Result<(), MeshEditError> {
        if scene.lights.len() > gpu.light_capacity as usize {
            return Err(MeshEditError::Lights {
                count: scene.lights.len(),
                capacity: gpu.light_capacity,
            });
        }
        // The frame's light count and the passes start from the scene's lights: the
        // buffers get the scene's lights once the prepare succeeded (a
        // refused edit leaves them as the last update wrote them).
        let light_stats = frame.stats.is_some();
        let rebound = self.prepare_reusing(
            frame.graph.clone(),
            scene,
            gpu,
            frame.size,
            light_stats,
            Some(frame),
        )?;
        gpu.write_lights(&self.ctx.queue, &scene.lights)
            .map_err(|e| RenderError::Pass {
                pass: "mesh edit".into(),
                message: e.to_string(),
            })?;
        *frame = rebound;
        Ok(())
    }
}

/// The first mesh-dependent feature that differs: the graph's `when:` conditions and
/// its shaders' specialisations were decided on these.
fn changed_feature(a: &SceneFeatures, b: &SceneFeatures) -> Option<&'static str> {
    [
        (a.has_transparent, b.has_transparent, "blended meshes"),
        (a.has_alpha_mask, b.has_alpha_mask, "alpha-masked meshes"),
        (
            a.has_double_sided,
            b.has_double_sided,
            "double-sided meshes",
        ),
        (a.has_emissive, b.has_emissive, "emissive meshes"),
    ]
    .into_iter()
    .find(|(x, y, _)| x != y)
    .map(|(_, _, feature)| feature)
}

/// What a scene file's mesh is held to: a triangle list indexing its own vertices,
/// positions and texture coordinates within the documented limits, a material of the
/// scene.
fn check_mesh(m: &Mesh, scene: &Scene) -> Result<(), MeshEditError> {
    let bad = |problem: String| MeshEditError::BadMesh {
        name: m.name.clone(),
        problem,
    };
    if m.material >= scene.materials.len() {
        return Err(bad(format!(
            "material {} is not one of the scene's {} materials",
            m.material,
            scene.materials.len()
        )));
    }
    if !m.indices.len().is_multiple_of(3) {
        return Err(bad(format!(
            "{} indices do not make whole triangles",
            m.indices.len()
        )));
    }
    if let Some(i) = m.indices.iter().find(|&&i| i as usize >= m.positions.len()) {
        return Err(bad(format!(
            "index {i} is past its {} vertices",
            m.positions.len()
        )));
    }
    if let Some((v, p)) = m
        .positions
        .iter()
        .enumerate()
        .find(|(_, p)| !(p.is_finite() && p.abs().max_element() <= MAX_COORDINATE))
    {
        return Err(bad(format!(
            "vertex {v}: position {p:?} is not finite or beyond ±{MAX_COORDINATE:e} m"
        )));
    }
    if let Some((v, problem)) = crate::scene::ranges::bad_texture_coordinate(m) {
        return Err(bad(format!("vertex {v}: {problem}")));
    }
    if let Some((v, c)) = m
        .colors
        .iter()
        .enumerate()
        .find(|(_, c)| !(c.cmpge(glam::Vec4::ZERO).all() && c.cmple(glam::Vec4::ONE).all()))
    {
        return Err(bad(format!("vertex {v}: colour {c:?} is not within 0..=1")));
    }
    if [
        m.normals.len(),
        m.uvs.len(),
        m.uvs1.len(),
        m.tangents.len(),
        m.colors.len(),
    ]
    .iter()
    .any(|&n| n != 0 && n != m.positions.len())
    {
        return Err(bad(format!(
            "normals, uvs (both sets), tangents and colours must be absent or one per vertex ({} vertices)",
            m.positions.len()
        )));
    }
    Ok(())
}
