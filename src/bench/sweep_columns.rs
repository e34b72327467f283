//! The columns of a sweep row that come from a technique's own reports: tile light lists,
//! ray-cast shadows, the shadow atlas, the light linked list.

use super::report::BenchRow;
use crate::graph::{self, PassKind, ResourceDesc, SceneResource};
use crate::render::{CullingReport, SceneGpu, ShadowReport};

/// The shadow atlas columns: memory, lights shadowed and dropped, views; the pair error
/// when a ShadowCompare pass ran.
pub(super) fn set_atlas_columns(row: &mut BenchRow, result: &crate::render::FrameResult) {
    if !result.atlases.is_empty() {
        let a = &result.atlases;
        row.atlas_mib = Some(
            a.iter()
                .map(|a| (a.atlas_bytes + a.table_bytes) as f64)
                .sum::<f64>()
                / MIB,
        );
        row.atlas_shadowed = Some(a.iter().map(|a| a.shadowed.len() as u64).sum());
        row.atlas_dropped = Some(a.iter().map(|a| a.dropped.len() as u64).sum());
        row.atlas_views = Some(a.iter().map(|a| a.views as u64).sum());
        row.atlas_views_rendered = Some(a.iter().map(|a| a.views_rendered as u64).sum());
    }
    if let Some(c) = result.shadow_compare.first() {
        row.shadow_pairs = Some(c.pairs);
        row.pair_error_pcf5 = Some(c.error_pcf5());
        row.pair_error_2x2 = Some(c.error_2x2());
    }
}

const MIB: f64 = (1u64 << 20) as f64;

/// The tile light list columns of the first culling pass: storage, memory, indices held
/// and wanted, lists cut, fills that disagreed with their count.
pub(super) fn set_list_columns(row: &mut BenchRow, c: &CullingReport) {
    row.overflow_tiles = Some(c.overflowed_lists);
    row.list_storage = Some(match c.layout.storage {
        graph::ListStorage::Fixed { capacity } => format!("fixed:{capacity}"),
        graph::ListStorage::Compact { max_indices, .. } => match c.layout.scratch_per_list() {
            0 => format!("compact:{max_indices}"),
            s => format!("compact:{max_indices}:scratch:{s}"),
        },
    });
    row.list_mib = Some(c.bytes() as f64 / MIB);
    row.list_indices = Some(c.listed());
    row.list_indices_wanted = c.wanted;
    row.list_mismatched = Some(c.mismatched_lists + c.misplaced_lists);
    row.list_pass = Some(c.pass.clone());
}

/// The ray-cast shadow columns: rays, rays a second of the `ShadowRayCast` passes, drops and
/// buffer memory when a `ShadowRayJobs` pass ran; the BVH's size and build time when a pass
/// that runs reads it (the naive graph traces it in the light loop).
pub(super) fn set_shadow_columns(
    row: &mut BenchRow,
    graph: &graph::CompiledGraph,
    gpu: &SceneGpu,
    shadows: &[ShadowReport],
) {
    let runs = |kind: fn(&PassKind) -> bool| graph.passes.iter().filter(move |p| kind(&p.kind));
    if runs(|k| matches!(k, PassKind::ShadowRayJobs(_)))
        .next()
        .is_some()
    {
        let rays: u64 = shadows.iter().map(ShadowReport::rays).sum();
        row.shadow_rays = Some(rays);
        row.shadow_jobs_dropped = Some(shadows.iter().map(|s| s.jobs_dropped).sum());
        row.shadow_overflow_pixels = Some(shadows.iter().map(|s| s.overflow_pixels).sum());
        row.shadow_buffers_mib = Some(
            shadows
                .iter()
                .map(|s| (s.job_bytes + s.mask_bytes) as f64)
                .sum::<f64>()
                / MIB,
        );
        // Every ShadowRayCast pass's median, found by kind; `None` if any is untimed.
        let cast_ms: Option<Vec<f64>> = runs(|k| matches!(k, PassKind::ShadowRayCast(_)))
            .map(|p| {
                row.pass_ms
                    .iter()
                    .find(|(n, _)| p.name == *n)
                    .map(|(_, t)| t.median)
            })
            .collect();
        row.shadow_rays_per_s = cast_ms
            .map(|v| v.iter().sum::<f64>())
            .filter(|&ms| ms > 0.0)
            .map(|ms| rays as f64 / (ms * 1e-3));
    }
    let desc = &graph.checked.desc;
    let bvh_imports: Vec<&str> = desc
        .resources
        .iter()
        .filter_map(|r| match r {
            ResourceDesc::Import {
                name,
                from: SceneResource::BvhNodes,
            } => Some(name.as_str()),
            _ => None,
        })
        .collect();
    let reads_bvh = graph.passes.iter().any(|p| {
        desc.passes[p.index]
            .reads
            .iter()
            .any(|r| bvh_imports.contains(&r.as_str()))
    });
    if let (true, Some(bvh)) = (reads_bvh, gpu.built_bvh()) {
        row.bvh_mib = Some(bvh.bytes() as f64 / MIB);
        row.bvh_build_ms = Some(bvh.stats.build_time.as_secs_f64() * 1e3);
    }
}

/// The light linked list columns: pool memory, links a list pixel, scale, dropped links.
pub(super) fn set_link_columns(row: &mut BenchRow, result: &crate::render::FrameResult) {
    if let Some(l) = result.links.first() {
        row.link_mib = Some(l.bytes() as f64 / MIB);
        row.links_per_list_pixel = Some(l.links() as f64 / l.layout.pixels().max(1) as f64);
        row.link_scale = Some(l.layout.scale);
        row.links_dropped = Some(l.links_dropped);
    }
}
