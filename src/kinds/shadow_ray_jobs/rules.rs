//! `ShadowRayJobs`: one job (pixel, light) for every shadow-casting light that reaches
//! and faces a pixel, walked from its light list; compacted per workgroup; writes the
//! casting pass's indirect dispatch and clears each pixel's hit mask. Runs
//! `shaders/shadow/shadow_ray_jobs.wgsl`.
//!
//! Both shadow passes take a pixel's surface from one of two sources, decided by their
//! reads ([`SurfaceSource`]): a G-buffer's `g_position` and `g_geometric`, or a visibility
//! buffer's `visibility` ids with the merged `vertices` and `triangles` (rebuilt as
//! visibility shading rebuilds them, `shaders/shadow/surface_source.wgsl`).
//!
//! With a `ShadowAtlas` pass's `shadow_views` in its reads it emits jobs only for lights
//! without a map this frame (the table's entry 0): the hybrid, where the atlas shadows
//! the lights its policy picks and rays the rest, dropped lights included. Casters keep
//! their numbers, so a light's mask bit is where the all-rays frame puts it.

use super::contracts::InputsCtx;
use super::g_buffer::{G_GEOMETRIC, G_POSITION};
use super::shadow_atlas::SHADOW_VIEWS;
use super::visibility_buffer::VISIBILITY;
use super::visibility_shading::{TRIANGLES, VERTICES};
use super::{slot, Access, BufferLayout, Contents, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;
use crate::graph::model::{PassDesc, PassKind, ResourceDesc, SceneResource, TextureFormat};
use crate::graph::plan::FrameSize;
use crate::graph::PassRoles;
use serde::{Deserialize, Serialize};

/// `ShadowRayJobs(jobs_per_pixel: 16.0)`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShadowRayJobs {
    /// Job buffer capacity, as jobs per output pixel on average (the paper's scene casts
    /// about 7.6 a pixel); jobs past it are dropped, counted and reported (lit unshadowed).
    #[serde(default = "default_jobs_per_pixel")]
    pub jobs_per_pixel: f32,
}

fn default_jobs_per_pixel() -> f32 {
    16.0
}

pub(crate) const SHADOW_JOBS: &str = "shadow_jobs";
pub(crate) const SHADOW_MASK: &str = "shadow_mask";

/// Words before the jobs: wanted, dropped, pixels over 128 casters, unused, then the
/// indirect dispatch (x, y, z, unused).
pub(crate) const JOB_HEADER_WORDS: u64 = 8;
/// A job: pixel index, then light index | caster number << 24.
pub(crate) const JOB_WORDS: u64 = 2;
/// After the jobs, per pixel its surface as job creation found it (position, geometric
/// normal), so each of its rays reads it instead of rebuilding it.
pub(crate) const JOB_SURFACE_WORDS: u64 = 6;
/// Mask words a pixel (128 casters).
pub(crate) const MASK_WORDS: u64 = 4;

impl ShadowRayJobs {
    /// Jobs the buffer holds at `width`×`height`.
    pub fn capacity(&self, width: u32, height: u32) -> u64 {
        capacity_for(width as u64 * height as u64, self.jobs_per_pixel)
    }
}

/// Jobs a buffer of `jobs_per_pixel` holds for `pixels` pixels.
fn capacity_for(pixels: u64, jobs_per_pixel: f32) -> u64 {
    ((pixels as f64 * jobs_per_pixel as f64).ceil() as u64).max(1)
}

/// The largest `jobs_per_pixel`, in hundredths, whose job buffer for `pixels` pixels
/// takes at most `max` bytes; `None` where even the smallest does not fit.
pub(crate) fn jobs_per_pixel_within(pixels: u64, max: u64) -> Option<f32> {
    let fixed = job_buffer_bytes(0, pixels);
    let jobs = max.saturating_sub(fixed) / (4 * JOB_WORDS);
    let mut hundredths = (jobs as f64 / pixels.max(1) as f64 * 100.0).floor() as u64;
    // At most a step down: f32 rounding of the value said can add a job.
    while hundredths > 0 {
        let x = hundredths as f32 / 100.0;
        if job_buffer_bytes(capacity_for(pixels, x), pixels) <= max {
            return Some(x);
        }
        hundredths -= 1;
    }
    None
}

/// Bytes of a job buffer holding `capacity` jobs and the surfaces of `pixels` pixels.
pub(crate) fn job_buffer_bytes(capacity: u64, pixels: u64) -> u64 {
    4 * (JOB_HEADER_WORDS + JOB_WORDS * capacity + JOB_SURFACE_WORDS * pixels)
}

/// Where a shadow pass reads its pixels' surfaces from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SurfaceSource {
    /// `g_position` and `g_geometric`: a G-buffer raster's world positions and geometric
    /// normals.
    GBuffer,
    /// `visibility`, `vertices` and `triangles`: each pixel's triangle, its surface rebuilt
    /// at the pixel centre (the triangle's normal facing the eye as geometric normal).
    VisibilityBuffer,
}

/// The G-buffer source's slots.
pub const G_BUFFER_SURFACE: [&str; 2] = [G_POSITION, G_GEOMETRIC];
/// The visibility-buffer source's slots.
pub const VISIBILITY_SURFACE: [&str; 3] = [VISIBILITY, VERTICES, TRIANGLES];

/// The surface slots both shadow passes share, all optional: `check_surface_source`
/// requires one whole source. The G-buffer's come first, so graphs that fill them by
/// type order keep their meaning.
pub const SURFACE_SLOTS: [SlotSpec; 5] = [
    SlotSpec::new(
        G_POSITION,
        SlotType::ColorTexture,
        Access::Read,
        Usage::Sampled,
    )
    .optional(),
    SlotSpec::new(
        G_GEOMETRIC,
        SlotType::ColorTexture,
        Access::Read,
        Usage::Sampled,
    )
    .optional(),
    SlotSpec::new(
        VISIBILITY,
        SlotType::ColorTexture,
        Access::Read,
        Usage::Sampled,
    )
    .optional(),
    SlotSpec::new(
        VERTICES,
        SlotType::Import(SceneResource::Vertices),
        Access::Read,
        Usage::Bound,
    )
    .optional(),
    SlotSpec::new(
        TRIANGLES,
        SlotType::Import(SceneResource::Triangles),
        Access::Read,
        Usage::Bound,
    )
    .optional(),
];

/// The source a validated shadow pass reads (its reads decide; validation made sure
/// they name one whole source).
pub fn surface_source(roles: &PassRoles) -> SurfaceSource {
    if roles.slot(VISIBILITY).is_some() {
        SurfaceSource::VisibilityBuffer
    } else {
        SurfaceSource::GBuffer
    }
}

/// A shadow pass reads one whole surface source: both G-buffer textures (single-sample
/// Rgba32Float), or the ids (single-sample R32Uint) with both geometry imports.
pub(crate) fn check_surface_source(ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    let kind = ctx.pass.kind.label();
    let filled = |slots: &[&'static str]| -> Vec<&'static str> {
        slots
            .iter()
            .copied()
            .filter(|s| ctx.slot(s).is_some())
            .collect()
    };
    let (g, v) = (filled(&G_BUFFER_SURFACE), filled(&VISIBILITY_SURFACE));
    let list = |slots: &[&str]| slots.join(", ");
    // Ids not named after their slot fill the G-buffer's by type order.
    for s in G_BUFFER_SURFACE {
        if let Some(name) = ctx.slot(s).filter(|n| is_ids(ctx, n)) {
            errors.push(ctx.mismatch(
                name,
                format!("an R32Uint texture of triangle ids fills slot 'visibility', not '{s}': read it as \"visibility={name}\" (with vertices and triangles)"),
            ));
            return;
        }
    }
    if !g.is_empty() && !v.is_empty() {
        let resource = ctx.slot(v[0]).unwrap_or_default();
        errors.push(ctx.mismatch(
            resource,
            format!(
                "{kind} reads surfaces from a G-buffer ({}) or from a visibility buffer ({}), not both: it reads '{}' as {} and '{resource}' as {}",
                list(&G_BUFFER_SURFACE),
                list(&VISIBILITY_SURFACE),
                ctx.slot(g[0]).unwrap_or_default(),
                g[0],
                v[0],
            ),
        ));
        return;
    }
    if g.is_empty() && v.is_empty() {
        errors.push(ctx.bad(format!(
            "{kind} needs the pixels' surfaces in reads: {} from a G-buffer, or {} from a visibility buffer",
            list(&G_BUFFER_SURFACE),
            list(&VISIBILITY_SURFACE)
        )));
        return;
    }
    let (all, got, source): (&[&str], _, _) = if v.is_empty() {
        (&G_BUFFER_SURFACE, &g, "a G-buffer")
    } else {
        (&VISIBILITY_SURFACE, &v, "a visibility buffer")
    };
    let missing: Vec<&str> = all.iter().copied().filter(|s| !got.contains(s)).collect();
    if !missing.is_empty() {
        errors.push(ctx.bad(format!(
            "{kind} reads surfaces from {source} ({}): {} missing from its reads",
            list(got),
            list(&missing)
        )));
        return;
    }
    if v.is_empty() {
        for s in G_BUFFER_SURFACE {
            let Some(name) = ctx.slot(s) else { continue };
            if !ctx.is_single_rgba32f(name) {
                errors.push(ctx.mismatch(
                    name,
                    "ray-cast shadows read world positions and geometric normals from single-sample Rgba32Float G-buffer textures (not the packed G-buffer)",
                ));
            }
        }
    } else {
        super::visibility_buffer::check_ids(ctx, errors);
    }
}

fn is_ids(ctx: &KindCtx, name: &str) -> bool {
    matches!(
        ctx.graph.resources.get(name),
        Some(ResourceDesc::Texture {
            format: TextureFormat::R32Uint,
            ..
        })
    )
}

pub(crate) const SLOTS: &[SlotSpec] = &[
    SURFACE_SLOTS[0],
    SURFACE_SLOTS[1],
    SURFACE_SLOTS[2],
    SURFACE_SLOTS[3],
    SURFACE_SLOTS[4],
    super::LIGHT_GEOMETRY_READ,
    super::LIGHT_PROPERTIES_READ,
    SlotSpec::new(
        slot::LIGHT_LISTS,
        SlotType::Buffer,
        Access::Read,
        Usage::Bound,
    )
    .needs(&[Contents::LightLists]),
    SlotSpec::new(SHADOW_JOBS, SlotType::Buffer, Access::Write, Usage::Bound),
    SlotSpec::new(SHADOW_MASK, SlotType::Buffer, Access::Write, Usage::Bound),
    // The hybrid: lights with an atlas map get no job.
    super::SHADOW_VIEWS_READ,
];

/// The `ShadowRayJobs` passes that read the view table `views` (they cast rays only for
/// lights without a map in it).
pub(crate) fn jobs_reading_views<'a>(
    ctx: &'a InputsCtx,
    views: &'a str,
) -> impl Iterator<Item = &'a PassDesc> + 'a {
    ctx.passes()
        .filter(move |(p, r)| {
            matches!(p.kind, PassKind::ShadowRayJobs(_)) && r.slot(SHADOW_VIEWS) == Some(views)
        })
        .map(|(p, _)| p)
}

/// A mask whose jobs skip the atlas's lights holds no answer for them: every pass that
/// reads it must be a shading pass sampling the same atlas for those lights (forward,
/// deferred or visibility shading: the hybrid).
fn check_mask_readers(ctx: &InputsCtx, errors: &mut Vec<GraphError>) {
    let (Some(views), Some(mask)) = (ctx.slot(SHADOW_VIEWS), ctx.slot(SHADOW_MASK)) else {
        return;
    };
    for (p, r) in ctx.passes() {
        if r.slot(SHADOW_MASK) != Some(mask) || p.writes.iter().any(|w| w == mask) {
            continue;
        }
        let hybrid_reader = matches!(
            p.kind,
            PassKind::VisibilityShading(_)
                | PassKind::ForwardShading(_)
                | PassKind::DeferredShading(_)
        );
        let problem = if !hybrid_reader {
            format!(
                "'{}' ({}) reads '{mask}', whose jobs pass '{}' casts no rays for lights with a map in '{views}'; only forward, deferred and visibility shading read such a mask (sampling the atlas for those lights)",
                p.name,
                p.kind.label(),
                ctx.pass().name
            )
        } else if r.slot(SHADOW_VIEWS) != Some(views) {
            format!(
                "'{}' reads '{mask}', whose jobs pass '{}' casts no rays for lights with a map in '{views}': read '{views}' and its atlas too, so those lights sample the atlas",
                p.name,
                ctx.pass().name
            )
        } else {
            continue;
        };
        errors.push(ctx.mismatch(mask, problem));
    }
}

pub(crate) fn check(p: &ShadowRayJobs, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    if !(p.jobs_per_pixel.is_finite() && p.jobs_per_pixel > 0.0 && p.jobs_per_pixel <= 128.0) {
        errors.push(ctx.bad(format!(
            "jobs_per_pixel {} must be in (0, 128] (at most 128 casters a pixel)",
            p.jobs_per_pixel
        )));
    }
    check_surface_source(ctx, errors);
}

impl KindRules for ShadowRayJobs {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(self, ctx, errors)
    }
    fn check_inputs(&self, ctx: &InputsCtx, errors: &mut Vec<GraphError>) {
        check_mask_readers(ctx, errors)
    }
    fn buffer_layout(&self, slot: &str, frame: FrameSize) -> Option<BufferLayout> {
        match slot {
            SHADOW_JOBS => Some(BufferLayout::ShadowJobs {
                capacity: self.capacity(frame.width, frame.height),
                pixels: frame.width as u64 * frame.height as u64,
            }),
            SHADOW_MASK => Some(BufferLayout::ShadowMask {
                pixels: frame.width as u64 * frame.height as u64,
            }),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{job_buffer_bytes, jobs_per_pixel_within, ShadowRayJobs};
    use crate::graph::kinds::test_support::errors;

    /// The jobs_per_pixel said to fit does, and a hundredth more does not: lavapipe's
    /// 128 MiB at 1920×1080 (the default graph's 16 take 315 MB), a bound met exactly,
    /// frames too small for a hundredth to add a job, and one whose surfaces alone do not
    /// fit.
    #[test]
    fn the_jobs_per_pixel_said_to_fit_fits() {
        let bytes = |w: u32, h: u32, x: f32| {
            let jobs = ShadowRayJobs { jobs_per_pixel: x };
            job_buffer_bytes(jobs.capacity(w, h), w as u64 * h as u64)
        };
        assert_eq!(bytes(1920, 1080, 16.0), 315_187_232);
        let lavapipe = 128 << 20;
        assert_eq!(jobs_per_pixel_within(1920 * 1080, lavapipe), Some(5.09));
        let exact = bytes(640, 360, 2.5);
        for (w, h, max) in [
            (1920, 1080, lavapipe),
            (640, 360, exact),
            (640, 360, exact - 1),
            (7, 3, 1000),
            (1, 1, 100),
        ] {
            let x = jobs_per_pixel_within(w as u64 * h as u64, max).unwrap();
            assert!(bytes(w, h, x) <= max, "{w}x{h} {max}: {x}");
            assert!(bytes(w, h, x + 0.01) > max, "{w}x{h} {max}: {x} is not the largest");
        }
        assert_eq!(jobs_per_pixel_within(640 * 360, exact), Some(2.5));
        assert_eq!(jobs_per_pixel_within(1920 * 1080, 40 << 20), None);
    }

    #[test]
    fn checks_capacity_and_inputs() {
        let e = errors(
            r#"Pass(name: "g", kind: GBuffer, reads: ["geometry"], writes: ["depth", "pos", "nrm", "geo"]),
               Pass(name: "c", kind: LightCulling(tile: 16), reads: ["depth", "lg"], writes: ["lists"]),
               Pass(name: "j", kind: ShadowRayJobs(jobs_per_pixel: 0.0), reads: ["pos", "geo", "lg", "lp", "lists"], writes: ["jobs", "mask"])"#,
            "pos",
        );
        assert!(e.contains("jobs_per_pixel 0 must be in (0, 128]"), "{e}");
        let e = errors(
            r#"Pass(name: "g", kind: GBuffer, reads: ["geometry"], writes: ["depth", "pos", "nrm", "geo"]),
               Pass(name: "j", kind: ShadowRayJobs(), reads: ["pos", "geo", "lg", "lp"], writes: ["jobs", "mask"])"#,
            "pos",
        );
        assert!(
            e.contains("ShadowRayJobs needs a buffer in reads (slot 'light_lists')"),
            "{e}"
        );
    }
}
