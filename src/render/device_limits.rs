//! What a frame asks of the device, checked against its limits before anything is
//! created: wgpu would report these as raw validation text with internal labels, or
//! panic in its default error handler. Errors name the graph file:line, the pass and the
//! resource.

use super::RenderError;
use crate::graph::plan::PhysicalDesc;
use crate::graph::CompiledGraph;
use crate::render::pipelines::PipelineKey;
use crate::shader::{BindingKind, ReflectedBinding, ShaderError};

/// Every planned texture and buffer against the device's size limits.
pub fn check_plan(graph: &CompiledGraph, limits: &wgpu::Limits) -> Result<(), RenderError> {
    for r in &graph.plan.resources {
        let physical = &graph.plan.physical[r.physical];
        let problem = match physical.desc {
            PhysicalDesc::Texture { width, height, .. } => {
                let max = limits.max_texture_dimension_2d;
                (width > max || height > max).then(|| {
                    format!(
                        "texture of {width}×{height} is over the device's limit of {max} per side"
                    )
                })
            }
            PhysicalDesc::Buffer { bytes } => {
                // Every planned buffer may be bound as storage.
                let max = limits
                    .max_buffer_size
                    .min(limits.max_storage_buffer_binding_size);
                (bytes > max).then(|| {
                    let hint = r.layout.and_then(|l| l.fit_hint(max));
                    format!(
                        "buffer of {bytes} bytes is over the device's limit of {max} bytes for a storage buffer{}",
                        hint.map_or_else(String::new, |h| format!(": {h}"))
                    )
                })
            }
        };
        if let Some(problem) = problem {
            let pass = graph
                .passes
                .get(r.first)
                .map_or_else(|| graph.output().to_string(), |p| p.name.to_string());
            return Err(RenderError::AtPass {
                at: graph.checked.source.in_pass(&pass, &r.name),
                pass,
                problem: format!("resource '{}': {problem}", r.name),
            });
        }
    }
    Ok(())
}

/// The sample counts the device offers for `format`: the adapter's own where the device
/// has adapter-specific format features, else WebGPU's guaranteed ones.
pub fn supported_sample_counts(
    format: wgpu::TextureFormat,
    adapter: &wgpu::Adapter,
    device: &wgpu::Device,
) -> Vec<u32> {
    let features = device.features();
    let flags = if features.contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES) {
        adapter.get_texture_format_features(format).flags
    } else {
        format.guaranteed_format_features(features).flags
    };
    let mut counts = flags.supported_sample_counts();
    if !counts.contains(&1) {
        counts.insert(0, 1);
    }
    counts
}

/// Every multisampled texture against the sample counts the adapter offers for its
/// format, naming the first pass that uses it and the counts it could have.
pub fn check_samples(
    graph: &CompiledGraph,
    adapter: &wgpu::Adapter,
    device: &wgpu::Device,
) -> Result<(), RenderError> {
    for r in &graph.plan.resources {
        let PhysicalDesc::Texture {
            format, samples, ..
        } = graph.plan.physical[r.physical].desc
        else {
            continue;
        };
        if samples <= 1 {
            continue;
        }
        let counts = supported_sample_counts(format.to_wgpu(), adapter, device);
        if counts.contains(&samples) {
            continue;
        }
        let pass = graph
            .passes
            .get(r.first)
            .map_or_else(|| graph.output().to_string(), |p| p.name.to_string());
        let list = counts
            .iter()
            .map(u32::to_string)
            .collect::<Vec<_>>()
            .join(", ");
        return Err(RenderError::AtPass {
            at: graph.checked.source.in_pass(&pass, &r.name),
            pass,
            problem: format!(
                "resource '{}': samples: {samples} is not supported for {format:?} on this adapter ({}); it supports {list}",
                r.name,
                adapter.get_info().name
            ),
        });
    }
    Ok(())
}

/// A compute dispatch's workgroup counts against the device's limit per dimension.
pub fn check_dispatch(
    graph: &CompiledGraph,
    pass: &str,
    groups: [u32; 3],
    limits: &wgpu::Limits,
) -> Result<(), RenderError> {
    let max = limits.max_compute_workgroups_per_dimension;
    if groups.iter().all(|&g| g <= max) {
        return Ok(());
    }
    Err(RenderError::AtPass {
        at: graph.checked.source.in_pass(pass, "dispatch"),
        pass: pass.to_string(),
        problem: format!(
            "dispatch of {groups:?} workgroups is over the device's limit of {max} per dimension (use a larger workgroup)"
        ),
    })
}

/// Creates a buffer a pass makes for itself (not planned by the graph, so not seen by
/// [`check_plan`]), checked first against the device's limits for its size and, as it is
/// bound whole, for a storage or uniform binding of it: wgpu would report an oversized one
/// as raw validation text (`max_*_buffer_binding_size`) at bind-group creation. The error
/// names `pass` (located at its declaration by the caller) and the buffer's label.
pub fn create_internal_buffer(
    device: &wgpu::Device,
    pass: &str,
    desc: &wgpu::BufferDescriptor,
) -> Result<wgpu::Buffer, RenderError> {
    let limits = device.limits();
    let mut max = (limits.max_buffer_size, "buffer");
    if desc.usage.contains(wgpu::BufferUsages::STORAGE) {
        max = max.min((
            limits.max_storage_buffer_binding_size,
            "storage buffer binding",
        ));
    }
    if desc.usage.contains(wgpu::BufferUsages::UNIFORM) {
        max = max.min((
            limits.max_uniform_buffer_binding_size,
            "uniform buffer binding",
        ));
    }
    if desc.size > max.0 {
        return Err(RenderError::Pass {
            pass: pass.to_string(),
            message: format!(
                "its buffer '{}' of {} bytes is over the device's limit of {} bytes for a {} (it grows with the frame size and the light count)",
                desc.label.unwrap_or("unnamed"),
                desc.size,
                max.0,
                max.1
            ),
        });
    }
    Ok(device.create_buffer(desc))
}

/// A shading pass's light loop of up to `most` lights at one pixel, against the most
/// iterations the adapter's driver lets one loop run (`GpuContext::driver_limits`, see
/// `gpu::driver_limits`); `what` says where the bound comes from, `adapter` names it.
pub fn check_light_loop(
    driver: &crate::gpu::DriverLimits,
    adapter: &str,
    pass: &str,
    most: u64,
    what: &str,
) -> Result<(), RenderError> {
    match driver.loop_iterations {
        Some(limit) if most > limit => Err(RenderError::Pass {
            pass: pass.to_string(),
            message: format!(
                "its light loop may visit {most} lights at one pixel ({what}), over this adapter's limit of {limit} iterations a loop ({adapter} ends longer loops silently, losing the lights past it)"
            ),
        }),
        _ => Ok(()),
    }
}

/// Every binding of a pass's layout is visible to its stage, so a module's storage
/// buffers all count against the device's per-stage limit: refused here with the
/// shader, its options and the counts, not by wgpu's layout validation.
pub(super) fn check_storage_buffers(
    key: &PipelineKey,
    bindings: &[ReflectedBinding],
    device: &wgpu::Device,
) -> Result<(), ShaderError> {
    let storage = bindings
        .iter()
        .filter(|b| matches!(b.kind, BindingKind::Storage { .. }))
        .count() as u32;
    let limit = device.limits().max_storage_buffers_per_shader_stage;
    if storage <= limit {
        return Ok(());
    }
    // The switches among its defines (the sizes say little here).
    let options: Vec<&str> = key
        .defines
        .iter()
        .filter(|(_, value)| value.as_str() == "1")
        .map(|(name, _)| name.as_str())
        .collect();
    Err(ShaderError::OverLimit {
        file: key.shader.clone().into(),
        message: format!(
            "binds {storage} storage buffers in one stage ({}), over the {limit} this device allows",
            options.join(", ")
        ),
    })
}
