//! What a technique adds to a frame's memory, from the resource plan (no GPU): the
//! textures and buffers of its passes, counted only where they do not share memory with
//! another resource (aliasing), and for MSAA the samples past the first.

use super::model::TextureFormat;
use super::plan::PhysicalDesc;
use super::CompiledGraph;

/// One resource a technique uses.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MemoryItem {
    /// The graph resource's name.
    pub resource: String,
    /// Bytes of its physical texture or buffer.
    pub bytes: u64,
    /// Bytes the technique adds for it: 0 where it shares another resource's memory;
    /// for MSAA, the samples past the first.
    pub added: u64,
    /// The resource whose memory it shares, if any.
    pub shares_with: Option<String>,
}

/// What one technique (transparency, MSAA) adds to a frame's memory, resource by resource.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TechniqueMemory {
    /// "transparency" or "MSAA 4×".
    pub technique: String,
    /// The resources its passes use.
    pub items: Vec<MemoryItem>,
}

impl TechniqueMemory {
    /// Bytes the technique adds in all.
    pub fn added(&self) -> u64 {
        self.items.iter().map(|i| i.added).sum()
    }
}

pub(crate) fn bytes_per_texel(format: TextureFormat) -> u64 {
    match format {
        TextureFormat::Rgba8Unorm
        | TextureFormat::R32Float
        | TextureFormat::R32Uint
        | TextureFormat::Depth32Float => 4,
        TextureFormat::Rgba16Float | TextureFormat::Rg32Float => 8,
        TextureFormat::Rgba32Float => 16,
        TextureFormat::Depth16Unorm => 2,
    }
}

pub(crate) fn physical_bytes(desc: &PhysicalDesc) -> u64 {
    match *desc {
        PhysicalDesc::Texture {
            format,
            width,
            height,
            samples,
        } => bytes_per_texel(format) * width as u64 * height as u64 * samples as u64,
        PhysicalDesc::Buffer { bytes } => bytes,
    }
}

/// The running passes' techniques with their memory: transparency (what TransparentDepth
/// passes and transparent culling write) and MSAA (every multisampled texture).
pub fn by_technique(graph: &CompiledGraph) -> Vec<TechniqueMemory> {
    let mut transparent: Vec<&str> = Vec::new();
    for p in &graph.passes {
        let is_transparent = p
            .kind
            .rules()
            .is_some_and(|rules| rules.writes_transparency(&p.roles));
        if is_transparent {
            let desc = &graph.checked.desc.passes[p.index];
            for w in &desc.writes {
                if !transparent.contains(&w.as_str()) {
                    transparent.push(w);
                }
            }
        }
    }
    let plan = &graph.plan;
    let item = |name: &str, added: &dyn Fn(&PhysicalDesc, u64) -> u64| {
        let r = plan.get(name)?;
        let physical = &plan.physical[r.physical];
        let bytes = physical_bytes(&physical.desc);
        let shares_with = physical
            .serves
            .iter()
            .find(|s| *s != name && !transparent.contains(&s.as_str()))
            .map(|s| s.to_string());
        Some(MemoryItem {
            resource: name.to_string(),
            bytes,
            added: if shares_with.is_some() {
                0
            } else {
                added(&physical.desc, bytes)
            },
            shares_with,
        })
    };
    let mut out = Vec::new();
    let items: Vec<MemoryItem> = transparent
        .iter()
        .filter_map(|n| item(n, &|_, b| b))
        .collect();
    if !items.is_empty() {
        out.push(TechniqueMemory {
            technique: "transparency".into(),
            items,
        });
    }
    let mut msaa: Vec<(u32, MemoryItem)> = Vec::new();
    for r in &plan.resources {
        if let PhysicalDesc::Texture { samples, .. } = plan.physical[r.physical].desc {
            if samples > 1 {
                let extra = |_: &PhysicalDesc, b: u64| b - b / samples as u64;
                if let Some(i) = item(&r.name, &extra) {
                    msaa.push((samples, i));
                }
            }
        }
    }
    let mut counts: Vec<u32> = msaa.iter().map(|(s, _)| *s).collect();
    counts.dedup();
    for n in counts {
        out.push(TechniqueMemory {
            technique: format!("MSAA {n}×"),
            items: msaa
                .iter()
                .filter(|(s, _)| *s == n)
                .map(|(_, i)| i.clone())
                .collect(),
        });
    }
    out
}

/// Bytes of every physical texture and buffer of the plan.
pub fn total_bytes(graph: &CompiledGraph) -> u64 {
    graph
        .plan
        .physical
        .iter()
        .map(|p| physical_bytes(&p.desc))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{check_text, compile, FrameSize};
    use crate::shader::ShaderLibrary;

    fn compiled(file: &str, transparent: bool) -> CompiledGraph {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("graphs")
            .join(file);
        let text = std::fs::read_to_string(&path).unwrap();
        let checked = check_text(&path, &text, &ShaderLibrary::builtin()).unwrap();
        let features = crate::scene::SceneFeatures {
            has_transparent: transparent,
            has_lights: true,
            ..Default::default()
        };
        let size = FrameSize {
            width: 100,
            height: 50,
            lights: 64,
        };
        compile(checked, &features, size)
    }

    #[test]
    fn transparency_and_msaa_count_what_they_add() {
        let t = by_technique(&compiled("transparent_msaa.ron", true));
        assert_eq!(t.len(), 2, "{t:?}");
        assert_eq!(t[0].technique, "transparency");
        let depth = &t[0].items[0];
        assert_eq!(depth.resource, "transparent_depth");
        assert_eq!(
            (depth.bytes, depth.added),
            (4 * 100 * 50 * 4, 4 * 100 * 50 * 4)
        );
        // The transparent lists reuse the opaque lists' memory (disjoint lifetimes).
        let lists = &t[0].items[1];
        assert_eq!(lists.resource, "transparent_lists");
        assert_eq!(
            (lists.added, lists.shares_with.as_deref()),
            (0, Some("light_lists"))
        );
        assert_eq!(t[1].technique, "MSAA 4×");
        let hdr = t[1]
            .items
            .iter()
            .find(|i| i.resource == "hdr_msaa")
            .unwrap();
        assert_eq!(
            (hdr.bytes, hdr.added),
            (16 * 100 * 50 * 4, 16 * 100 * 50 * 3)
        );
        // Without blended meshes, no transparency memory; plain Forward+ has neither.
        let t = by_technique(&compiled("transparent.ron", false));
        assert!(t.is_empty(), "{t:?}");
        assert!(by_technique(&compiled("forward_plus.ron", false)).is_empty());
    }

    #[test]
    fn deferred_msaa_counts_its_multisampled_g_buffer() {
        // The depth and the four G-buffer textures at 4×; the output stays single-sample and
        // there is no multisampled colour texture (the shading pass resolves).
        let t = by_technique(&compiled("tiled_deferred_msaa.ron", false));
        assert_eq!(t.len(), 1, "{t:?}");
        assert_eq!(t[0].technique, "MSAA 4×");
        let mut items: Vec<(&str, u64, u64)> = t[0]
            .items
            .iter()
            .map(|i| (i.resource.as_str(), i.bytes, i.added))
            .collect();
        items.sort();
        let px = 100 * 50;
        assert_eq!(
            items,
            [
                ("depth_msaa", 4 * px * 4, 4 * px * 3),
                ("g_normal", 16 * px * 4, 16 * px * 3),
                ("g_position", 16 * px * 4, 16 * px * 3),
                ("g_surface", 16 * px * 4, 16 * px * 3),
                ("g_uv1", 16 * px * 4, 16 * px * 3),
                ("g_uv1_grad", 16 * px * 4, 16 * px * 3),
                ("g_uv_grad", 16 * px * 4, 16 * px * 3),
            ]
        );
        let t = by_technique(&compiled("tiled_deferred_msaa_8x.ron", false));
        assert_eq!(t[0].technique, "MSAA 8×");
        assert_eq!(t[0].added(), (4 + 6 * 16) * px * 7);
    }
}
