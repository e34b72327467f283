//! `GBuffer`: the scene's geometry into one packed Rgba32Float texture (view depth,
//! octahedral normal, material) or two (world position with the material in w, shading
//! normal), plus optionally the surface the material samples (`g_surface`: uv, tangent;
//! `g_uv_grad`: the uv's screen derivatives) for textured and anisotropic materials, and
//! the second uv set and its derivatives (`g_uv1`, `g_uv1_grad`) for materials that
//! sample with glTF `TEXCOORD_1`.
//! After a depth prepass it only tests depth. Runs `shaders/forward/forward.wgsl` with
//! `GBUFFER`.

use super::{slot, Access, KindCtx, KindRules, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;

pub(crate) const G_POSITION: &str = "g_position";
pub(crate) const G_NORMAL: &str = "g_normal";
/// Geometric (face) normals facing the viewer, for ray-cast shadows' origin offset.
pub(crate) const G_GEOMETRIC: &str = "g_geometric";
/// The material's surface inputs: uv, the tangent's angle about the normal, handedness.
pub(crate) const G_SURFACE: &str = "g_surface";
/// The uv's screen derivatives (d/dx, d/dy), the mip footprint textures are sampled with.
pub(crate) const G_UV_GRAD: &str = "g_uv_grad";
/// The second uv set (glTF `TEXCOORD_1`) in x, y, for materials that sample with it.
pub(crate) const G_UV1: &str = "g_uv1";
/// The second uv set's screen derivatives (d/dx, d/dy).
pub(crate) const G_UV1_GRAD: &str = "g_uv1_grad";

pub(crate) const SLOTS: &[SlotSpec] = &[
    super::GEOMETRY_READ,
    SlotSpec::new(
        slot::DEPTH,
        SlotType::DepthTexture,
        Access::ReadOrWrite,
        Usage::Attachment,
    ),
    // Positions, or the packed texture when there is no normals texture.
    SlotSpec::new(
        G_POSITION,
        SlotType::ColorTexture,
        Access::Write,
        Usage::Attachment,
    ),
    SlotSpec::new(
        G_NORMAL,
        SlotType::ColorTexture,
        Access::Write,
        Usage::Attachment,
    )
    .optional(),
    SlotSpec::new(
        G_GEOMETRIC,
        SlotType::ColorTexture,
        Access::Write,
        Usage::Attachment,
    )
    .optional(),
    // Last, so graphs that fill the slots above by order keep their meaning.
    SlotSpec::new(
        G_SURFACE,
        SlotType::ColorTexture,
        Access::Write,
        Usage::Attachment,
    )
    .optional(),
    SlotSpec::new(
        G_UV_GRAD,
        SlotType::ColorTexture,
        Access::Write,
        Usage::Attachment,
    )
    .optional(),
    SlotSpec::new(
        G_UV1,
        SlotType::ColorTexture,
        Access::Write,
        Usage::Attachment,
    )
    .optional(),
    SlotSpec::new(
        G_UV1_GRAD,
        SlotType::ColorTexture,
        Access::Write,
        Usage::Attachment,
    )
    .optional(),
];

/// Every colour target of a G-buffer, in the fragment shader's order: the positions (or
/// the packed texture) first, then the optional ones.
pub(crate) const TARGETS: [&str; 7] = [
    G_POSITION,
    G_NORMAL,
    G_GEOMETRIC,
    G_SURFACE,
    G_UV_GRAD,
    G_UV1,
    G_UV1_GRAD,
];

pub(crate) fn check(ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    for s in TARGETS {
        if let Some(name) = ctx.slot(s) {
            if !ctx.is_rgba32f(name) {
                errors.push(ctx.mismatch(name, "G-buffer textures are Rgba32Float"));
            }
        }
    }
    check_surface_pair(ctx, errors);
    let Some(depth) = ctx.slot(slot::DEPTH) else {
        return;
    };
    // MSAA: every target and the depth at one sample count (a render pass's attachments
    // must agree), and only the two-texture layout (see check_msaa_layout).
    let ds = ctx.samples(depth);
    for name in TARGETS.iter().filter_map(|s| ctx.slot(s)) {
        let ts = ctx.samples(name);
        if ts != ds {
            errors.push(ctx.mismatch(
                name,
                format!("G-buffer texture has {ts} sample(s) but depth '{depth}' has {ds}: every G-buffer texture takes the depth's sample count"),
            ));
        }
    }
    if ds > 1 {
        check_msaa_layout(ctx, depth, errors);
    }
}

/// `g_surface` and `g_uv_grad` come together: textures are sampled at the stored uv
/// with the stored derivatives. So do `g_uv1` and `g_uv1_grad`, the second uv set's,
/// and only beside the first pair.
pub(crate) fn check_surface_pair(ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    match (ctx.slot(G_SURFACE), ctx.slot(G_UV_GRAD)) {
        (Some(one), None) | (None, Some(one)) => errors.push(ctx.mismatch(
            one,
            format!("the G-buffer's surface is two textures, {G_SURFACE} (uv, tangent) and {G_UV_GRAD} (uv derivatives): give both or neither"),
        )),
        _ => {}
    }
    match (ctx.slot(G_UV1), ctx.slot(G_UV1_GRAD)) {
        (Some(one), None) | (None, Some(one)) => errors.push(ctx.mismatch(
            one,
            format!("the second uv set is two textures, {G_UV1} (uv) and {G_UV1_GRAD} (its derivatives): give both or neither"),
        )),
        (Some(one), Some(_)) if ctx.slot(G_SURFACE).is_none() => errors.push(ctx.mismatch(
            one,
            format!("the second uv set ({G_UV1}, {G_UV1_GRAD}) goes with the surface ({G_SURFACE}, {G_UV_GRAD}), which this pass does not name"),
        )),
        _ => {}
    }
}

/// A multisampled G-buffer holds world positions and shading normals per sample: the
/// packed layout rebuilds positions on the pixel centre's view ray, which is not where
/// an edge sample's surface lies (MSAA interpolates at the centroid), and ray-cast
/// shadows' jobs read a single-sample G-buffer.
pub(crate) fn check_msaa_layout(ctx: &KindCtx, at: &str, errors: &mut Vec<GraphError>) {
    if ctx.slot(G_NORMAL).is_none() {
        errors.push(ctx.mismatch(
            at,
            "a multisampled G-buffer is the two-texture layout (g_position, g_normal): the packed one rebuilds positions on the pixel centre's ray, not at each sample's surface",
        ));
    }
    if let Some(g) = ctx.slot(G_GEOMETRIC) {
        errors.push(ctx.mismatch(
            g,
            "ray-cast shadows read a single-sample G-buffer: a multisampled one has no geometric normals",
        ));
    }
}

/// The shadow atlas comparison's read of the unpacked G-buffer's world positions.
pub(crate) const G_POSITION_READ: SlotSpec = SlotSpec::new(
    G_POSITION,
    SlotType::ColorTexture,
    Access::Read,
    Usage::Sampled,
);

/// Deferred shading's reads of the surface targets.
pub(crate) const G_SURFACE_READ: SlotSpec = SlotSpec::new(
    G_SURFACE,
    SlotType::ColorTexture,
    Access::Read,
    Usage::Sampled,
)
.optional();
pub(crate) const G_UV_GRAD_READ: SlotSpec = SlotSpec::new(
    G_UV_GRAD,
    SlotType::ColorTexture,
    Access::Read,
    Usage::Sampled,
)
.optional();
pub(crate) const G_UV1_READ: SlotSpec =
    SlotSpec::new(G_UV1, SlotType::ColorTexture, Access::Read, Usage::Sampled).optional();
pub(crate) const G_UV1_GRAD_READ: SlotSpec = SlotSpec::new(
    G_UV1_GRAD,
    SlotType::ColorTexture,
    Access::Read,
    Usage::Sampled,
)
.optional();

/// Whether the pass writes the packed layout (one texture: no normals of either kind).
pub fn packed(roles: &crate::graph::PassRoles) -> bool {
    roles.slot(G_NORMAL).is_none() && roles.slot(G_GEOMETRIC).is_none()
}

/// `GBuffer` has no parameters: this names it for its rules.
pub struct GBuffer;

impl KindRules for GBuffer {
    fn slots(&self) -> &'static [SlotSpec] {
        SLOTS
    }
    fn check(&self, ctx: &KindCtx, errors: &mut Vec<GraphError>) {
        check(ctx, errors)
    }
}

#[cfg(test)]
mod tests {
    use crate::graph::kinds::test_support::{errors, validate};

    #[test]
    fn one_or_two_rgba32f_textures() {
        validate(
            r#"Pass(name: "g", kind: GBuffer, reads: ["geometry"], writes: ["depth", "pos", "nrm"])"#,
            "pos",
        )
        .unwrap();
        validate(
            r#"Pass(name: "g", kind: GBuffer, reads: ["geometry"], writes: ["depth", "pos"])"#,
            "pos",
        )
        .unwrap();
        let e = errors(
            r#"Pass(name: "g", kind: GBuffer, reads: ["geometry"], writes: ["depth", "small"])"#,
            "hdr",
        );
        assert!(e.contains("G-buffer textures are Rgba32Float"), "{e}");
        let e = errors(
            r#"Pass(name: "g", kind: GBuffer, reads: ["geometry", "lg"], writes: ["depth", "pos"])"#,
            "pos",
        );
        assert!(
            e.contains("GBuffer has no free slot for an Import of LightGeometry"),
            "{e}"
        );
    }

    #[test]
    fn surface_targets_come_in_pairs_at_the_depths_samples() {
        let pass = |writes: &str| {
            format!(r#"Pass(name: "g", kind: GBuffer, reads: ["geometry"], writes: [{writes}])"#)
        };
        validate(
            &pass(r#""depth", "pos", "nrm", "g_surface=geo", "g_uv_grad=hdr""#),
            "pos",
        )
        .unwrap();
        let e = errors(&pass(r#""depth", "pos", "nrm", "g_surface=geo""#), "pos");
        assert!(
            e.contains("resource 'geo': the G-buffer's surface is two textures"),
            "{e}"
        );
        let e = errors(
            &pass(r#""depth4", "pos4", "nrm4", "g_surface=geo", "g_uv_grad=hdr4""#),
            "geo",
        );
        assert!(
            e.contains("resource 'geo': G-buffer texture has 1 sample(s) but depth 'depth4' has 4"),
            "{e}"
        );
        // The second uv set: a pair too, and only beside the surface pair.
        let e = errors(
            &pass(r#""depth", "pos", "g_surface=geo", "g_uv_grad=hdr", "g_uv1=nrm""#),
            "pos",
        );
        assert!(
            e.contains("resource 'nrm': the second uv set is two textures"),
            "{e}"
        );
        let e = errors(
            &pass(r#""depth", "pos", "g_uv1=geo", "g_uv1_grad=hdr""#),
            "pos",
        );
        assert!(
            e.contains(
                "resource 'geo': the second uv set (g_uv1, g_uv1_grad) goes with the surface"
            ),
            "{e}"
        );
    }

    #[test]
    fn msaa_targets_take_the_depths_samples_and_two_textures() {
        // The G-buffer pass writes `targets`; a deferred pass reads its colour textures.
        let graph = |targets: &str, reads: &str| {
            format!(
                r#"Pass(name: "g", kind: GBuffer, reads: ["geometry"], writes: [{targets}]), Pass(name: "d", kind: DeferredShading(), reads: [{reads}, "lg", "lp"], writes: ["hdr"])"#
            )
        };
        validate(
            &graph(r#""depth4", "pos4", "nrm4""#, r#""pos4", "nrm4""#),
            "hdr",
        )
        .unwrap();
        let e = errors(
            &graph(r#""depth4", "pos4", "nrm""#, r#""pos4", "nrm""#),
            "hdr",
        );
        assert!(
            e.contains("pass 'g', resource 'nrm': G-buffer texture has 1 sample(s) but depth 'depth4' has 4"),
            "{e}"
        );
        let e = errors(
            &graph(r#""depth", "pos4", "nrm4""#, r#""pos4", "nrm4""#),
            "hdr",
        );
        assert!(
            e.contains("pass 'g', resource 'pos4': G-buffer texture has 4 sample(s) but depth 'depth' has 1"),
            "{e}"
        );
        let e = errors(&graph(r#""depth4", "pos4""#, r#""pos4""#), "hdr");
        assert!(
            e.contains(
                "pass 'g', resource 'depth4': a multisampled G-buffer is the two-texture layout"
            ),
            "{e}"
        );
        let e = errors(
            &graph(
                r#""depth4", "pos4", "nrm4", "g_geometric=hdr4""#,
                r#""pos4", "nrm4""#,
            ),
            "hdr",
        );
        assert!(
            e.contains("resource 'hdr4': ray-cast shadows read a single-sample G-buffer"),
            "{e}"
        );
    }
}
