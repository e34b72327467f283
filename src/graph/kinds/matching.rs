//! The slot matcher every built-in kind shares: a pass's declared resources to its
//! kind's slot table, by name where the declaration says so, else by type and order.

use super::{check, is_float_depth, KindCtx, SlotSpec, SlotType};
use crate::graph::error::GraphError;
use crate::graph::model::{Name, PassDesc, ResourceDesc};
use crate::graph::roles::{PassRoles, RoleCtx};

fn slot_type_of(ctx: &RoleCtx, name: &str) -> Option<SlotType> {
    Some(match ctx.resources.get(name)? {
        ResourceDesc::Texture { format, .. } if format.is_depth() => SlotType::DepthTexture,
        ResourceDesc::Texture { .. } => SlotType::ColorTexture,
        ResourceDesc::Buffer { .. } => SlotType::Buffer,
        ResourceDesc::Import { from, .. } => SlotType::Import(*from),
    })
}

/// Matches a built-in pass's declared resources to its kind's slots: by name where the
/// declaration says `slot=resource` or the resource is named like a slot of its type,
/// else to the first free slot of the resource's type
/// that takes it from that list (reads or writes), in the table's order. Every resource
/// must fill a slot and every required slot must be filled; then the kind checks.
pub(crate) fn resolve(
    ctx: &RoleCtx,
    pass: &PassDesc,
    specs: &[SlotSpec],
) -> Result<PassRoles, Vec<GraphError>> {
    let mut roles = PassRoles::default();
    let mut errors = Vec::new();
    let kind = pass.kind.label();
    let names = || specs.iter().map(|s| s.name).collect::<Vec<_>>().join(", ");
    // Explicit slots and resources named like a free slot of their type go first, so
    // one that fills by type order cannot take the slot a later one is named after.
    let float_depth = |name: &str| is_float_depth(ctx.resources.get(name).copied());
    let named_like = |name: &str, ty: SlotType, write: bool| {
        specs.iter().any(|s| {
            s.name == name && s.ty.takes(ty, true, float_depth(name)) && s.access.allows(write)
        })
    };
    // Each resource's slot type, looked up once for both rounds.
    let typed: Vec<(bool, &Name, SlotType)> = [(false, &pass.reads), (true, &pass.writes)]
        .into_iter()
        .flat_map(|(write, list)| list.iter().map(move |name| (write, name)))
        .filter_map(|(write, name)| Some((write, name, slot_type_of(ctx, name)?)))
        .collect(); // unknown resources are reported by validation

    // An R32Float texture this kind cannot read as depth: say which kinds can.
    let depth_hint = |name: &str| {
        let has_depth_slot = specs.iter().any(|s| s.ty == SlotType::DepthTexture);
        if float_depth(name) && has_depth_slot {
            format!(" ({kind} reads depth from a depth texture only; an R32Float depth is read by LightCulling, LightLinkedList and TransparentShading)")
        } else {
            String::new()
        }
    };
    for by_name in [true, false] {
        for &(write, name, ty) in &typed {
            let first = pass.explicit_slot(name).is_some() || named_like(name, ty, write);
            if first != by_name {
                continue;
            }
            if write && matches!(ty, SlotType::Import(_)) {
                continue; // a write to a read-only import, reported by validation
            }
            if roles.slots.values().any(|v| v == name) {
                continue; // in reads and writes: one slot
            }
            let wanted = pass
                .explicit_slot(name)
                .or_else(|| named_like(name, ty, write).then_some(name.as_str()));
            let spec = match wanted {
                Some(wanted) => match specs.iter().find(|s| s.name == wanted) {
                    None => {
                        errors.push(ctx.mismatch(
                            pass,
                            name,
                            format!("{kind} has no slot '{wanted}' (its slots: {})", names()),
                        ));
                        continue;
                    }
                    Some(s)
                        if !s.ty.takes(ty, true, float_depth(name)) || !s.access.allows(write) =>
                    {
                        errors.push(ctx.mismatch(
                            pass,
                            name,
                            format!(
                                "slot '{wanted}' takes {} {}{}",
                                s.ty.describe(),
                                s.access.describe(),
                                depth_hint(name)
                            ),
                        ));
                        continue;
                    }
                    Some(s) => s,
                },
                None => match specs.iter().find(|s| {
                    s.ty.takes(ty, false, float_depth(name))
                        && s.access.allows(write)
                        && !roles.slots.contains_key(s.name)
                }) {
                    Some(s) => s,
                    None => {
                        let list = if write { "writes" } else { "reads" };
                        errors.push(ctx.mismatch(
                            pass,
                            name,
                            format!(
                                "{kind} has no free slot for {} in {list} (its slots: {}){}",
                                ty.describe(),
                                names(),
                                depth_hint(name)
                            ),
                        ));
                        continue;
                    }
                },
            };
            if let Some(prev) = roles.slots.insert(spec.name, name.clone()) {
                errors.push(ctx.mismatch(
                    pass,
                    name,
                    format!("slot '{}' already filled by '{prev}'", spec.name),
                ));
            }
        }
    }
    for s in specs.iter().filter(|s| !s.optional) {
        if !roles.slots.contains_key(s.name) {
            // A missing depth while an R32Float depth filled another slot (a shadow
            // atlas takes one): say which kinds read such a depth.
            let hint = match typed.iter().find(|(_, name, _)| float_depth(name)) {
                Some((_, name, _)) if s.ty == SlotType::DepthTexture => depth_hint(name),
                _ => String::new(),
            };
            errors.push(ctx.bad(
                pass,
                format!(
                    "{kind} needs {} {} (slot '{}'){hint}",
                    s.ty.describe(),
                    s.access.describe(),
                    s.name
                ),
            ));
        }
    }
    if errors.is_empty() {
        check(
            &KindCtx {
                roles: &roles,
                pass,
                graph: ctx,
            },
            &mut errors,
        );
    }
    if errors.is_empty() {
        Ok(roles)
    } else {
        Err(errors)
    }
}
