//! `GBuffer`: the scene's geometry into one packed Rgba32Float texture (view depth,
//! octahedral normal, material) or two (world position with the material in w, shading
//! normal). After a depth prepass it only tests depth. Runs `shaders/forward/forward.wgsl`
//! with `GBUFFER`.

use super::{slot, Access, KindCtx, SlotSpec, SlotType, Usage};
use crate::graph::error::GraphError;

pub const G_POSITION: &str = "g_position";
pub const G_NORMAL: &str = "g_normal";
/// Geometric (face) normals facing the viewer, for ray-cast shadows' origin offset.
pub const G_GEOMETRIC: &str = "g_geometric";

pub const SLOTS: &[SlotSpec] = &[
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
];

pub fn check(ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    ctx.require_single_rgba32f(
        &[G_POSITION, G_NORMAL, G_GEOMETRIC],
        "G-buffer textures are single-sample Rgba32Float",
        errors,
    );
    if let Some(depth) = ctx.slot(slot::DEPTH) {
        if ctx.samples(depth) != 1 {
            errors.push(ctx.mismatch(depth, "the G-buffer is single-sample"));
        }
    }
}

/// Ray-cast shadows' reads of the unpacked G-buffer: world positions, geometric normals.
pub const G_POSITION_READ: SlotSpec = SlotSpec::new(
    G_POSITION,
    SlotType::ColorTexture,
    Access::Read,
    Usage::Sampled,
);
pub const G_GEOMETRIC_READ: SlotSpec = SlotSpec::new(
    G_GEOMETRIC,
    SlotType::ColorTexture,
    Access::Read,
    Usage::Sampled,
);

/// Whether the pass writes the packed layout (one texture: no normals of either kind).
pub fn packed(roles: &crate::graph::PassRoles) -> bool {
    roles.slot(G_NORMAL).is_none() && roles.slot(G_GEOMETRIC).is_none()
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
        assert!(e.contains("single-sample Rgba32Float"), "{e}");
        let e = errors(
            r#"Pass(name: "g", kind: GBuffer, reads: ["geometry", "lg"], writes: ["depth", "pos"])"#,
            "pos",
        );
        assert!(
            e.contains("GBuffer has no free slot for an Import of LightGeometry"),
            "{e}"
        );
    }
}
