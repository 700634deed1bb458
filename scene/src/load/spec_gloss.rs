//! KHR_materials_pbrSpecularGlossiness textures baked into metallic-roughness ones.
//!
//! The conversion to metallic-roughness ([`spec_gloss_to_metal_rough`]) is not linear: a
//! texel's metallic depends on its diffuse and specular colours together, and its base colour
//! on its metallic. So a material whose `specularGlossinessTexture` varies, or whose
//! `diffuseTexture` varies where the material is partly metallic, gets two new images when it is
//! loaded: its base colour (sRGB, with the diffuse alpha) and its metallic-roughness (linear:
//! roughness in G, metallic in B), each texel converted as the factors are. The new textures keep
//! the source texture's sampler (wrap modes), UV set and KHR_texture_transform, and the
//! material's factors become 1 (the texels carry them).

use super::context::Ctx;
use super::material::spec_gloss_to_metal_rough;
use crate::material::Material;
use crate::texture::{ColorSpace, Image, Texture, TextureRef};
use glam::{Vec2, Vec3, Vec4};

/// What a specular-glossiness material needs baked: its factors (clamped to [0, 1]) and its two
/// textures. While the images load, the material's base colour slot holds `diffuse` and its
/// metallic-roughness slot `specular_glossiness` (read as sRGB colour: the specular RGB is
/// sRGB-encoded, the glossiness in alpha linear), so that both images are decoded.
#[derive(Debug, Clone, Copy)]
pub(super) struct Bake {
    /// `diffuseFactor` (linear RGBA).
    pub diffuse: Vec4,
    /// `specularFactor` (linear RGB).
    pub specular: Vec3,
    /// `glossinessFactor`.
    pub glossiness: f32,
}

impl Bake {
    /// Whether the material's textures need a bake: a specular-glossiness texture always; a
    /// diffuse texture alone only where the factors make the material partly metallic (a
    /// dielectric's base colour is its diffuse colour times a constant, so the diffuse
    /// texture times the converted factor is exact there).
    pub(super) fn needed(&self, diffuse_texture: bool, specular_glossiness_texture: bool) -> bool {
        let (_, metallic, _) = spec_gloss_to_metal_rough(self.diffuse, self.specular, self.glossiness);
        specular_glossiness_texture || (diffuse_texture && metallic > 0.0)
    }
}

/// A texture's texels read at the texel centres of a `width × height` grid (its own UVs before
/// any transform), linear RGBA; white where there is no texture.
fn read_grid(
    r: Option<&TextureRef>,
    width: u32,
    height: u32,
    textures: &[Texture],
    images: &[Image],
) -> Vec<Vec4> {
    let mut out = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let uv = Vec2::new((x as f32 + 0.5) / width as f32, (y as f32 + 0.5) / height as f32);
            out.push(r.map_or(Vec4::ONE, |r| {
                // The grid is in the texture's own UVs: no transform here (the baked texture
                // keeps it).
                TextureRef { transform: None, ..*r }.sample_bilinear(uv, textures, images)
            }));
        }
    }
    out
}

/// The size of a texture's image (1 × 1 without one).
fn size(r: Option<&TextureRef>, textures: &[Texture], images: &[Image]) -> (u32, u32) {
    r.and_then(|r| textures.get(r.texture as usize))
        .and_then(|t| images.get(t.image as usize))
        .map_or((1, 1), |i| (i.width, i.height))
}

/// Bakes material `m` (material index `index`) as `bake` says: its base colour and
/// metallic-roughness slots, holding the diffuse and specular-glossiness textures while the
/// images loaded, are replaced by new textures over new images, and its factors set to 1. The
/// grid is the larger of the two images' sizes; where the two textures use different UV sets or
/// transforms their texels do not correspond, and the metallic-roughness texture is baked
/// from the specular-glossiness texels with the diffuse texture's mean, the diffuse texture
/// staying the base colour (a warning says so).
pub(super) fn bake(
    ctx: &mut Ctx<'_>,
    index: usize,
    bake: &Bake,
    m: &mut Material,
    textures: &mut Vec<Texture>,
    images: &mut Vec<Image>,
) {
    let sg = m.metallic_roughness_texture.take();
    let diffuse = m.base_color_texture;
    let Some(grid_ref) = sg.or(diffuse) else {
        // Both images failed to load (warned): the factors alone.
        let (base, metallic, roughness) =
            spec_gloss_to_metal_rough(bake.diffuse, bake.specular, bake.glossiness);
        (m.base_color_factor, m.metallic_factor, m.roughness_factor) = (base, metallic, roughness);
        return;
    };
    let aligned = match (sg, diffuse) {
        (Some(s), Some(d)) => s.tex_coord == d.tex_coord && s.transform == d.transform,
        _ => true,
    };
    let path = format!("materials[{index}].extensions.KHR_materials_pbrSpecularGlossiness");
    let (sw, sh) = size(sg.as_ref(), textures, images);
    let (dw, dh) = size(diffuse.as_ref().filter(|_| aligned), textures, images);
    let (width, height) = (sw.max(dw), sh.max(dh));
    let specular_glossiness = read_grid(sg.as_ref(), width, height, textures, images);
    let diffuse_texels = if aligned {
        read_grid(diffuse.as_ref(), width, height, textures, images)
    } else {
        ctx.warn(
            path.clone(),
            "diffuseTexture and specularGlossinessTexture use different UV sets or transforms: \
             metallic-roughness baked with the diffuse texture's mean colour, and the diffuse texture \
             kept as the base colour",
        );
        let mean = mean_texel(diffuse.as_ref(), textures, images);
        vec![mean; (width * height) as usize]
    };
    let mut base_texels = Vec::with_capacity(specular_glossiness.len());
    let mut mr_texels = Vec::with_capacity(specular_glossiness.len());
    for (sgt, dt) in specular_glossiness.iter().zip(&diffuse_texels) {
        let (base, metallic, roughness) = spec_gloss_to_metal_rough(
            bake.diffuse * *dt,
            bake.specular * sgt.truncate(),
            bake.glossiness * sgt.w,
        );
        base_texels.push(encode_base_color(base));
        mr_texels.push([0, unorm8(roughness), unorm8(metallic), 255]);
    }
    let source = textures[grid_ref.texture as usize];
    let mut add = |texels: Vec<[u8; 4]>, color_space| {
        images.push(Image { width, height, texels });
        textures.push(Texture { image: (images.len() - 1) as u32, ..source });
        TextureRef { texture: (textures.len() - 1) as u32, color_space, ..grid_ref }
    };
    m.metallic_roughness_texture = Some(add(mr_texels, ColorSpace::Linear));
    (m.metallic_factor, m.roughness_factor) = (1.0, 1.0);
    if aligned {
        m.base_color_texture = Some(add(base_texels, ColorSpace::Srgb));
        m.base_color_factor = Vec4::ONE;
    } else {
        // The factors' conversion times the diffuse texture, as without a bake.
        let (base, _, _) = spec_gloss_to_metal_rough(bake.diffuse, bake.specular, bake.glossiness);
        m.base_color_factor = base;
    }
}

/// The mean linear RGBA of a texture's image (white without one).
fn mean_texel(r: Option<&TextureRef>, textures: &[Texture], images: &[Image]) -> Vec4 {
    let Some(image) =
        r.and_then(|r| textures.get(r.texture as usize)).and_then(|t| images.get(t.image as usize))
    else {
        return Vec4::ONE;
    };
    let space = r.map_or(ColorSpace::Srgb, |r| r.color_space);
    let sum = image.texels.iter().fold(glam::DVec4::ZERO, |s, &t| s + decode(t, space).as_dvec4());
    (sum / image.texels.len().max(1) as f64).as_vec4()
}

/// An 8-bit texel decoded to linear RGBA (alpha linear).
fn decode([r, g, b, a]: [u8; 4], space: ColorSpace) -> Vec4 {
    let c = |v: u8| match space {
        ColorSpace::Srgb => crate::texture::srgb_to_linear(f32::from(v) / 255.0),
        ColorSpace::Linear => f32::from(v) / 255.0,
    };
    Vec4::new(c(r), c(g), c(b), f32::from(a) / 255.0)
}

/// A value in [0, 1] as the nearest 8-bit unorm.
pub(super) fn unorm8(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// A linear base colour (RGB in [0, 1]) and alpha as an sRGB-encoded 8-bit texel.
pub(super) fn encode_base_color(c: Vec4) -> [u8; 4] {
    let s = |v: f32| unorm8(furnace_post::linear_to_srgb(v.clamp(0.0, 1.0)));
    [s(c.x), s(c.y), s(c.z), unorm8(c.w)]
}

/// Runs the `bakes` ([`read_materials`](super::material::read_materials)'s, by material index)
/// once the images are loaded; a source image that no material samples any more is replaced by
/// a 1 × 1 white placeholder (as an unused image is), so that it costs no memory.
pub(super) fn bake_all(
    ctx: &mut Ctx<'_>,
    bakes: &[(usize, Bake)],
    materials: &mut [Material],
    textures: &mut Vec<Texture>,
    images: &mut Vec<Image>,
) {
    let mut sources = Vec::new();
    for &(i, ref b) in bakes {
        let Some(m) = materials.get_mut(i) else { continue };
        let image_of =
            |r: &Option<TextureRef>| r.and_then(|r| textures.get(r.texture as usize)).map(|t| t.image);
        sources.extend(image_of(&m.base_color_texture));
        sources.extend(image_of(&m.metallic_roughness_texture));
        bake(ctx, i, b, m, textures, images);
    }
    let used: std::collections::HashSet<u32> = materials
        .iter()
        .flat_map(Material::texture_refs)
        .filter_map(|r| textures.get(r.texture as usize).map(|t| t.image))
        .collect();
    for s in sources {
        if !used.contains(&s)
            && let Some(image) = images.get_mut(s as usize)
        {
            *image = Image { width: 1, height: 1, texels: vec![[255; 4]] };
        }
    }
}
