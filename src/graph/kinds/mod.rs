//! The graph side of the built-in pass kinds. A kind is one folder, `src/kinds/<kind>/`,
//! whose `rules.rs` build.rs mounts here as `graph::kinds::<kind>`: its parameters, its
//! slot table and its checks (a `KindRules` impl). This file holds the registry of kinds
//! (`built_in_kinds!`), which generates `PassKind` and every dispatch over it, and the
//! rows and checks several kinds share; `matching.rs` holds the slot matcher they all use
//! and `contracts.rs` the checks of read buffers against their writers. Generic kinds
//! (Compute, Fullscreen) bind by reflected shader binding names instead (see `roles.rs`).

/// The built-in pass kinds: one line each, in the order graph files list them. A line
/// names the variant graph files spell, its parameters (a kind without any names
/// none) and its module, the name of its folder `src/kinds/<module>/`: `rules.rs`
/// (parameters, slot table, checks: [`KindRules`]) and `prepare.rs` (prepare and record).
/// `$then` is the macro that makes something of the list: the `PassKind` enum and the
/// graph's dispatch here, the prepare dispatch in `render/passes/`. Each is generated
/// from this one list, so none can miss a kind; a line without its folder's files, a
/// `rules.rs` without its `KindRules` impl, a `prepare.rs` without its `prepare`, or a
/// folder without its line (build.rs asserts `registered` of each) does not compile.
macro_rules! built_in_kinds {
    ($then:ident) => {
        $then! {
            /// Depth only, no colour target; alpha-masked geometry discards.
            DepthPrepass => depth_prepass,
            /// Tiled light culling against the prepass depth.
            LightCulling(params: LightCulling) => light_culling,
            /// Per-pixel light linked lists (Bezrati, "Real-Time Lighting via Light Linked
            /// List") at full or reduced resolution.
            LightLinkedList(params: LightLinkedList) => light_linked_list,
            /// Forward shading of the scene's materials through the light loop.
            ForwardShading(params: ForwardShading) => forward_shading,
            /// Geometry into a G-buffer: a depth texture and one packed or two Rgba32Float textures.
            GBuffer => g_buffer,
            /// Lighting in a compute shader from the G-buffer (tiled deferred with `Culled`).
            DeferredShading(params: DeferredShading) => deferred_shading,
            /// Ray-cast shadow jobs from the light lists (one per shadow-casting light a pixel sees).
            ShadowRayJobs(params: ShadowRayJobs) => shadow_ray_jobs,
            /// One any-hit ray a job against the scene BVH, into the per-pixel hit mask.
            ShadowRayCast(params: ShadowRayCast) => shadow_ray_cast,
            /// Every shadow-casting light's depth views into one atlas, in one render pass.
            ShadowAtlas(params: ShadowAtlas) => shadow_atlas,
            /// Counts (pixel, light) pairs where the atlas and ray-cast shadows disagree.
            ShadowCompare => shadow_compare,
            /// Stochastic direct lighting: the most important lights traced exactly, the
            /// rest resampled (RIS reservoirs, optional spatial reuse), a shadow ray a sample.
            LightSampling(params: LightSampling) => light_sampling,
            /// The nearest depth of blended meshes, for their own light lists.
            TransparentDepth => transparent_depth,
            /// Blended meshes, back to front, lit two-sided over the opaque colour.
            TransparentShading(params: TransparentShading) => transparent_shading,
            /// Reflective shadow maps of every indirect light (depth, normal, flux, position).
            ReflectiveShadowMaps(params: ReflectiveShadowMaps) => reflective_shadow_maps,
            /// Virtual point lights from the reflective shadow maps, appended to the lights.
            VplSpawn(params: VplSpawn) => vpl_spawn,
            /// Which VPLs each block of pixels sees: a ray per block and VPL against the shadow BVH.
            VplVisibility(params: VplVisibility) => vpl_visibility,
            /// Depth and a 32-bit triangle id per pixel (R32Uint) for every opaque mesh.
            VisibilityBuffer => visibility_buffer,
            /// Every material shaded in compute from the visibility buffer's triangle ids.
            VisibilityShading(params: VisibilityShading) => visibility_shading,
            /// Opaque triangles rasterized in compute (64-bit atomic min per pixel) into a depth
            /// texture and an R32Uint triangle-id visibility texture.
            ComputeRaster => compute_raster,
        }
    };
}
pub(crate) use built_in_kinds;

/// What a registry line's kind is matched as: its parameters, or the unit struct its
/// module names after a kind without any.
macro_rules! kind_value {
    ($params:ident ; $unit:path) => {
        $params
    };
    (; $unit:path) => {
        &$unit
    };
}

/// The graph side of the registry: the kinds' modules, `PassKind` with the two generic
/// kinds after the built-in ones, its label, and the kind's rules.
macro_rules! graph_side {
    ($( $(#[$doc:meta])* $kind:ident $( ($params:ident : $ty:ident) )? => $module:ident, )*) => {
        /// Each built-in kind's module name, in registry order.
        pub const KIND_MODULES: &[&str] = &[$( stringify!($module) ),*];

        /// A pass's kind and its parameters, as graph files write it (`kind: DepthPrepass`,
        /// `kind: LightCulling(tile: 16)`).
        #[derive(Clone, Debug, serde::Deserialize, serde::Serialize, PartialEq)]
        #[serde(deny_unknown_fields)]
        pub enum PassKind {
            $( $(#[$doc])* $kind $( ($module::$ty) )?, )*
            /// A compute shader the graph file names; bindings are matched by name.
            Compute {
                /// The WGSL file, relative to the shader root.
                shader: String,
                /// The entry point (`main` unless given).
                #[serde(default = "super::model::default_entry")]
                entry: String,
                /// How many workgroups it dispatches.
                dispatch: super::model::Dispatch,
            },
            /// A full-screen triangle with a fragment shader; bindings matched by name.
            Fullscreen {
                /// The WGSL file, relative to the shader root.
                shader: String,
                /// The fragment entry point (`fs_main` unless given).
                #[serde(default = "super::model::default_fragment_entry")]
                entry: String,
            },
        }

        impl PassKind {
            /// The kind's name as graph files spell it (`"LightCulling"`, `"Compute"`).
            pub fn label(&self) -> &'static str {
                match self {
                    $( PassKind::$kind { .. } => stringify!($kind), )*
                    PassKind::Compute { .. } => "Compute",
                    PassKind::Fullscreen { .. } => "Fullscreen",
                }
            }
            /// The shader a generic pass runs; `None` for built-in kinds.
            pub(crate) fn generic_shader(&self) -> Option<super::model::GenericShader<'_>> {
                use super::model::GenericShader;
                match self {
                    $( PassKind::$kind { .. } => None, )*
                    PassKind::Compute { shader, entry, .. } => Some(GenericShader {
                        file: shader,
                        entry,
                        stage: naga::ShaderStage::Compute,
                    }),
                    PassKind::Fullscreen { shader, entry } => Some(GenericShader {
                        file: shader,
                        entry,
                        stage: naga::ShaderStage::Fragment,
                    }),
                }
            }
            /// The rules of a built-in kind; `None` for generic kinds, which bind by
            /// reflected shader binding names instead (see `roles.rs`).
            pub(crate) fn rules(&self) -> Option<&dyn KindRules> {
                Some(match self {
                    $( PassKind::$kind $( ($params) )? => {
                        kind_value!($($params)? ; $module::$kind)
                    } )*
                    PassKind::Compute { .. } | PassKind::Fullscreen { .. } => return None,
                })
            }
        }
    };
}

built_in_kinds!(graph_side);

// Each kind folder's `rules.rs` as `graph::kinds::<kind>`, and a check that the folder
// has its registry line (build.rs).
include!(concat!(env!("OUT_DIR"), "/kind_rules.rs"));

/// The generic kinds' modules: their folders hold only a `prepare.rs`; `PassKind` and
/// the prepare dispatch name their variants by hand.
const GENERIC_KIND_MODULES: &[&str] = &["compute", "fullscreen"];

/// Whether `module` is a registered kind's, built-in or generic: what build.rs asserts
/// of every folder under `src/kinds/`.
const fn registered(module: &str) -> bool {
    // Byte by byte: `==` on strings is not callable in constants.
    const fn same(a: &[u8], b: &[u8]) -> bool {
        if a.len() != b.len() {
            return false;
        }
        let mut i = 0;
        while i < a.len() {
            if a[i] != b[i] {
                return false;
            }
            i += 1;
        }
        true
    }
    const fn contains(list: &[&str], module: &str) -> bool {
        let mut i = 0;
        while i < list.len() {
            if same(list[i].as_bytes(), module.as_bytes()) {
                return true;
            }
            i += 1;
        }
        false
    }
    contains(KIND_MODULES, module) || contains(GENERIC_KIND_MODULES, module)
}

pub(crate) mod contracts;
mod layout;
mod matching;
mod slots;

pub use layout::{BufferLayout, Contents};
pub use slots::*;

/// What a built-in kind tells validation and planning, implemented by its parameters
/// (or the unit struct its module names after a kind without any).
pub(crate) trait KindRules {
    /// Its slot table.
    fn slots(&self) -> &'static [SlotSpec];
    /// Its own checks, after its slots were matched.
    fn check(&self, _ctx: &KindCtx, _errors: &mut Vec<GraphError>) {}
    /// The layout it gives a buffer it writes into `slot`, published on the planned
    /// buffer for its readers.
    fn buffer_layout(&self, _slot: &str, _frame: FrameSize) -> Option<BufferLayout> {
        None
    }
    /// Checks against what the writers of its read buffers published (after every
    /// pass's slots were matched and each slot's `needs` was met).
    fn check_inputs(&self, _ctx: &contracts::InputsCtx, _errors: &mut Vec<GraphError>) {}
    /// Whether what the pass writes is memory spent on transparency (memory by technique).
    fn writes_transparency(&self, _roles: &PassRoles) -> bool {
        false
    }
}

use super::error::GraphError;
use super::model::{PassDesc, ResourceDesc};
use super::plan::FrameSize;
use super::roles::{PassRoles, RoleCtx};

pub(crate) use matching::resolve;

/// The slot table of a built-in kind; `None` for generic kinds.
pub fn slots(kind: &PassKind) -> Option<&'static [SlotSpec]> {
    kind.rules().map(|r| r.slots())
}

/// The kind's own checks, after its slots were matched.
fn check(ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    if let Some(rules) = ctx.pass.kind.rules() {
        rules.check(ctx, errors);
    }
}

/// The layout a built-in pass gives a buffer it writes into `slot`.
pub(crate) fn buffer_layout(kind: &PassKind, slot: &str, frame: FrameSize) -> Option<BufferLayout> {
    kind.rules()?.buffer_layout(slot, frame)
}

/// A matched pass, for its kind's checks.
pub(crate) struct KindCtx<'a> {
    pub roles: &'a PassRoles,
    pub pass: &'a PassDesc,
    pub(crate) graph: &'a RoleCtx<'a>,
}

impl KindCtx<'_> {
    pub fn slot(&self, name: &str) -> Option<&str> {
        self.roles.slot(name)
    }
    pub(crate) fn mismatch(&self, resource: &str, problem: impl Into<String>) -> GraphError {
        self.graph.mismatch(self.pass, resource, problem)
    }
    pub fn bad(&self, problem: impl Into<String>) -> GraphError {
        self.graph.bad(self.pass, problem)
    }
    /// Sample count of a texture (1 for anything else).
    pub fn samples(&self, name: &str) -> u32 {
        match self.graph.resources.get(name) {
            Some(ResourceDesc::Texture { samples, .. }) => *samples,
            _ => 1,
        }
    }
    /// Reports each filled slot of `slots` whose texture is not single-sample
    /// Rgba32Float, with `problem`.
    pub fn require_single_rgba32f(
        &self,
        slots: &[&str],
        problem: &str,
        errors: &mut Vec<GraphError>,
    ) {
        for s in slots {
            if let Some(name) = self.slot(s) {
                if !self.is_single_rgba32f(name) {
                    errors.push(self.mismatch(name, problem));
                }
            }
        }
    }
    /// Whether the texture is Rgba32Float, at any sample count.
    pub fn is_rgba32f(&self, name: &str) -> bool {
        matches!(
            self.graph.resources.get(name),
            Some(ResourceDesc::Texture {
                format: super::model::TextureFormat::Rgba32Float,
                ..
            })
        )
    }
    /// Whether the texture holds depths as R32Float (a `DepthValues` slot's other
    /// format), at any sample count.
    pub fn is_float_depth(&self, name: &str) -> bool {
        is_float_depth(self.graph.resources.get(name).copied())
    }
    pub(crate) fn is_single_rgba32f(&self, name: &str) -> bool {
        matches!(
            self.graph.resources.get(name),
            Some(ResourceDesc::Texture {
                format: super::model::TextureFormat::Rgba32Float,
                samples: 1,
                ..
            })
        )
    }
    pub fn writes(&self, name: &str) -> bool {
        self.pass.writes.iter().any(|w| w == name)
    }
}

/// Whether a resource is an R32Float texture: what a `DepthValues` slot takes besides
/// depth formats.
pub(crate) fn is_float_depth(resource: Option<&ResourceDesc>) -> bool {
    matches!(
        resource,
        Some(ResourceDesc::Texture {
            format: super::model::TextureFormat::R32Float,
            ..
        })
    )
}

/// A `DepthValues` slot filled with an R32Float texture: single-sample (compute stores
/// one value a pixel), else an error naming the pass and resource.
pub(crate) fn check_float_depth_samples(ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    if let Some(depth) = ctx.slot(slot::DEPTH) {
        if ctx.is_float_depth(depth) && ctx.samples(depth) > 1 {
            errors.push(ctx.mismatch(
                depth,
                format!(
                    "an R32Float depth is single-sample (compute stores one depth a pixel); it has {} samples: use a multisampled Depth32Float for MSAA",
                    ctx.samples(depth)
                ),
            ));
        }
    }
}

/// A shading pass that reads a shadow mask must read the culled lists it numbers.
pub(crate) fn check_shadow_mask(ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    if let (Some(mask), None) = (
        ctx.slot(shadow_ray_jobs::SHADOW_MASK),
        ctx.slot(slot::LIGHT_LISTS),
    ) {
        errors.push(ctx.mismatch(
            mask,
            "the shadow mask numbers the lights of the culled lists it was made from: read them too (lights: Culled)",
        ));
    }
}

/// A light loop that casts its own shadow rays binds the whole BVH.
pub(crate) fn check_bvh_trace(ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    use shadow_ray_cast::{BVH_NODES, BVH_TRIANGLES};
    if ctx.slot(BVH_NODES).is_some() != ctx.slot(BVH_TRIANGLES).is_some() {
        errors.push(
            ctx.bad("tracing shadows in the light loop needs both bvh_nodes and bvh_triangles"),
        );
    }
}

/// A shading pass samples an atlas through its view table, and shadows one way only, or
/// the atlas and `hybrid` together (the hybrid: the atlas for lights with a map, the
/// ray-cast mask, or the BVH traced in the light loop, for the rest).
pub(crate) fn check_shadow_atlas(
    ctx: &KindCtx,
    errors: &mut Vec<GraphError>,
    hybrid: Option<&str>,
) {
    use shadow_atlas::{SHADOW_ATLAS, SHADOW_VIEWS};
    match (ctx.slot(SHADOW_ATLAS), ctx.slot(SHADOW_VIEWS)) {
        (Some(atlas), None) => errors.push(ctx.mismatch(
            atlas,
            "a shadow atlas is sampled through its view table: read the ShadowAtlas pass's shadow_views buffer too",
        )),
        (None, Some(views)) => errors.push(ctx.mismatch(
            views,
            "a view table is read with its atlas: read the ShadowAtlas pass's depth texture too",
        )),
        (Some(_), Some(_)) => {
            check_shadow_atlas_texture(ctx, errors);
            let other = [shadow_ray_jobs::SHADOW_MASK, shadow_ray_cast::BVH_NODES]
                .into_iter()
                .filter(|s| hybrid != Some(*s))
                .find_map(|s| ctx.slot(s));
            if let Some(other) = other {
                errors.push(ctx.mismatch(
                    other,
                    "a pass shadows its lights one way: from the atlas, the ray-cast mask or the BVH (the hybrid: forward, deferred and visibility shading read the atlas and the mask together, glass shading the atlas and the BVH)",
                ));
            }
        }
        (None, None) => {}
    }
}

/// The hybrid (the atlas and the mask read together): the jobs pass that writes the mask
/// reads the same view table, so it casts rays only for the lights without a map.
pub(crate) fn check_hybrid_jobs(ctx: &contracts::InputsCtx, errors: &mut Vec<GraphError>) {
    let (Some(mask), Some(views)) = (
        ctx.slot(shadow_ray_jobs::SHADOW_MASK),
        ctx.slot(shadow_atlas::SHADOW_VIEWS),
    ) else {
        return;
    };
    for (p, r) in ctx.passes() {
        let writes_mask = p.writes.iter().any(|w| w == mask);
        if writes_mask
            && matches!(p.kind, PassKind::ShadowRayJobs(_))
            && r.slot(shadow_atlas::SHADOW_VIEWS) != Some(views)
        {
            errors.push(ctx.mismatch(
                mask,
                format!(
                    "the pass samples the atlas for lights with a map in '{views}' and reads the mask for the rest, but jobs pass '{}' does not read '{views}': it would cast rays for every caster; add '{views}' to its reads",
                    p.name
                ),
            ));
        }
    }
}

/// A read shadow atlas is one a ShadowAtlas pass can have written.
pub(crate) fn check_shadow_atlas_texture(ctx: &KindCtx, errors: &mut Vec<GraphError>) {
    if let Some(atlas) = ctx.slot(shadow_atlas::SHADOW_ATLAS) {
        if shadow_atlas::atlas_side(ctx.graph.resources.get(atlas).copied()).is_none() {
            errors.push(ctx.mismatch(
                atlas,
                "a shadow atlas is a single-sample square depth texture of a fixed power-of-two size (size: Fixed(4096, 4096))",
            ));
        }
    }
}

/// What every shading pass (forward or deferred) needs to read its lights.
pub(crate) fn check_light_source(
    ctx: &KindCtx,
    lights: super::model::LightSource,
    errors: &mut Vec<GraphError>,
) {
    use super::model::LightSource;
    match (lights, ctx.slot(slot::LIGHT_LISTS)) {
        (LightSource::Culled, None) => errors.push(ctx.bad(
            "lights: Culled needs the light-list buffer of a LightCulling or LightLinkedList pass in reads",
        )),
        (LightSource::AllLights, Some(name)) => {
            errors.push(ctx.mismatch(name, "lights: AllLights reads no light lists"))
        }
        _ => {}
    }
}

/// An optional number written plainly (`capacity: 4096`, not `Some(4096)`).
pub(crate) fn plain_some<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<u32>, D::Error> {
    <u32 as serde::Deserialize>::deserialize(d).map(Some)
}

/// Writes a set optional number plainly; pair with `skip_serializing_if = "Option::is_none"`.
pub(crate) fn plain_u32<S: serde::Serializer>(v: &Option<u32>, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_u32(v.unwrap_or_default())
}

#[cfg(test)]
mod registry_tests {
    /// A kind is its folder under src/kinds/ (build.rs mounts it): the places kinds had
    /// files before hold only shared support, so a kind file left there (a merge of a
    /// branch from before the folders) is refused instead of lingering uncompiled.
    #[test]
    fn kind_files_live_in_their_folders() {
        let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let support: [(&str, &[&str]); 2] = [
            (
                "graph/kinds",
                &["mod", "matching", "contracts", "slots", "layout"],
            ),
            ("render/passes", &["mod"]),
        ];
        for (dir, shared) in support {
            for entry in std::fs::read_dir(src.join(dir)).unwrap() {
                let path = entry.unwrap().path();
                let stem = path.file_stem().unwrap().to_str().unwrap().to_string();
                assert!(
                    shared.contains(&stem.as_str()),
                    "src/{dir}/{stem}: a kind's files belong in its folder src/kinds/<kind>/ \
                     (docs/adding_a_pass_kind.md); only shared support stays here"
                );
            }
        }
    }
}

#[cfg(test)]
pub(crate) mod test_support {
    //! Validates a one-pass graph around a pass declaration, for the kinds' unit tests.
    use crate::graph::{check_text, GraphErrors};
    use crate::shader::ShaderLibrary;

    /// The depth prepass and the tiled culling pass many kinds' tests put first.
    pub const PREPASS: &str =
        r#"Pass(name: "pre", kind: DepthPrepass, reads: ["geometry"], writes: ["depth"]),"#;
    pub const CULL: &str = r#"Pass(name: "c", kind: LightCulling(tile: 16), reads: ["depth", "lg"], writes: ["lists"]),"#;

    /// A graph with the usual resources and `passes` (RON text), validated.
    pub fn validate(passes: &str, output: &str) -> Result<(), GraphErrors> {
        let text = format!(
            r#"Graph(
    name: "t",
    resources: [
        Texture(name: "depth", format: Depth32Float),
        Texture(name: "depth4", format: Depth32Float, samples: 4),
        Texture(name: "hdr", format: Rgba32Float),
        Texture(name: "hdr4", format: Rgba32Float, samples: 4),
        Texture(name: "pos", format: Rgba32Float),
        Texture(name: "nrm", format: Rgba32Float),
        Texture(name: "pos4", format: Rgba32Float, samples: 4),
        Texture(name: "nrm4", format: Rgba32Float, samples: 4),
        Texture(name: "small", format: Rgba8Unorm),
        Texture(name: "geo", format: Rgba32Float),
        Texture(name: "atlas", format: Depth32Float, size: Fixed(2048, 2048)),
        Texture(name: "atlas_odd", format: Depth32Float, size: Fixed(1000, 1000)),
        Texture(name: "atlas_f", format: R32Float, size: Fixed(2048, 2048)),
        Buffer(name: "views"),
        Buffer(name: "shadow_views"),
        Buffer(name: "jobs"),
        Buffer(name: "mask"),
        Buffer(name: "small_buf", size: Bytes(16)),
        Texture(name: "rsm_depth", format: Depth32Float, size: Fixed(256, 256)),
        Texture(name: "rsm_depth_f", format: R32Float, size: Fixed(256, 256)),
        Texture(name: "rsm_normal", format: Rgba32Float, size: Fixed(256, 256)),
        Texture(name: "rsm_flux", format: Rgba32Float, size: Fixed(256, 256)),
        Texture(name: "rsm_position", format: Rgba32Float, size: Fixed(256, 256)),
        Buffer(name: "rsm_views"),
        Buffer(name: "light_geometry"),
        Buffer(name: "light_properties"),
        Import(name: "bn", from: BvhNodes),
        Import(name: "bt", from: BvhTriangles),
        Texture(name: "vis", format: R32Uint),
        Texture(name: "vis4", format: R32Uint, samples: 4),
        Import(name: "vertices", from: Vertices),
        Import(name: "triangles", from: Triangles),
        Import(name: "material_triangles", from: MaterialTriangles),
        Texture(name: "visibility", format: R32Uint),
        Texture(name: "ids4", format: R32Uint, samples: 4),
        Texture(name: "fdepth", format: R32Float),
        Texture(name: "fdepth2", format: R32Float),
        Texture(name: "fdepth4", format: R32Float, samples: 4),
        Texture(name: "tdepth_f", format: R32Float),
        Buffer(name: "lists"),
        Buffer(name: "lists2"),
        Buffer(name: "links"),
        Import(name: "geometry", from: Geometry),
        Import(name: "lg", from: LightGeometry),
        Import(name: "lp", from: LightProperties),
    ],
    passes: [{passes}],
    output: "{output}",
    side_effects: [],
)"#
        );
        check_text(
            std::path::Path::new("t.ron"),
            &text,
            &ShaderLibrary::builtin(),
        )
        .map(|_| ())
    }

    /// The messages of a failed validation, joined.
    pub fn errors(passes: &str, output: &str) -> String {
        match validate(passes, output) {
            Ok(()) => panic!("expected errors for {passes}"),
            Err(e) => e.to_string(),
        }
    }
}
