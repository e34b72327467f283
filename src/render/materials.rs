//! Materials as the renderer sees them: the layered material's generated WGSL (the
//! `<material>` include of `shaders/forward/forward.wgsl`), its textures uploaded into
//! bind group 2, and what the pipelines need to know.

use super::bind::{BindingSet, Bound};
use crate::material::model::{Filter, MipmapFilter, SamplerDesc, Wrap};
use crate::material::{Material, MaterialError, TextureSource};
use crate::scene::{AlphaMode, Scene, SurfaceMaterial};
use std::path::PathBuf;
use wgpu::util::DeviceExt;

/// Where `MaterialProgram::shared_wgsl` binds its constants (group 0): a binding every
/// shader that includes shared material code leaves free.
pub(crate) const CONSTANTS_BINDING: u32 = 20;

/// The materials of `shaded` (indices into `materials`, ascending) in groups that one
/// visibility-shading dispatch shades together, in the order of their first material,
/// each ascending: materials whose `shared_wgsl` is the same text (they differ only in
/// constants) and whose textures are the same images through the same samplers (none,
/// or glTF materials that read one texture with other factors) form one group; a
/// dispatch binds one material's textures.
pub fn shared_code_groups(materials: &[MaterialProgram], shaded: &[usize]) -> Vec<Vec<usize>> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut by_code: std::collections::HashMap<(&str, Option<&str>), usize> = Default::default();
    for &i in shaded {
        let m = &materials[i];
        let key = (m.shared_wgsl.as_str(), m.texture_key.as_deref());
        match by_code.get(&key) {
            Some(&g) => groups[g].push(i),
            None => {
                by_code.insert(key, groups.len());
                groups.push(vec![i]);
            }
        }
    }
    groups
}

/// The constants of a pass's shading groups in one buffer (`material_constants`, where
/// `shared_wgsl` reads them) and where each material's begin: one table for visibility
/// and deferred shading.
pub(crate) struct GroupConstants {
    /// Per material index: its first constant (0 for a material in no group).
    pub first: Vec<u32>,
    /// Every grouped material's constants, group by group.
    pub values: Vec<f32>,
}

impl GroupConstants {
    pub(crate) fn new(materials: &[MaterialProgram], groups: &[Vec<usize>]) -> Self {
        let mut first = vec![0u32; materials.len()];
        let mut values = Vec::new();
        for &i in groups.iter().flatten() {
            first[i] = values.len() as u32;
            values.extend_from_slice(&materials[i].constants);
        }
        Self { first, values }
    }

    /// Offers the constants as `material_constants` (one zero where there are none: a
    /// binding is never empty).
    pub(in crate::render) fn offer(&self, device: &wgpu::Device, offered: &mut BindingSet) {
        let values: &[f32] = if self.values.is_empty() {
            &[0.0]
        } else {
            &self.values
        };
        let buffer = super::scene_gpu::storage_buffer(
            device,
            "material constants",
            bytemuck::cast_slice(values),
            wgpu::BufferUsages::empty(),
        );
        offered.buffer("material_constants", &buffer);
    }
}

/// The pipeline label of a shading group's dispatch in pass `pass`: its first material,
/// and how many more share its code.
pub(crate) fn group_label(pass: &str, materials: &[MaterialProgram], group: &[usize]) -> String {
    let name = &materials[group[0]].name;
    match group.len() {
        1 => format!("{pass} (material '{name}')"),
        n => format!("{pass} (material '{name}' and {} sharing its code)", n - 1),
    }
}

/// Which image a texture slot reads: a file and its encoding, or the decoded image itself
/// (a glTF importer hands materials that read one image the same one).
fn image_key(source: &TextureSource) -> String {
    match source {
        TextureSource::File { path, srgb } => format!("{}:{srgb}", path.display()),
        TextureSource::Image(image) => format!("{:p}", std::sync::Arc::as_ptr(image)),
    }
}

/// The GPU textures uploaded for a scene's materials, by [`image_key`]: materials that
/// read one image share one copy.
#[derive(Default)]
pub(crate) struct TextureUploads {
    views: std::collections::HashMap<String, wgpu::TextureView>,
}

/// Each texture slot's image ([`image_key`]) and sampler.
fn texture_key(slots: &[crate::material::TextureSlot]) -> String {
    slots
        .iter()
        .map(|slot| {
            format!(
                "{}={}/{:?}",
                slot.binding,
                image_key(&slot.source),
                slot.sampler
            )
        })
        .collect::<Vec<_>>()
        .join(";")
}

/// One scene material compiled for the GPU: its generated WGSL, its textures uploaded and
/// bound, and what pipelines need to know about it.
#[derive(Clone)]
pub struct MaterialProgram {
    /// The material's name (from the scene or material file).
    pub name: String,
    /// Generated WGSL, included as `<material>`.
    pub wgsl: String,
    /// The same for compute shaders (textures sampled with explicit derivatives, see
    /// `WgslOptions::sample_grad`); None when `wgsl` has no textures, so serves as is.
    pub compute_wgsl: Option<String>,
    /// The compute code with its constants read from a buffer (`WgslOptions::
    /// constants_binding` at `CONSTANTS_BINDING`): the same text for every material
    /// that differs from this one only in its constants, so visibility shading shades
    /// them in one dispatch.
    pub shared_wgsl: String,
    /// The constants `shared_wgsl` reads, in its order.
    pub constants: Vec<f32>,
    /// What the textures are (each slot's image and sampler): materials whose shared code
    /// and textures are the same can share one dispatch and its bind group. None
    /// without textures.
    pub texture_key: Option<String>,
    /// How the material blends: opaque, alpha-masked or blended.
    pub alpha_mode: AlphaMode,
    /// Whether back faces are drawn (and lit) too.
    pub double_sided: bool,
    /// Group 2's sampler and textures by binding name; None without textures.
    pub(super) textures: Option<BindingSet>,
    /// GPU bytes of the textures this material uploaded, every mip level included (4/3 of
    /// level 0); an image an earlier material of the scene uploaded counts there only.
    pub texture_bytes: u64,
    /// Whether shading reads the uv or the tangent ([`Material::reads_uv_or_tangent`]).
    pub reads_uv_or_tangent: bool,
    /// Whether shading reads the vertex colour ([`MaterialDesc::reads_vertex_color`]).
    ///
    /// [`MaterialDesc::reads_vertex_color`]: crate::material::model::MaterialDesc::reads_vertex_color
    pub reads_vertex_color: bool,
    /// Whether a texture samples TEXCOORD_1 ([`Material::reads_uv1`]).
    pub reads_uv1: bool,
}

impl MaterialProgram {
    /// The material code a compute shader includes.
    pub(crate) fn wgsl_for_compute(&self) -> &str {
        self.compute_wgsl.as_deref().unwrap_or(&self.wgsl)
    }

    /// The code a shading group's dispatch includes: `shared_wgsl` (its constants read
    /// from `material_constants`, the shader told so by `SHARED_CODE`) where the material
    /// shares its code, else its own.
    pub(crate) fn group_code(&self, shared: bool) -> &str {
        if shared {
            &self.shared_wgsl
        } else {
            self.wgsl_for_compute()
        }
    }

    /// Generates `material`'s WGSL and uploads its textures (with mip levels) for bind
    /// group 2.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        material: &Material,
        alpha_mode: AlphaMode,
        double_sided: bool,
    ) -> Result<Self, MaterialError> {
        let mut uploads = TextureUploads::default();
        Self::new_sharing(
            device,
            queue,
            material,
            alpha_mode,
            double_sided,
            &mut uploads,
        )
    }

    /// [`Self::new`], with the textures that `uploads` already holds (an image another
    /// material of the scene read) bound instead of uploaded again; those it uploads
    /// are added.
    pub(crate) fn new_sharing(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        material: &Material,
        alpha_mode: AlphaMode,
        double_sided: bool,
        uploads: &mut TextureUploads,
    ) -> Result<Self, MaterialError> {
        let code = MaterialCode::generate(material)?;
        Self::with_code(
            device,
            queue,
            material,
            code,
            alpha_mode,
            double_sided,
            uploads,
        )
    }

    /// [`Self::new_sharing`] with `material`'s code already generated.
    fn with_code(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        material: &Material,
        code: MaterialCode,
        alpha_mode: AlphaMode,
        double_sided: bool,
        uploads: &mut TextureUploads,
    ) -> Result<Self, MaterialError> {
        let MaterialCode {
            wgsl,
            compute_wgsl,
            shared_wgsl,
            constants,
        } = code;
        let slots = material.texture_slots();
        let texture_key = (!slots.is_empty()).then(|| texture_key(slots));
        // Offered by the names the generated WGSL declares (`material_sampler`,
        // `material_tex{i}`); the layout comes from reflecting the composed shader.
        let mut texture_bytes = 0u64;
        let textures = if slots.is_empty() {
            None
        } else {
            let mut set = BindingSet::default();
            // One sampler per distinct sampler of the slots (glTF samplers), by the names
            // the generated WGSL declares.
            let (samplers, _) = material.samplers();
            for (k, desc) in samplers.iter().enumerate() {
                let name = crate::material::sampler_wgsl_name(k);
                set.offer(
                    &name,
                    Bound::Sampler(device.create_sampler(&sampler_descriptor(&name, desc))),
                );
            }
            for (i, slot) in slots.iter().enumerate() {
                let name = format!("material_tex{i}");
                let key = image_key(&slot.source);
                if let Some(view) = uploads.views.get(&key) {
                    set.offer(&name, Bound::View(view.clone()));
                    continue;
                }
                let image = slot.source.load()?;
                let max = device.limits().max_texture_dimension_2d;
                let fitted = super::texture_fit::fit_to_device(&image, max, material.path())
                    .map_err(|message| MaterialError::TextureDecode {
                        name: image.name.clone(),
                        path: material.path().to_path_buf(),
                        message,
                    })?;
                let image = fitted.as_ref().unwrap_or(&image);
                let chain = super::texture_mips::mip_chain(
                    image.width,
                    image.height,
                    &image.rgba8,
                    image.srgb,
                )
                .map_err(|message| MaterialError::TextureDecode {
                    name: image.name.clone(),
                    path: material.path().to_path_buf(),
                    message,
                })?;
                // The chain adds a third to level 0; said, so a memory report can add it.
                texture_bytes += chain.rgba8.len() as u64;
                log::debug!(
                    "material {}: texture {} {}×{}, {} mip levels, {} bytes",
                    material.name(),
                    image.name,
                    image.width,
                    image.height,
                    chain.levels,
                    chain.rgba8.len()
                );
                let format = if image.srgb {
                    wgpu::TextureFormat::Rgba8UnormSrgb
                } else {
                    wgpu::TextureFormat::Rgba8Unorm
                };
                let texture = device.create_texture_with_data(
                    queue,
                    &wgpu::TextureDescriptor {
                        label: Some(&image.name),
                        size: wgpu::Extent3d {
                            width: image.width,
                            height: image.height,
                            depth_or_array_layers: 1,
                        },
                        mip_level_count: chain.levels,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D2,
                        format,
                        usage: wgpu::TextureUsages::TEXTURE_BINDING,
                        view_formats: &[],
                    },
                    wgpu::util::TextureDataOrder::LayerMajor,
                    &chain.rgba8,
                );
                let view = texture.create_view(&Default::default());
                uploads.views.insert(key, view.clone());
                set.offer(&name, Bound::View(view));
            }
            Some(set)
        };
        Ok(Self {
            name: material.name().to_string(),
            wgsl,
            compute_wgsl,
            shared_wgsl,
            constants,
            texture_key,
            alpha_mode,
            double_sided,
            textures,
            texture_bytes,
            reads_uv_or_tangent: material.reads_uv_or_tangent(),
            reads_vertex_color: material.desc().reads_vertex_color(),
            reads_uv1: material.reads_uv1(),
        })
    }

    /// One program per scene material: glTF materials map exactly onto the layered
    /// model; `material_overrides` replace a material by name with a RON material.
    pub fn for_scene(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
    ) -> Result<Vec<Self>, MaterialError> {
        let defaults = [crate::scene::SurfaceMaterial::default()];
        let surfaces = if scene.materials.is_empty() {
            &defaults[..]
        } else {
            &scene.materials[..]
        };
        let materials = surfaces
            .iter()
            .map(|surface| scene_material(scene, surface).map(|(m, _)| m))
            .collect::<Result<Vec<_>, _>>()?;
        let codes = MaterialCode::generate_all(&materials);
        let mut uploads = TextureUploads::default();
        surfaces
            .iter()
            .zip(materials.iter().zip(codes))
            .map(|(surface, (material, code))| {
                Self::with_code(
                    device,
                    queue,
                    material,
                    code?,
                    surface.alpha_mode,
                    surface.double_sided,
                    &mut uploads,
                )
            })
            .collect()
    }

    /// The program for one scene material, and the files it was read from (the override
    /// RON and its texture files; none for a material mapped from glTF).
    pub(crate) fn for_surface(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        surface: &SurfaceMaterial,
        uploads: &mut TextureUploads,
    ) -> Result<(Self, Vec<PathBuf>), MaterialError> {
        let (material, files) = scene_material(scene, surface)?;
        let program = Self::new_sharing(
            device,
            queue,
            &material,
            surface.alpha_mode,
            surface.double_sided,
            uploads,
        )?;
        Ok((program, files))
    }
}

/// The layered material a scene material stands for, and the files it was read from:
/// its override RON (and texture files) where the scene names one, else the glTF
/// material mapped onto the layered model.
pub(crate) fn scene_material(
    scene: &Scene,
    surface: &SurfaceMaterial,
) -> Result<(Material, Vec<PathBuf>), MaterialError> {
    match override_path(scene, &surface.name) {
        Some(path) => {
            let material = Material::load(&path).and_then(|m| m.wgsl().map(|_| m));
            let material = material.map_err(|e| override_error(scene, &surface.name, e))?;
            let mut files = vec![path];
            files.extend(
                material
                    .texture_slots()
                    .iter()
                    .filter_map(|s| match &s.source {
                        TextureSource::File { path, .. } => Some(path.clone()),
                        TextureSource::Image(_) => None,
                    }),
            );
            Ok((material, files))
        }
        None => Ok((Material::from_surface(surface), Vec::new())),
    }
}

/// A material's generated WGSL: its own, the compute copy of a textured one (gradient
/// sampling), and the shared copy that reads its constants from a buffer (grouping),
/// with those constants. Pure CPU work, apart from any device.
struct MaterialCode {
    wgsl: String,
    compute_wgsl: Option<String>,
    shared_wgsl: String,
    constants: Vec<f32>,
}

impl MaterialCode {
    fn generate(material: &Material) -> Result<Self, MaterialError> {
        let wgsl = material.renderer_wgsl(&Default::default())?;
        let textured = !material.texture_slots().is_empty();
        let compute_wgsl = if textured {
            Some(material.renderer_wgsl(&crate::material::WgslOptions {
                sample_grad: true,
                ..Default::default()
            })?)
        } else {
            None
        };
        let (shared_wgsl, constants) =
            material.renderer_wgsl_with_constants(&crate::material::WgslOptions {
                sample_grad: textured,
                constants_binding: Some(CONSTANTS_BINDING),
                ..Default::default()
            })?;
        Ok(Self {
            wgsl,
            compute_wgsl,
            shared_wgsl,
            constants,
        })
    }

    /// Each material's code, in order, generated on every core (a scene's materials are
    /// independent; the gallery's 142 take 0.38 s on one core of the development
    /// machine).
    fn generate_all(materials: &[Material]) -> Vec<Result<Self, MaterialError>> {
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .min(materials.len())
            .max(1);
        let chunk = materials.len().div_ceil(threads).max(1);
        std::thread::scope(|s| {
            let handles: Vec<_> = materials
                .chunks(chunk)
                .map(|part| s.spawn(move || part.iter().map(Self::generate).collect::<Vec<_>>()))
                .collect();
            handles
                .into_iter()
                .flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
                .collect()
        })
    }
}

/// The wgpu sampler of a material sampler. Textures carry full mip chains
/// (texture_mips.rs); `MipmapFilter::None` clamps the level of detail to 0.25 with the
/// nearest level: level 0 only, while min_filter still applies where minified (a clamp
/// of 0 would make every sample magnified, as the Vulkan spec notes).
fn sampler_descriptor<'a>(label: &'a str, d: &SamplerDesc) -> wgpu::SamplerDescriptor<'a> {
    let wrap = |w: Wrap| match w {
        Wrap::Repeat => wgpu::AddressMode::Repeat,
        Wrap::ClampToEdge => wgpu::AddressMode::ClampToEdge,
        Wrap::MirroredRepeat => wgpu::AddressMode::MirrorRepeat,
    };
    let filter = |f: Filter| match f {
        Filter::Nearest => wgpu::FilterMode::Nearest,
        Filter::Linear => wgpu::FilterMode::Linear,
    };
    let (mipmap_filter, lod_max_clamp) = match d.mipmap_filter {
        MipmapFilter::None => (wgpu::MipmapFilterMode::Nearest, 0.25),
        MipmapFilter::Nearest => (wgpu::MipmapFilterMode::Nearest, 32.0),
        MipmapFilter::Linear => (wgpu::MipmapFilterMode::Linear, 32.0),
    };
    wgpu::SamplerDescriptor {
        label: Some(label),
        address_mode_u: wrap(d.wrap_u),
        address_mode_v: wrap(d.wrap_v),
        mag_filter: filter(d.mag_filter),
        min_filter: filter(d.min_filter),
        mipmap_filter,
        lod_max_clamp,
        ..Default::default()
    }
}

/// An override's error, named with the scene file and the material it replaces.
pub fn override_error(scene: &Scene, name: &str, e: MaterialError) -> MaterialError {
    MaterialError::Override {
        scene: scene.source_path.clone().unwrap_or_default(),
        name: name.to_string(),
        source: Box::new(e),
    }
}

/// The material RON that replaces the scene material `name`, if the scene overrides it:
/// the path as written if it exists, else relative to the scene file's folder.
pub fn override_path(scene: &Scene, name: &str) -> Option<PathBuf> {
    let (_, path) = scene.material_overrides.iter().find(|(n, _)| n == name)?;
    let base = scene.source_path.as_deref().and_then(|p| p.parent());
    Some(match base {
        Some(dir) if path.is_relative() && !path.exists() => dir.join(path),
        _ => path.clone(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Generated on every core, each material keeps its own code, in order: the same
    /// text as one at a time (eleven materials: chunks of unequal length on any core
    /// count).
    #[test]
    fn code_generated_in_parallel_is_each_materials_in_order() {
        let materials: Vec<Material> = (0..11)
            .map(|i| {
                Material::from_surface(&SurfaceMaterial {
                    name: format!("m{i}"),
                    base_color: glam::Vec4::new(i as f32 / 10.0, 0.5, 0.25, 1.0),
                    roughness: 0.05 + i as f32 / 20.0,
                    ..Default::default()
                })
            })
            .collect();
        let parallel = MaterialCode::generate_all(&materials);
        assert_eq!(parallel.len(), materials.len());
        for (m, code) in materials.iter().zip(parallel) {
            let code = code.expect("valid code");
            let one = MaterialCode::generate(m).expect("valid code");
            assert_eq!(code.wgsl, one.wgsl);
            assert_eq!(code.shared_wgsl, one.shared_wgsl);
            assert_eq!(code.constants, one.constants);
        }
    }
}
