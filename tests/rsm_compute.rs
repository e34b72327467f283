//! `ReflectiveShadowMaps(raster: Compute)` against the hardware pass it replaces: the
//! same maps (depth, normal, flux, position) in every view's tile, the same VPLs, the
//! same image. On lavapipe, tiny renders.

mod common;

use common::{graph_text, max_rel_diff, renderer};
use lightgraph::graph::{self, FrameSize};
use lightgraph::render::{FrameResult, PreparedFrame, Renderer, SceneGpu};
use lightgraph::scene::{self, Scene};
use lightgraph::shader::ShaderLibrary;
use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
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
    gpu: SceneGpu,
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
    Ok(Frame {
        prepared,
        result,
        gpu,
    })
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

/// The largest difference of `a` from `b`, relative to the larger magnitude among the
/// two (at least 1e-6, so zeros compare absolutely).
fn rel_diff(a: [f32; 4], b: [f32; 4]) -> f32 {
    let scale = a.iter().chain(&b).fold(1e-6f32, |m, v| m.max(v.abs()));
    a.iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs() / scale)
        .fold(0.0, f32::max)
}

/// Attributes of a texel that the two rasterizers take from the same triangle agree to
/// this, relative to their largest component: the hardware interpolates the vertex
/// attributes at the texel centre, the compute resolve rebuilds them from
/// perspective-correct barycentrics (visibility/surface.wgsl), so they differ by the
/// two interpolations' rounding (measured on lavapipe at most 4.0e-5 for the normalized
/// normal, 1.1e-5 for the position, 1.7e-6 for the flux, over the atrium's large
/// floor and wall triangles); another surface's attributes are off by far more.
const SAME_TRIANGLE: f32 = 1e-4;
/// Depths of a texel from the same triangle agree to 4 ulps of 1.0: the hardware
/// interpolates z at the texel centre, the compute raster evaluates the triangle's depth
/// plane from its first vertex (shadow/atlas_raster.wgsl); measured 2 ulps.
const DEPTH_ULPS: f32 = 4.0 * f32::EPSILON;

/// How the compute maps differ from the hardware ones over the views' tiles.
#[derive(Debug)]
struct MapDiff {
    texels: usize,
    covered: usize,
    /// Texels covered in one map and not the other.
    coverage: usize,
    /// Covered in both, some attribute off by more than rounding: another triangle
    /// was nearest (a silhouette or a tie the two rasterizers broke differently).
    other_triangle: usize,
    /// Among the rest: the largest relative difference of the normal, the flux and the
    /// position, and the largest depth difference.
    attribute: [f32; 3],
    depth: f32,
}

fn compare(h: &Maps, c: &Maps) -> MapDiff {
    assert_eq!(h.tiles, c.tiles);
    assert!(!h.tiles.is_empty());
    assert_eq!((h.width, h.tile), (c.width, c.tile));
    assert_eq!(h.depth.len(), c.depth.len());
    let mut d = MapDiff {
        texels: 0,
        covered: 0,
        coverage: 0,
        other_triangle: 0,
        attribute: [0.0; 3],
        depth: 0.0,
    };
    for i in h.texels() {
        d.texels += 1;
        let (hc, cc) = (h.depth[i] < 1.0, c.depth[i] < 1.0);
        if hc != cc {
            d.coverage += 1;
            continue;
        }
        let attributes = [
            (h.normal[i], c.normal[i]),
            (h.flux[i], c.flux[i]),
            (h.position[i], c.position[i]),
        ];
        if !hc {
            // Nothing drawn: both as cleared, exactly.
            assert_eq!((h.depth[i], c.depth[i]), (1.0, 1.0), "texel {i}");
            for (a, b) in attributes {
                assert_eq!((a, b), ([0.0; 4], [0.0; 4]), "empty texel {i}");
            }
            continue;
        }
        d.covered += 1;
        let diffs = attributes.map(|(a, b)| rel_diff(a, b));
        if diffs.iter().any(|&x| x > SAME_TRIANGLE) {
            d.other_triangle += 1;
            continue;
        }
        for (worst, x) in d.attribute.iter_mut().zip(diffs) {
            *worst = worst.max(x);
        }
        d.depth = d.depth.max((h.depth[i] - c.depth[i]).abs());
    }
    d
}

/// The Cornell box (one indirect point light: six cube faces, both faces of its walls in
/// view) and the atrium (four indirect spot lights, columns and arches), each through the
/// graph that draws its maps with either raster.
const CASES: [(&str, &str); 2] = [
    ("cornell_indirect.ron", "indirect_vpl.ron"),
    ("atrium_indirect.ron", "visibility_indirect_vpl.ron"),
];

/// The maps are independent of the frame's size: a tiny frame.
const W: u32 = 32;
const H: u32 = 24;

#[test]
fn compute_maps_equal_the_hardware_maps() {
    let mut r = renderer();
    for (scene, graph) in CASES {
        let s = load(scene);
        let text = graph_text(graph);
        let hw = prepare(&mut r, &with_raster(&text, "Hardware"), &s, W, H).unwrap();
        let cs = prepare(&mut r, &with_raster(&text, "Compute"), &s, W, H).unwrap();
        let d = compare(&maps(&r, &hw), &maps(&r, &cs));
        println!("{scene}: {d:?}");
        // Most of the tiles are covered (the test compares surfaces, not clears).
        assert!(d.covered * 2 > d.texels, "{scene}: {d:?}");
        // Both rasterizers snap to 1/256 texel and take the top-left rule, so they
        // cover the same texels with the same triangles; measured: no texel differs on
        // lavapipe. Silhouette texels whose edge test rounds differently on another
        // rasterizer may: at most 1 in 500 of the tiles' texels.
        let edges = d.coverage + d.other_triangle;
        assert!(
            edges * 500 <= d.texels,
            "{scene}: {edges} texels differ: {d:?}"
        );
        assert!(d.depth <= DEPTH_ULPS, "{scene}: {d:?}");
    }
}

/// The VPLs `VplSpawn` appended (light geometry and properties, 8 words each after the
/// scene's lights).
fn vpls(r: &Renderer, f: &Frame, lights: usize) -> Vec<[f32; 16]> {
    let read = |name: &str| {
        let bytes = f.prepared.read_buffer(r, name).unwrap();
        bytemuck::cast_slice::<u8, f32>(&bytes).to_vec()
    };
    let (g, p) = (read("light_geometry"), read("light_properties"));
    let n = f.result.vpls[0].spawned as usize;
    (lights..lights + n)
        .map(|i| {
            let mut v = [0.0; 16];
            v[..8].copy_from_slice(&g[8 * i..8 * i + 8]);
            v[8..].copy_from_slice(&p[8 * i..8 * i + 8]);
            v
        })
        .collect()
}

#[test]
fn the_vpls_and_the_image_equal_the_hardware_paths() {
    let mut r = renderer();
    for (scene, graph) in CASES {
        let s = load(scene);
        let text = graph_text(graph);
        let hw = prepare(&mut r, &with_raster(&text, "Hardware"), &s, W, H).unwrap();
        let cs = prepare(&mut r, &with_raster(&text, "Compute"), &s, W, H).unwrap();
        let (a, b) = (&hw.result.vpls[0], &cs.result.vpls[0]);
        assert_eq!((a.spawned, a.dropped), (b.spawned, b.dropped), "{scene}");
        assert!(a.spawned > 32, "{scene}: {a:?}");
        // A VPL is a flux-weighted average of its block's texels: same texels to 2e-5
        // (above) give the same VPLs to about that (measured below 1e-5).
        // Appended in the order their threads took slots: compared sorted by position
        // (rounded to 1e-3 m, far coarser than their differences, finer than their
        // spacing).
        let sorted = |f: &Frame| {
            let mut v = vpls(&r, f, s.lights.len());
            let key = |v: &[f32; 16]| [0, 1, 2].map(|k| (v[k] * 1e3).round() as i64);
            v.sort_by_key(key);
            v
        };
        let (va, vb) = (sorted(&hw), sorted(&cs));
        let mut worst = 0.0f32;
        for (x, y) in va.iter().zip(&vb) {
            for k in 0..4 {
                let q = |v: &[f32; 16]| [v[4 * k], v[4 * k + 1], v[4 * k + 2], v[4 * k + 3]];
                worst = worst.max(rel_diff(q(x), q(y)));
            }
        }
        assert!(worst <= 5e-5, "{scene}: VPLs differ by {worst:e}");
        // The image: every pixel sums the VPLs, each within the bound above.
        assert_eq!(hw.result.image.len(), (W * H) as usize);
        assert_eq!(cs.result.image.len(), hw.result.image.len());
        let (image, px) = max_rel_diff(&hw.result.image, &cs.result.image);
        println!("{scene}: VPLs {worst:e}, image {image:e} at {px}");
        assert!(
            image <= 5e-5,
            "{scene}: image differs by {image:e} at pixel {px}"
        );
    }
}

/// The Cornell box with a striped, alpha-masked quad held over its floor (a mip-mapped
/// checker whose alpha is 255 and 20 in stripes, cut at 0.5); `solid`: the same quad
/// opaque.
fn masked_quad_scene(solid: bool) -> Scene {
    let mut s = load("cornell_indirect.ron");
    common::textured::push_striped_quad(
        &mut s,
        "stripes",
        glam::Vec3::new(0.0, 0.3, 0.0),
        glam::Vec3::X * 0.7,
        glam::Vec3::Z * 0.7,
        solid,
    );
    s
}

/// Alpha-masked casters are alpha-tested by the compute raster (a run of the material's
/// own, in its depth pass and its id pass): the maps equal the hardware pass's, whose
/// fragment stage discards below the cutoff, to the same bound as opaque maps; the mask
/// shows through (the floor under the cut stripes: many texels differ from the solid
/// quad's maps); the frames agree to the order VPLs are summed in (5e-5, as above).
#[test]
fn alpha_masked_casters_are_alpha_tested_in_compute() {
    let mut r = renderer();
    let s = masked_quad_scene(false);
    let text = graph_text("indirect_vpl.ron");
    let hw = prepare(&mut r, &with_raster(&text, "Hardware"), &s, W, H).unwrap();
    let cs = prepare(&mut r, &with_raster(&text, "Compute"), &s, W, H).unwrap();
    let (mh, mc) = (maps(&r, &hw), maps(&r, &cs));
    let d = compare(&mh, &mc);
    println!("masked: {d:?}");
    assert!(d.covered * 2 > d.texels, "{d:?}");
    let edges = d.coverage + d.other_triangle;
    assert!(edges * 500 <= d.texels, "{edges} texels differ: {d:?}");
    assert!(d.depth <= DEPTH_ULPS, "{d:?}");
    let solid = prepare(
        &mut r,
        &with_raster(&text, "Compute"),
        &masked_quad_scene(true),
        W,
        H,
    )
    .unwrap();
    let cut = compare(&maps(&r, &solid), &mc);
    println!("masked against solid: {cut:?}");
    assert!(
        cut.other_triangle > 100,
        "the mask shows the floor at {} texels",
        cut.other_triangle
    );
    assert_eq!(cs.result.image.len(), (W * H) as usize);
    assert_eq!(cs.result.image.len(), hw.result.image.len());
    let (image, px) = max_rel_diff(&hw.result.image, &cs.result.image);
    assert!(image <= 5e-5, "image differs by {image:e} at pixel {px}");
}

/// The Cornell box (which has no uvs) with a checker-textured quad on its floor: the
/// resolve samples it with the uv footprint of the texel's 2×2 quad, as the fragment
/// stage's implicit derivatives do.
#[test]
fn a_textured_floor_reflects_the_same_flux() {
    use common::textured::{checker, quad};
    use lightgraph::scene::SurfaceMaterial;
    let mut r = renderer();
    let mut s = load("cornell_indirect.ron");
    let tex = std::sync::Arc::new(checker("checker", 64, 8, [230, 120, 40], [40, 90, 200]));
    s.materials.push(SurfaceMaterial {
        name: "checker_floor".into(),
        base_color_texture: Some(tex),
        ..Default::default()
    });
    let m = s.materials.len() - 1;
    s.meshes.push(quad(
        "checker_floor",
        glam::Vec3::new(0.0, 0.01, 0.0),
        glam::Vec3::X * 0.7,
        glam::Vec3::Z * 0.7,
        m,
    ));
    let text = graph_text("indirect_vpl.ron");
    let hw = prepare(&mut r, &with_raster(&text, "Hardware"), &s, W, H).unwrap();
    let cs = prepare(&mut r, &with_raster(&text, "Compute"), &s, W, H).unwrap();
    let (mh, mc) = (maps(&r, &hw), maps(&r, &cs));
    let d = compare(&mh, &mc);
    println!("textured: {d:?}");
    // The checker shows in the flux: its two colours' red/blue ratios differ by 30×.
    let ratios: Vec<f32> = mh
        .texels()
        .into_iter()
        .filter(|&i| mh.flux[i][2] > 0.0)
        .map(|i| mh.flux[i][0] / mh.flux[i][2])
        .collect();
    let (lo, hi) = ratios
        .iter()
        .fold((f32::MAX, 0.0f32), |(l, h), &x| (l.min(x), h.max(x)));
    assert!(hi > 10.0 * lo, "no checker in the flux: ratios {lo}..{hi}");
    let edges = d.coverage + d.other_triangle;
    assert!(edges * 500 <= d.texels, "{edges} texels differ: {d:?}");
    assert!(d.depth <= DEPTH_ULPS, "{d:?}");
}

/// A moved light (`update_lights`) lays the compute pass's views and jobs out again:
/// the maps equal a fresh prepare's at the new place, exactly (the same work in the
/// same order).
#[test]
fn a_moved_light_rasterizes_its_new_views() {
    let mut r = renderer();
    let s = load("cornell_indirect.ron");
    let text = with_raster(&graph_text("indirect_vpl.ron"), "Compute");
    let start = prepare(&mut r, &text, &s, W, H).unwrap();
    let before = maps(&r, &start);
    let mut moved = s.clone();
    moved.lights[0].position.x += 0.5;
    start
        .prepared
        .update_lights(&r, &start.gpu, &moved.lights)
        .unwrap();
    start.prepared.render(&r).unwrap();
    let after = maps(&r, &start);
    let fresh = prepare(&mut r, &text, &moved, W, H).unwrap();
    let fresh = maps(&r, &fresh);
    assert_eq!(after.tiles, fresh.tiles);
    let mut changed = 0;
    for i in fresh.texels() {
        assert_eq!(
            after.depth[i].to_bits(),
            fresh.depth[i].to_bits(),
            "texel {i}"
        );
        assert_eq!(after.normal[i], fresh.normal[i], "texel {i}");
        assert_eq!(after.flux[i], fresh.flux[i], "texel {i}");
        assert_eq!(after.position[i], fresh.position[i], "texel {i}");
        changed += usize::from(after.position[i] != before.position[i]);
    }
    // The move changed what the views see (the test can fail).
    assert!(
        changed * 2 > fresh.texels().len(),
        "{changed} texels changed"
    );
}
