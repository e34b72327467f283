//! Alpha-tested shadow rays: what a ray needs to tell whether the alpha-masked caster
//! triangle it hit is cut out where it hit, packed into one `u32` storage buffer
//! (`bvh_alpha`) that `shaders/shadow/bvh.wgsl` reads under `BVH_ALPHA_TEST`, and
//! the CPU twin of that reading ([`AlphaTable::cut_out`]).
//!
//! A masked material's alpha is a small expression (its `alpha` in the layered model:
//! constants, texture channels, the vertex alpha, `1 − x` and products), compiled here
//! into a few fixed-size operations. Its textures are copied as RGBA8 texels and
//! sampled by hand with the material's wrap modes, filter and uv transform, always at
//! level 0 (a shadow ray has no footprint to pick a mip level by; textures over
//! [`MAX_TEXTURE_SIDE`] keep the first mip level within it). Each masked triangle has
//! a record of its vertices' uvs and vertex alphas; the BVH triangle names it.
//!
//! Layout (words): a header `[records, record count, textures, texels]` (offsets of
//! their sections), then the programs, the texture records, the texels and the
//! triangle records.

use crate::material::model::{Filter, Scalar, ScalarExpr, Wrap};
use crate::material::{Material, TextureSlot};
use crate::scene::{Mesh, Scene};
use glam::{Vec2, Vec4};

/// Words of the header.
pub const HEADER_WORDS: usize = 4;
/// Words of one triangle record: program, three vertex alphas, three uvs of each set.
pub const RECORD_WORDS: usize = 16;
/// Words of one texture record: texels, width, height, flags, the uv transform's two rows.
pub const TEXTURE_WORDS: usize = 12;
/// Words of one operation: opcode (and channel), texture, value.
pub const OP_WORDS: usize = 3;
/// Values an alpha expression may hold at once (`BVH_ALPHA_STACK` in the WGSL).
pub const STACK: usize = 8;
/// Textures are copied at the first mip level no side of which is longer (or shorter
/// sides, where the whole table must fit a byte budget: [`AlphaTable::builder`]).
pub const MAX_TEXTURE_SIDE: u32 = 2048;
/// The shortest side a budget may shrink textures to before the alpha test is given up.
const MIN_TEXTURE_SIDE: u32 = 64;

/// Operation codes (`BVH_ALPHA_OP_*` in the WGSL).
pub(crate) const OP_CONST: u32 = 0;
pub(crate) const OP_TEXTURE: u32 = 1;
pub(crate) const OP_VERTEX_ALPHA: u32 = 2;
pub(crate) const OP_ONE_MINUS: u32 = 3;
pub(crate) const OP_MUL: u32 = 4;

/// Texture flags: wrap u (bits 0–1), wrap v (2–3), bilinear, sRGB, second uv set.
pub(crate) const FLAG_LINEAR: u32 = 1 << 4;
pub(crate) const FLAG_SRGB: u32 = 1 << 5;
pub(crate) const FLAG_UV1: u32 = 1 << 6;

pub(crate) const WRAP_REPEAT: u32 = 0;
pub(crate) const WRAP_CLAMP: u32 = 1;
pub(crate) const WRAP_MIRROR: u32 = 2;

/// The packed alpha data of a scene's masked casters, and its CPU reading.
#[derive(Clone, Debug, PartialEq)]
pub struct AlphaTable {
    /// The `bvh_alpha` buffer's words.
    pub words: Vec<u32>,
    /// What is not alpha-tested, and why (a material whose alpha could not be compiled,
    /// or every masked caster where the data would not fit): those triangles block rays
    /// as opaque ones do.
    pub unsupported: Vec<String>,
}

impl Default for AlphaTable {
    fn default() -> Self {
        AlphaTable {
            words: vec![0; HEADER_WORDS],
            unsupported: Vec::new(),
        }
    }
}

/// What [`AlphaTable::builder`] makes from a scene's materials, before the triangles.
pub(crate) struct AlphaBuilder {
    table: AlphaTable,
    /// Per scene material: the absolute word offset of its program, where it has one.
    programs: Vec<Option<u32>>,
    records: Vec<[u32; RECORD_WORDS]>,
}

/// An alpha-masked scene material, as its alpha is compiled from.
struct MaskedMaterial<'a> {
    /// Its index in `Scene::materials`.
    index: usize,
    name: &'a str,
    /// The layered material (an override's or the glTF mapping), or why it is not there.
    material: Result<Material, String>,
}

/// One texture as it is copied: which image, sampled how.
#[derive(PartialEq)]
struct TextureKey {
    image: *const crate::scene::TextureImage,
    flags: u32,
    matrix: [u32; 6],
}

impl AlphaTable {
    /// Compiles the alpha of every alpha-masked material of `scene` (by its index in
    /// `scene.materials`) whose meshes cast shadows; [`AlphaBuilder::push_triangle`] then
    /// adds their triangles. The whole table (with a record for each of those triangles)
    /// stays within `max_bytes` (a storage binding's limit): textures are copied at
    /// smaller mip levels until it fits, down to [`MIN_TEXTURE_SIDE`]; past that no
    /// triangle alpha-tests, and `unsupported` says why.
    pub(crate) fn builder(scene: &Scene, max_bytes: u64) -> AlphaBuilder {
        let masked = |m: &Mesh| {
            scene.casts_shadow(m)
                && scene
                    .materials
                    .get(m.material)
                    .is_some_and(|s| s.alpha_mode.is_masked())
        };
        let triangles: u64 = scene
            .meshes
            .iter()
            .filter(|m| masked(m))
            .map(|m| (m.indices.len() / 3) as u64)
            .sum();
        let record_bytes = 4 * RECORD_WORDS as u64 * triangles;
        // Each masked material read once (an override's file parsed once), whatever the
        // sides tried.
        let masked_materials: Vec<MaskedMaterial> = scene
            .materials
            .iter()
            .enumerate()
            .filter(|(_, surface)| surface.alpha_mode.is_masked())
            .map(|(index, surface)| MaskedMaterial {
                index,
                name: &surface.name,
                material: crate::render::materials::scene_material(scene, surface)
                    .map(|(material, _)| material)
                    .map_err(|e| e.to_string()),
            })
            .collect();
        let count = scene.materials.len();
        let mut side = MAX_TEXTURE_SIDE;
        loop {
            let builder = Self::builder_with_side(&masked_materials, count, side);
            let bytes = 4 * builder.table.words.len() as u64 + record_bytes;
            if bytes <= max_bytes || triangles == 0 {
                return builder;
            }
            if side <= MIN_TEXTURE_SIDE {
                let mut none = Self::builder_with_side(&[], count, side);
                none.table.unsupported.push(format!(
                    "any masked caster: their alpha data takes {} MiB with textures of {side} texels a side, over the {} MiB a storage binding holds here",
                    bytes.div_ceil(1 << 20),
                    max_bytes >> 20
                ));
                return none;
            }
            side /= 2;
        }
    }

    /// [`Self::builder`] over `masked` (of `count` scene materials) with textures at most
    /// `side` texels a side, whatever the bytes.
    fn builder_with_side(masked: &[MaskedMaterial], count: usize, side: u32) -> AlphaBuilder {
        let mut programs_words: Vec<u32> = Vec::new();
        let mut programs = vec![None; count];
        let mut textures: Vec<(TextureKey, [u32; TEXTURE_WORDS])> = Vec::new();
        let mut texels: Vec<u32> = Vec::new();
        let mut unsupported = Vec::new();
        for m in masked {
            let compiled = m
                .material
                .as_ref()
                .map_err(Clone::clone)
                .and_then(|material| {
                    compile(material, side, &mut textures, &mut texels)
                        .map_err(|why| format!("its alpha {why}"))
                });
            match compiled {
                Ok(words) => {
                    programs[m.index] = Some(programs_words.len() as u32);
                    programs_words.extend(words);
                }
                Err(why) => unsupported.push(format!("material '{}': {why}", m.name)),
            }
        }
        let textures_at = HEADER_WORDS + programs_words.len();
        let texels_at = textures_at + TEXTURE_WORDS * textures.len();
        let mut words = vec![0u32; HEADER_WORDS];
        words[2] = textures_at as u32;
        words[3] = texels_at as u32;
        words.extend(programs_words);
        words.extend(textures.iter().flat_map(|(_, t)| *t));
        words.extend(texels);
        AlphaBuilder {
            table: AlphaTable { words, unsupported },
            programs: programs
                .into_iter()
                .map(|p| p.map(|p| p + HEADER_WORDS as u32))
                .collect(),
            records: Vec::new(),
        }
    }

    /// Triangle records in the table.
    pub fn records(&self) -> u32 {
        self.words[1]
    }

    /// Whether a ray crossing record `record`'s triangle at barycentrics (`u`, `v`)
    /// (weights of its second and third vertex) passes through a cut-out part: the
    /// material's alpha there is under its cutoff. The CPU twin of `bvh_alpha_cut_out`
    /// in `shaders/shadow/bvh.wgsl`, in the same f32 steps.
    pub fn cut_out(&self, record: u32, u: f32, v: f32) -> bool {
        let w = &self.words;
        let get = |i: usize| w.get(i).copied().unwrap_or(0);
        let at = get(0) as usize + RECORD_WORDS * record as usize;
        let f = |i: usize| f32::from_bits(get(i));
        let bary = |i: usize| f(i) * (1.0 - u - v) + f(i + 1) * u + f(i + 2) * v;
        let uv = |i: usize| Vec2::new(bary2(&f, i, 0, u, v), bary2(&f, i, 1, u, v));
        let vertex_alpha = bary(at + 1);
        let (uv0, uv1) = (uv(at + 4), uv(at + 10));
        let program = get(at) as usize;
        let cutoff = f(program);
        let count = (get(program + 1) as usize).min(64);
        let mut stack = [0f32; STACK];
        let mut sp = 0usize;
        for k in 0..count {
            let op = program + 2 + OP_WORDS * k;
            let code = get(op) & 0xff;
            let value = f(op + 2);
            let x = match code {
                OP_CONST => value,
                OP_TEXTURE => {
                    let channel = (get(op) >> 8) as usize & 3;
                    let texture = get(2) as usize + TEXTURE_WORDS * get(op + 1) as usize;
                    let uv = if get(texture + 3) & FLAG_UV1 != 0 {
                        uv1
                    } else {
                        uv0
                    };
                    sample(&get, texture, uv)[channel] * value
                }
                OP_VERTEX_ALPHA => vertex_alpha,
                OP_ONE_MINUS => 1.0 - stack[sp.saturating_sub(1)],
                _ => stack[sp.saturating_sub(2)] * stack[sp.saturating_sub(1)],
            };
            // One-operand operations replace their operand; products pop two.
            match code {
                OP_ONE_MINUS => sp = sp.saturating_sub(1),
                OP_MUL => sp = sp.saturating_sub(2),
                _ => {}
            }
            if sp < STACK {
                stack[sp] = x;
                sp += 1;
            }
        }
        let alpha = stack[0].clamp(0.0, 1.0);
        // As the rasterizers' alpha test: kept where alpha >= cutoff. NaN alpha keeps.
        alpha < cutoff
    }
}

/// Coordinate `c` of the uv whose three vertices start at word `i`, interpolated.
fn bary2(f: &impl Fn(usize) -> f32, i: usize, c: usize, u: f32, v: f32) -> f32 {
    f(i + c) * (1.0 - u - v) + f(i + 2 + c) * u + f(i + 4 + c) * v
}

/// The texel at integer coordinates already wrapped into the texture, decoded.
fn texel(get: &impl Fn(usize) -> u32, texture: usize, x: i32, y: i32) -> Vec4 {
    let (width, height, flags) = (get(texture + 1), get(texture + 2), get(texture + 3));
    let x = x.clamp(0, width as i32 - 1) as usize;
    let y = y.clamp(0, height as i32 - 1) as usize;
    let at = texel_base(get) + get(texture) as usize + y * width as usize + x;
    let t = get(at);
    let byte = |k: u32| ((t >> (8 * k)) & 0xff) as f32 / 255.0;
    let decode = |c: f32| {
        if flags & FLAG_SRGB == 0 {
            c
        } else if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    Vec4::new(decode(byte(0)), decode(byte(1)), decode(byte(2)), byte(3))
}

fn texel_base(get: &impl Fn(usize) -> u32) -> usize {
    get(3) as usize
}

/// A coordinate in [0, 1] (repeat and mirror folded there; clamp clamped), so texel
/// indices stay within one texel of the texture. Not finite: 0.
fn fold(c: f32, wrap: u32) -> f32 {
    // As the WGSL, which cannot test for NaN directly.
    if c.is_nan() || c.abs() >= 3.0e38 {
        return 0.0;
    }
    match wrap {
        WRAP_REPEAT => c - c.floor(),
        WRAP_MIRROR => {
            let m = c - 2.0 * (c * 0.5).floor();
            if m > 1.0 {
                2.0 - m
            } else {
                m
            }
        }
        _ => c.clamp(0.0, 1.0),
    }
}

/// A texel index one past either side wrapped back (repeat), else clamped (a mirror
/// folded into [0, 1] repeats its edge texel there, as clamp does).
fn wrap_index(i: i32, n: i32, wrap: u32) -> i32 {
    if wrap == WRAP_REPEAT {
        (i + n) % n
    } else {
        i.clamp(0, n - 1)
    }
}

/// The texture at `uv` (after its transform), level 0, nearest or bilinear.
fn sample(get: &impl Fn(usize) -> u32, texture: usize, uv: Vec2) -> Vec4 {
    let f = |i: usize| f32::from_bits(get(i));
    let m = texture + 4;
    let uv = Vec2::new(
        f(m) * uv.x + f(m + 1) * uv.y + f(m + 2),
        f(m + 3) * uv.x + f(m + 4) * uv.y + f(m + 5),
    );
    let (width, height, flags) = (get(texture + 1), get(texture + 2), get(texture + 3));
    let (wrap_u, wrap_v) = (flags & 3, (flags >> 2) & 3);
    let (n, h) = (width.max(1) as i32, height.max(1) as i32);
    let x = fold(uv.x, wrap_u) * n as f32;
    let y = fold(uv.y, wrap_v) * h as f32;
    if flags & FLAG_LINEAR == 0 {
        let (i, j) = ((x.floor() as i32).min(n - 1), (y.floor() as i32).min(h - 1));
        return texel(get, texture, i, j);
    }
    let (x, y) = (x - 0.5, y - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (tx, ty) = (x - x0, y - y0);
    let (i0, j0) = (x0 as i32, y0 as i32);
    let (i0w, i1w) = (wrap_index(i0, n, wrap_u), wrap_index(i0 + 1, n, wrap_u));
    let (j0w, j1w) = (wrap_index(j0, h, wrap_v), wrap_index(j0 + 1, h, wrap_v));
    let a = texel(get, texture, i0w, j0w);
    let b = texel(get, texture, i1w, j0w);
    let c = texel(get, texture, i0w, j1w);
    let d = texel(get, texture, i1w, j1w);
    let top = a + (b - a) * tx;
    let bottom = c + (d - c) * tx;
    top + (bottom - top) * ty
}

/// The program words of `material`'s alpha: cutoff, operation count, operations.
fn compile(
    material: &Material,
    side: u32,
    textures: &mut Vec<(TextureKey, [u32; TEXTURE_WORDS])>,
    texels: &mut Vec<u32>,
) -> Result<Vec<u32>, String> {
    let desc = material.desc();
    let cutoff = desc.alpha_mode.cutoff();
    let mut ops: Vec<[u32; OP_WORDS]> = Vec::new();
    let mut copy = |slot: &TextureSlot| texture_index(slot, side, textures, texels);
    let depth = emit(&desc.alpha, material.texture_slots(), &mut copy, &mut ops)?;
    if depth > STACK {
        return Err(format!("needs {depth} values at once, over {STACK}"));
    }
    let mut words = vec![cutoff.to_bits(), ops.len() as u32];
    words.extend(ops.iter().flatten());
    Ok(words)
}

/// Appends the operations of `s` (postfix); returns the values it holds at most.
fn emit(
    s: &Scalar,
    slots: &[TextureSlot],
    copy: &mut impl FnMut(&TextureSlot) -> Result<u32, String>,
    ops: &mut Vec<[u32; OP_WORDS]>,
) -> Result<usize, String> {
    Ok(match s {
        Scalar::Val(x) => {
            ops.push([OP_CONST, 0, x.to_bits()]);
            1
        }
        Scalar::Expr(ScalarExpr::Tex {
            texture,
            channel,
            scale,
        }) => {
            let slot = slots
                .iter()
                .find(|s| &s.name == texture)
                .ok_or_else(|| format!("reads texture '{texture}', which it does not declare"))?;
            let index = copy(slot)?;
            ops.push([
                OP_TEXTURE | ((channel.index() as u32) << 8),
                index,
                scale.to_bits(),
            ]);
            1
        }
        Scalar::Expr(ScalarExpr::VertexAlpha) => {
            ops.push([OP_VERTEX_ALPHA, 0, 0]);
            1
        }
        Scalar::Expr(ScalarExpr::OneMinus(a)) => {
            let d = emit(a, slots, copy, ops)?;
            ops.push([OP_ONE_MINUS, 0, 0]);
            d
        }
        Scalar::Expr(ScalarExpr::Mul(a, b)) => {
            let da = emit(a, slots, copy, ops)?;
            let db = emit(b, slots, copy, ops)?;
            ops.push([OP_MUL, 0, 0]);
            da.max(db + 1)
        }
    })
}

/// The index of `slot`'s texture record, copying its texels (at most `side` a side) the
/// first time.
fn texture_index(
    slot: &TextureSlot,
    side: u32,
    textures: &mut Vec<(TextureKey, [u32; TEXTURE_WORDS])>,
    texels: &mut Vec<u32>,
) -> Result<u32, String> {
    let image = slot.source.load().map_err(|e| e.to_string())?;
    let wrap = |w: Wrap| match w {
        Wrap::Repeat => WRAP_REPEAT,
        Wrap::ClampToEdge => WRAP_CLAMP,
        Wrap::MirroredRepeat => WRAP_MIRROR,
    };
    let mut flags = wrap(slot.sampler.wrap_u) | (wrap(slot.sampler.wrap_v) << 2);
    if slot.sampler.mag_filter == Filter::Linear {
        flags |= FLAG_LINEAR;
    }
    if image.srgb {
        flags |= FLAG_SRGB;
    }
    if slot.tex_coord == 1 {
        flags |= FLAG_UV1;
    }
    let matrix = slot
        .transform
        .map_or([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], |t| t.matrix());
    let key = TextureKey {
        image: std::sync::Arc::as_ptr(&image),
        flags,
        matrix: [
            matrix[0][0],
            matrix[0][1],
            matrix[0][2],
            matrix[1][0],
            matrix[1][1],
            matrix[1][2],
        ]
        .map(f32::to_bits),
    };
    if let Some(i) = textures.iter().position(|(k, _)| *k == key) {
        return Ok(i as u32);
    }
    let (width, height, bytes) = level_within(&image, side)?;
    let mut record = [0u32; TEXTURE_WORDS];
    record[0] = texels.len() as u32;
    record[1] = width;
    record[2] = height;
    record[3] = flags;
    record[4..10].copy_from_slice(&key.matrix);
    texels.extend(
        bytes
            .chunks_exact(4)
            .map(|p| u32::from_le_bytes([p[0], p[1], p[2], p[3]])),
    );
    textures.push((key, record));
    Ok(textures.len() as u32 - 1)
}

/// Level 0 of `image`, or its first mip level within `side`.
fn level_within(
    image: &crate::scene::TextureImage,
    side: u32,
) -> Result<(u32, u32, Vec<u8>), String> {
    let (w, h) = (image.width, image.height);
    if w.max(h) <= side {
        return Ok((w, h, image.rgba8.clone()));
    }
    let chain = crate::render::texture_mips::mip_chain(w, h, &image.rgba8, image.srgb)?;
    let mut at = 0usize;
    let mut level = 0;
    loop {
        let (lw, lh) = ((w >> level).max(1), (h >> level).max(1));
        let bytes = 4 * lw as usize * lh as usize;
        if lw.max(lh) <= side {
            return Ok((lw, lh, chain.rgba8[at..at + bytes].to_vec()));
        }
        at += bytes;
        level += 1;
    }
}

impl AlphaBuilder {
    /// Whether `material` (an index into `scene.materials`) alpha-tests rays.
    pub(crate) fn tests(&self, material: usize) -> bool {
        self.programs.get(material).is_some_and(|p| p.is_some())
    }

    /// A record for triangle `t` (three indices) of `mesh`, whose material tests rays;
    /// returns what its BVH triangle holds: 1 + the record's index.
    pub(crate) fn push_triangle(&mut self, mesh: &Mesh, t: [u32; 3]) -> u32 {
        let program = self
            .programs
            .get(mesh.material)
            .copied()
            .flatten()
            .unwrap_or(0);
        let mut r = [0u32; RECORD_WORDS];
        r[0] = program;
        for (k, &i) in t.iter().enumerate() {
            let i = i as usize;
            let alpha = mesh.colors.get(i).map_or(1.0, |c| c.w);
            r[1 + k] = alpha.to_bits();
            let uv0 = mesh.uvs.get(i).copied().unwrap_or(Vec2::ZERO);
            let uv1 = mesh.uvs1.get(i).copied().unwrap_or(Vec2::ZERO);
            r[4 + 2 * k] = uv0.x.to_bits();
            r[5 + 2 * k] = uv0.y.to_bits();
            r[10 + 2 * k] = uv1.x.to_bits();
            r[11 + 2 * k] = uv1.y.to_bits();
        }
        self.records.push(r);
        self.records.len() as u32
    }

    /// The finished table.
    pub(crate) fn finish(self) -> AlphaTable {
        let mut table = self.table;
        table.words[0] = table.words.len() as u32;
        table.words[1] = self.records.len() as u32;
        table.words.extend(self.records.iter().flatten());
        table
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folding_keeps_coordinates_in_the_texture() {
        assert_eq!(fold(1.25, WRAP_REPEAT), 0.25);
        assert_eq!(fold(-0.25, WRAP_REPEAT), 0.75);
        assert_eq!(fold(1.25, WRAP_MIRROR), 0.75);
        assert_eq!(fold(-0.25, WRAP_MIRROR), 0.25);
        assert_eq!(fold(2.25, WRAP_MIRROR), 0.25);
        assert_eq!(fold(-3.0, WRAP_CLAMP), 0.0);
        assert_eq!(fold(f32::NAN, WRAP_REPEAT), 0.0);
        assert_eq!(wrap_index(-1, 8, WRAP_REPEAT), 7);
        assert_eq!(wrap_index(8, 8, WRAP_REPEAT), 0);
        assert_eq!(wrap_index(8, 8, WRAP_MIRROR), 7);
    }
}
