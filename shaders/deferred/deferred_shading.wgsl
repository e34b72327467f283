// Deferred shading in a compute shader: one dispatch per group of materials that share
// their code (one per material with a multisampled G-buffer) over the whole frame; each
// invocation shades the pixel if the G-buffer holds one of the group's materials there,
// with the same material code and light loop as forward shading. On GPUs where few SMs run
// fragment work (GH100) this is where the lighting throughput is.
// With G_PACKED the G-buffer is one texture: view depth, octahedral normal, material;
// the position is rebuilt on the pixel's view ray.
// With G_SURFACE the G-buffer also holds the material's surface (deferred/g_surface.wgsl:
// uv and tangent) and the uv's screen derivatives, which textured materials
// (MATERIAL_TEXTURED, code generated with explicit derivatives) sample with; with G_UV1
// as well the second uv set and its derivatives (g_uv1, g_uv1_grad), for TEXCOORD_1.
// Defines: GROUP_INDEX (the group: `material_groups` gives each material's group and
// first constant; SHARED_CODE where the group's code reads its constants from
// `material_constants`) or, with G_SAMPLES, MATERIAL_INDEX; LIGHT_LISTS (tile lists) or
// LINKED_LISTS (a light linked list), G_PACKED, G_SAMPLES (a multisampled G-buffer of that many samples: the main of
// deferred/deferred_msaa.wgsl), SHADOWS with SHADOW_MASK (ray-cast shadows from
// shadow/shadow_ray_cast.wgsl) or SHADOW_ATLAS (a ShadowAtlas pass's maps),
// VPL_VISIBILITY (VPLs hidden from the pixel's block add nothing: indirect/vpl_lookup.wgsl).

#include "common/types.wgsl"
#include "common/lighting.wgsl"

@group(0) @binding(0) var<uniform> frame: Frame;
#include "common/light_inputs.wgsl"
#if G_SAMPLES
#else
// Per material index: (its group, its first constant in material_constants).
@group(0) @binding(15) var<storage, read> material_groups: array<vec2<u32>>;
#endif
#if G_SAMPLES
// A multisampled G-buffer (see deferred/deferred_msaa.wgsl): `hdr` holds partial sums
// between the materials' dispatches.
@group(0) @binding(5) var g_position: texture_multisampled_2d<f32>;
@group(0) @binding(6) var g_normal: texture_multisampled_2d<f32>;
@group(0) @binding(7) var hdr: texture_storage_2d<rgba32float, read_write>;
#if G_SURFACE
@group(0) @binding(12) var g_surface: texture_multisampled_2d<f32>;
@group(0) @binding(13) var g_uv_grad: texture_multisampled_2d<f32>;
#endif
#if G_UV1
@group(0) @binding(16) var g_uv1: texture_multisampled_2d<f32>;
@group(0) @binding(17) var g_uv1_grad: texture_multisampled_2d<f32>;
#endif
#else
@group(0) @binding(5) var g_position: texture_2d<f32>;
#if G_PACKED
#include "common/octahedral.wgsl"
#else
@group(0) @binding(6) var g_normal: texture_2d<f32>;
#endif
@group(0) @binding(7) var hdr: texture_storage_2d<rgba32float, write>;
#if G_SURFACE
@group(0) @binding(12) var g_surface: texture_2d<f32>;
@group(0) @binding(13) var g_uv_grad: texture_2d<f32>;
#endif
#if G_UV1
@group(0) @binding(16) var g_uv1: texture_2d<f32>;
@group(0) @binding(17) var g_uv1_grad: texture_2d<f32>;
#endif
#endif

#if SHADOW_MASK
@group(0) @binding(8) var<storage, read> shadow_mask: array<u32>;
#endif
#if SHADOW_ATLAS
@group(0) @binding(9) var<storage, read> shadow_views: array<vec4<f32>>;
#if SHADOW_ATLAS_FLOAT
@group(0) @binding(10) var shadow_atlas: texture_2d<f32>;
@group(0) @binding(11) var shadow_gather: sampler;
#else
@group(0) @binding(10) var shadow_atlas: texture_depth_2d;
@group(0) @binding(11) var shadow_sampler: sampler_comparison;
#endif
#endif
#if SHADOWS
#include "common/shadows.wgsl"
#endif
#if VPL_VISIBILITY
@group(0) @binding(14) var<storage, read> vpl_visibility: array<u32>;
#include "indirect/vpl_lookup.wgsl"
#endif

#include "common/shading_point.wgsl"

#include <material>
#include "common/light_loop.wgsl"
#if G_SURFACE
#include "deferred/g_surface.wgsl"
#endif

// The material's inputs at sample `s` of pixel `p` besides position and normal: the
// surface's uv and tangent (zero without G_SURFACE), and for textured materials the uv
// derivatives their samples take.
fn load_surface(q: ptr<function, ShadingPoint>, p: vec2<u32>, s: u32) {
#if G_SURFACE
    let t = textureLoad(g_surface, p, s);
    // Its rgb to 8 bits, alpha 1 (deferred/g_surface.wgsl).
    (*q).color = surface_color(t);
    (*q).uv = t.xy;
#if G_UV1
    (*q).uv1 = textureLoad(g_uv1, p, s).xy;
#else
    // Without the second uv set's targets a TEXCOORD_1 texture samples TEXCOORD_0 (the
    // pass warns).
    (*q).uv1 = t.xy;
#endif
    (*q).tangent = surface_tangent((*q).normal, t);
#if MATERIAL_TEXTURED
    let d = textureLoad(g_uv_grad, p, s);
    material_uv_ddx = d.xy;
    material_uv_ddy = d.zw;
#if G_UV1
    let d1 = textureLoad(g_uv1_grad, p, s);
    material_uv1_ddx = d1.xy;
    material_uv1_ddy = d1.zw;
#else
    material_uv1_ddx = d.xy;
    material_uv1_ddy = d.zw;
#endif
#endif
#else
    (*q).color = vec4<f32>(1.0);
    (*q).tangent = vec4<f32>(0.0);
    (*q).uv = vec2<f32>(0.0);
    (*q).uv1 = vec2<f32>(0.0);
#endif
}

#if G_SAMPLES
#include "deferred/deferred_msaa.wgsl"
#else

#if G_PACKED
// The world point at view depth `view_z` on the ray through framebuffer position `pixel`.
fn position_on_view_ray(pixel: vec2<f32>, view_z: f32) -> vec3<f32> {
    let size = vec2<f32>(frame.size);
    let ndc = vec2<f32>(pixel.x / size.x * 2.0 - 1.0, 1.0 - pixel.y / size.y * 2.0);
    let far = frame.inv_proj * vec4<f32>(ndc, 1.0, 1.0);
    let ray = far.xyz / far.w;
    let view_pos = ray * (view_z / -ray.z);
    // The view matrix is a rotation and a translation: its inverse is the transpose.
    let r = mat3x3<f32>(frame.view[0].xyz, frame.view[1].xyz, frame.view[2].xyz);
    return transpose(r) * (view_pos - frame.view[3].xyz);
}
#endif

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= frame.size)) {
        return;
    }
    let g = textureLoad(g_position, id.xy, 0);
    let here = i32(round(g.w));
    if (here < 0) {
        // Nothing drawn: the first group's dispatch clears the pixel.
        if (GROUP_INDEX == 0u) {
            textureStore(hdr, id.xy, vec4<f32>(0.0));
        }
        return;
    }
    let group = material_groups[u32(here)];
    if (group.x != GROUP_INDEX) {
        return;
    }
#if SHARED_CODE
    material_constant_base = group.y;
#endif
    var p: ShadingPoint;
#if G_PACKED
    p.position = position_on_view_ray(vec2<f32>(id.xy) + 0.5, g.x);
    p.normal = oct_decode(g.yz);
#else
    p.position = g.xyz;
    p.normal = textureLoad(g_normal, id.xy, 0).xyz;
#endif
    p.view = normalize(frame.camera_pos.xyz - p.position);
    load_surface(&p, id.xy, 0u);
    let m = material_setup(p);
    let view_z = -(frame.view * vec4<f32>(p.position, 1.0)).z;
    let pixel = vec2<f32>(id.xy) + 0.5;
    textureStore(hdr, id.xy, vec4<f32>(shade_surface(p, m, pixel, view_z), material_alpha(m)));
}
#endif
