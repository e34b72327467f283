//! Meshes, cameras, KHR_lights_punctual lights and the nodes that place them.

use super::desc::{NodeDesc, PrimitiveDesc};
use super::{index, position, GltfWriter};
use glam::{Vec2, Vec3};
use gltf::json;
use gltf::json::extensions::scene::khr_lights_punctual as punctual;
use gltf::json::mesh::{Mode, Semantic};
use gltf::json::validation::Checked::Valid;
use std::collections::BTreeMap;

impl GltfWriter {
    /// Adds a mesh of these primitives; returns the mesh index.
    ///
    /// # Panics
    ///
    /// When a primitive's `mode` is not one of glTF's seven (0..=6).
    pub fn add_mesh(&mut self, name: &str, prims: &[PrimitiveDesc]) -> usize {
        let primitives = prims
            .iter()
            .map(|p| {
                let mut attributes = BTreeMap::new();
                attributes.insert(Valid(Semantic::Positions), index(p.positions));
                for (semantic, accessor) in [
                    (Semantic::Normals, p.normals),
                    (Semantic::TexCoords(0), p.uvs),
                    (Semantic::TexCoords(1), p.uvs1),
                    (Semantic::Tangents, p.tangents),
                    (Semantic::Colors(0), p.colors),
                ] {
                    if let Some(a) = accessor {
                        attributes.insert(Valid(semantic), index(a));
                    }
                }
                json::mesh::Primitive {
                    attributes,
                    extensions: None,
                    extras: Default::default(),
                    indices: p.indices.map(index),
                    material: p.material.map(index),
                    mode: Valid(p.mode.map_or(Mode::Triangles, mode)),
                    targets: None,
                }
            })
            .collect();
        position(self.root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: Some(name.to_string()),
            primitives,
            weights: None,
        }))
    }

    /// Adds a mesh of one primitive from raw arrays (normals/uvs optional, indexed or not).
    pub fn add_simple_mesh(
        &mut self,
        name: &str,
        positions: &[Vec3],
        normals: Option<&[Vec3]>,
        uvs: Option<&[Vec2]>,
        indices: Option<&[u32]>,
        material: Option<usize>,
    ) -> usize {
        let prim = PrimitiveDesc {
            positions: self.add_positions(positions),
            normals: normals.map(|n| self.add_vec3(n)),
            uvs: uvs.map(|u| self.add_vec2(u)),
            uvs1: None,
            tangents: None,
            colors: None,
            indices: indices.map(|i| self.add_indices(i)),
            material,
            mode: None,
        };
        self.add_mesh(name, &[prim])
    }

    /// Adds a perspective camera (`yfov` in radians, `znear`, optional `zfar`; infinite when
    /// `None`); returns its index.
    pub fn add_camera(&mut self, yfov: f32, znear: f32, zfar: Option<f32>) -> usize {
        position(self.root.push(json::Camera {
            name: None,
            orthographic: None,
            perspective: Some(json::camera::Perspective {
                aspect_ratio: None,
                yfov,
                zfar,
                znear,
                extensions: None,
                extras: Default::default(),
            }),
            type_: Valid(json::camera::Type::Perspective),
            extensions: None,
            extras: Default::default(),
        }))
    }

    /// A KHR_lights_punctual light. `spot`: (inner, outer) cone angles in radians.
    pub fn add_light(
        &mut self,
        name: &str,
        color: Vec3,
        intensity: f32,
        range: Option<f32>,
        spot: Option<(f32, f32)>,
    ) -> usize {
        let light = punctual::Light {
            color: color.to_array(),
            extensions: None,
            extras: Default::default(),
            intensity,
            name: Some(name.to_string()),
            range,
            spot: spot.map(|(inner, outer)| punctual::Spot {
                inner_cone_angle: inner,
                outer_cone_angle: outer,
            }),
            type_: Valid(if spot.is_some() {
                punctual::Type::Spot
            } else {
                punctual::Type::Point
            }),
        };
        let lights = &mut self
            .root
            .extensions
            .get_or_insert_with(Default::default)
            .khr_lights_punctual
            .get_or_insert_with(|| json::extensions::root::KhrLightsPunctual { lights: Vec::new() })
            .lights;
        position(json::Index::push(lights, light))
    }

    /// Adds a node; returns its index (make it a root with [`GltfWriter::add_root`], or a
    /// child of another node).
    pub fn add_node(&mut self, n: &NodeDesc) -> usize {
        position(
            self.root.push(json::Node {
                camera: n.camera.map(index),
                children: (!n.children.is_empty())
                    .then(|| n.children.iter().copied().map(index).collect()),
                extensions: n.light.map(|l| json::extensions::scene::Node {
                    khr_lights_punctual: Some(punctual::KhrLightsPunctual { light: index(l) }),
                    ..Default::default()
                }),
                mesh: n.mesh.map(index),
                name: n.name.clone(),
                rotation: n
                    .rotation
                    .map(|r| json::scene::UnitQuaternion(r.to_array())),
                scale: n.scale.map(|s| s.to_array()),
                translation: n.translation.map(|t| t.to_array()),
                ..Default::default()
            }),
        )
    }
}

/// glTF's primitive mode `code` (0 points .. 6 triangle fan).
fn mode(code: u32) -> Mode {
    match code {
        0 => Mode::Points,
        1 => Mode::Lines,
        2 => Mode::LineLoop,
        3 => Mode::LineStrip,
        4 => Mode::Triangles,
        5 => Mode::TriangleStrip,
        6 => Mode::TriangleFan,
        _ => panic!("primitive mode {code} is not one of glTF's 0..=6"),
    }
}
