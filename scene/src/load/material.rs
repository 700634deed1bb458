//! Textures and materials: samplers, texture references (with KHR_texture_transform),
//! metallic-roughness factors and the supported extensions, a warning for each ignored feature.

use super::context::Ctx;
use super::spec_gloss::Bake;
use crate::material::{
    AlphaMode, Anisotropy, ClearcoatLayer, DiffuseTransmissionFactors, Iridescence, Material, MaterialLayers,
    SheenLayer, SpecularTextures,
};
use crate::texture::{ColorSpace, Texture, TextureRef, TextureTransform, WrapMode};
use glam::{Vec2, Vec3, Vec4};

/// Marks a texture whose image is missing.
const NO_IMAGE: u32 = u32::MAX;

/// The textures (glTF `textures`, same indices); one without an image source is kept, marked
/// [`NO_IMAGE`], with a warning.
pub(super) fn read_textures(ctx: &mut Ctx<'_>, doc: &gltf::Document) -> Vec<Texture> {
    let mut textures = Vec::new();
    for (t, tj) in doc.textures().zip(&doc.as_json().textures) {
        // The JSON `source` (not `Texture::source()`, which unwraps a missing one), or the image
        // an image-format extension names.
        let image = super::texture_source::choose(ctx, doc, t.index(), tj).unwrap_or_else(|| {
            ctx.warn(format!("textures[{}]", t.index()), "no image source: texture ignored");
            NO_IMAGE
        });
        let s = t.sampler();
        let wrap = |w: gltf::texture::WrappingMode| match w {
            gltf::texture::WrappingMode::Repeat => WrapMode::Repeat,
            gltf::texture::WrappingMode::ClampToEdge => WrapMode::ClampToEdge,
            gltf::texture::WrappingMode::MirroredRepeat => WrapMode::MirroredRepeat,
        };
        textures.push(Texture { image, wrap_s: wrap(s.wrap_s()), wrap_t: wrap(s.wrap_t()) });
    }
    textures
}

/// The file's materials, then glTF's default material (the last one: primitives without a
/// material use it); and the bakes of the specular-glossiness materials that need one, by
/// material index (run [`super::spec_gloss::bake_all`] once the images are loaded).
pub(super) fn read_materials(ctx: &mut Ctx<'_>, doc: &gltf::Document) -> (Vec<Material>, Vec<(usize, Bake)>) {
    let mut bakes = Vec::new();
    let mut materials: Vec<Material> = doc
        .materials()
        .enumerate()
        .map(|(i, m)| {
            let (material, bake) = read_material(ctx, &m, doc.textures().len());
            bakes.extend(bake.map(|b| (i, b)));
            material
        })
        .collect();
    materials.push(Material::default());
    (materials, bakes)
}

/// A texture's UV set, `TEXCOORD_0` with a warning past the sets furnace reads.
fn read_uv_set(ctx: &mut Ctx<'_>, tex_coord: u32, path: String) -> u32 {
    if (tex_coord as usize) < crate::MAX_UV_SETS {
        return tex_coord;
    }
    ctx.warn(
        path,
        format!(
            "uses TEXCOORD_{tex_coord}; sets up to TEXCOORD_{} are read: TEXCOORD_0 used",
            crate::MAX_UV_SETS - 1
        ),
    );
    0
}

fn texture_ref(
    ctx: &mut Ctx<'_>,
    info: Option<gltf::texture::Info<'_>>,
    space: ColorSpace,
    path: String,
) -> Option<TextureRef> {
    let info = info?;
    let transform = info.texture_transform().map(|t| TextureTransform {
        offset: Vec2::from(t.offset()),
        rotation: t.rotation(),
        scale: Vec2::from(t.scale()),
    });
    let tex_coord = info.texture_transform().and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord());
    let tex_coord = read_uv_set(ctx, tex_coord, path);
    Some(TextureRef { texture: info.texture().index() as u32, tex_coord, color_space: space, transform })
}

fn read_material(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>, textures: usize) -> (Material, Option<Bake>) {
    let i = m.index().unwrap_or(0);
    let p = format!("materials[{i}]");
    let pbr = match m.pbr_specular_glossiness() {
        Some(sg) => spec_gloss(ctx, &sg, &p),
        None => metal_rough(ctx, &m.pbr_metallic_roughness(), &p),
    };
    let (mut normal_texture, normal_scale) = normal_texture(m);
    let mut emissive_texture =
        texture_ref(ctx, m.emissive_texture(), ColorSpace::Srgb, format!("{p}.emissiveTexture"));
    let mut emissive = emissive(ctx, m, &p);
    let alpha_mode = alpha_mode(m);
    let (specular_factor, mut specular_color_factor, specular_textures) = specular(ctx, m, &p);
    let ior = ior(ctx, m, &p);
    if ior != 1.5 {
        // The opaque BSDF's dielectric F0 is 0.04·specularColor; KHR_materials_ior sets it to
        // ((ior − 1)/(ior + 1))² (1.5 gives 0.04: left exactly as it was).
        let f0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
        specular_color_factor *= f0 / 0.04;
    }
    let mut transmission = transmission(ctx, m, &p);
    let mut layers = layers(ctx, m, &p, textures);
    let mut iridescence = iridescence(ctx, m, &p, textures);
    let mut anisotropy = anisotropy(ctx, m, &p, textures);
    let mut diffuse_transmission = diffuse_transmission(ctx, m, &p, textures);
    let mut dispersion = dispersion(ctx, m, &p, &transmission, ior);
    warn_ignored(ctx, m);
    let unlit = m.unlit();
    if unlit {
        // KHR_materials_unlit: only the base colour and alpha count.
        (emissive, emissive_texture, normal_texture) = (Vec3::ZERO, None, None);
        transmission.factor = 0.0;
        transmission.texture = None;
        layers = MaterialLayers::default();
        iridescence = None;
        anisotropy = None;
        diffuse_transmission = None;
        dispersion = 0.0;
    }
    let roughness_factor = pbr.roughness_factor;
    let transmissive = transmission.factor > 0.0;
    // Light passes through either way: KHR_materials_volume makes the surface a solid's.
    let passes_light = transmissive || diffuse_transmission.is_some();
    let material = Material {
        name: m.name().map(str::to_string),
        base_color_factor: pbr.base_color_factor,
        base_color_texture: pbr.base_color_texture,
        metallic_factor: pbr.metallic_factor,
        roughness_factor,
        metallic_roughness_texture: pbr.metallic_roughness_texture,
        normal_texture,
        normal_scale,
        emissive,
        emissive_texture,
        alpha_mode,
        // A solid's surface is one interface whatever doubleSided says (KHR_materials_volume),
        // and a sheet is seen from both sides: (diffusely) transmissive surfaces are two-sided.
        double_sided: m.double_sided() || passes_light,
        specular_factor,
        specular_color_factor,
        specular_textures,
        transmission_factor: transmission.factor,
        transmission_texture: transmission.texture,
        ior,
        volume: passes_light && transmission.volume,
        absorption: transmission.absorption,
        diffuse_transmission,
        layers,
        iridescence,
        anisotropy,
        dispersion,
        unlit,
    };
    (material, pbr.bake)
}

/// The metallic-roughness part of a material, read from `pbrMetallicRoughness` or converted
/// from KHR_materials_pbrSpecularGlossiness.
struct MetalRough {
    base_color_factor: Vec4,
    base_color_texture: Option<TextureRef>,
    metallic_factor: f32,
    roughness_factor: f32,
    metallic_roughness_texture: Option<TextureRef>,
    /// The bake a specular-glossiness material's textures need ([`super::spec_gloss`]).
    bake: Option<Bake>,
}

/// A factor clamped to [0, 1]; NaN reads as 1.
fn clamp01(x: f32) -> f32 {
    if x.is_nan() { 1.0 } else { x.clamp(0.0, 1.0) }
}

fn metal_rough(ctx: &mut Ctx<'_>, pbr: &gltf::material::PbrMetallicRoughness<'_>, p: &str) -> MetalRough {
    MetalRough {
        base_color_factor: Vec4::from(pbr.base_color_factor()),
        base_color_texture: texture_ref(
            ctx,
            pbr.base_color_texture(),
            ColorSpace::Srgb,
            format!("{p}.pbrMetallicRoughness.baseColorTexture"),
        ),
        metallic_factor: clamp01(pbr.metallic_factor()),
        roughness_factor: clamp01(pbr.roughness_factor()),
        metallic_roughness_texture: texture_ref(
            ctx,
            pbr.metallic_roughness_texture(),
            ColorSpace::Linear,
            format!("{p}.pbrMetallicRoughness.metallicRoughnessTexture"),
        ),
        bake: None,
    }
}

/// KHR_materials_pbrSpecularGlossiness converted to metallic-roughness
/// ([`spec_gloss_to_metal_rough`]): from its factors, `diffuseTexture` becoming the base colour
/// texture, when that is exact; else (a `specularGlossinessTexture`, or a diffuse texture on a
/// partly metallic material) the textures are baked after the images load
/// ([`super::spec_gloss`]), and until then the base colour slot holds `diffuseTexture` and the
/// metallic-roughness slot `specularGlossinessTexture`.
fn spec_gloss(ctx: &mut Ctx<'_>, sg: &gltf::material::PbrSpecularGlossiness<'_>, p: &str) -> MetalRough {
    let ext = format!("{p}.extensions.KHR_materials_pbrSpecularGlossiness");
    let finite01 = |x: f32| if x.is_finite() { x.clamp(0.0, 1.0) } else { 1.0 };
    let factors = Bake {
        diffuse: Vec4::from(sg.diffuse_factor().map(finite01)),
        specular: Vec3::from(sg.specular_factor().map(finite01)),
        glossiness: finite01(sg.glossiness_factor()),
    };
    let (base_color_factor, metallic_factor, roughness_factor) =
        spec_gloss_to_metal_rough(factors.diffuse, factors.specular, factors.glossiness);
    let base_color_texture =
        texture_ref(ctx, sg.diffuse_texture(), ColorSpace::Srgb, format!("{ext}.diffuseTexture"));
    // The specular RGB is sRGB-encoded like a colour (its glossiness in alpha is linear, as
    // every alpha is).
    let specular_glossiness_texture = texture_ref(
        ctx,
        sg.specular_glossiness_texture(),
        ColorSpace::Srgb,
        format!("{ext}.specularGlossinessTexture"),
    );
    let bake = factors
        .needed(base_color_texture.is_some(), specular_glossiness_texture.is_some())
        .then_some(factors);
    MetalRough {
        base_color_factor,
        base_color_texture,
        metallic_factor,
        roughness_factor,
        metallic_roughness_texture: specular_glossiness_texture.filter(|_| bake.is_some()),
        bake,
    }
}

/// The dielectric reflectance at normal incidence of the metallic-roughness model.
const DIELECTRIC_F0: f32 = 0.04;

/// Converts specular-glossiness factors (linear RGB, each in [0, 1]) to metallic-roughness:
/// `(baseColor, metallic, roughness)`, as the Khronos converter does
/// (`KHR_materials_pbrSpecularGlossiness/examples/convert-between-workflows`, Babylon.js's
/// `ConvertToMetallicRoughness`).
///
/// With perceived brightness `L(c) = √(0.299 r² + 0.587 g² + 0.114 b²)`, `d = L(diffuse)`,
/// `s = L(specular)` and `k = 1 − max(specular)`, metallic solves
/// `0.04 m² + (d·k/0.96 + s − 0.08) m + (0.04 − s) = 0` (0 when `s < 0.04`: a dielectric);
/// the base colour blends `diffuse·k/(0.96 (1 − m))` and `(specular − 0.04 (1 − m))/m` by `m²`,
/// clamped to [0, 1]; alpha is the diffuse alpha; roughness is `1 − glossiness`.
pub(crate) fn spec_gloss_to_metal_rough(diffuse: Vec4, specular: Vec3, glossiness: f32) -> (Vec4, f32, f32) {
    const EPSILON: f32 = 1e-6;
    let brightness = |c: Vec3| (0.299 * c.x * c.x + 0.587 * c.y * c.y + 0.114 * c.z * c.z).sqrt();
    let one_minus_specular = 1.0 - specular.max_element();
    let (d, s) = (brightness(diffuse.truncate()), brightness(specular));
    let metallic = if s < DIELECTRIC_F0 {
        0.0
    } else {
        let a = DIELECTRIC_F0;
        let b = d * one_minus_specular / (1.0 - DIELECTRIC_F0) + s - 2.0 * DIELECTRIC_F0;
        let c = DIELECTRIC_F0 - s;
        let disc = (b * b - 4.0 * a * c).max(0.0);
        ((-b + disc.sqrt()) / (2.0 * a)).clamp(0.0, 1.0)
    };
    let from_diffuse =
        diffuse.truncate() * (one_minus_specular / (1.0 - DIELECTRIC_F0) / (1.0 - metallic).max(EPSILON));
    let from_specular = (specular - Vec3::splat(DIELECTRIC_F0 * (1.0 - metallic))) / metallic.max(EPSILON);
    let base = from_diffuse.lerp(from_specular, metallic * metallic).clamp(Vec3::ZERO, Vec3::ONE);
    (base.extend(diffuse.w), metallic, 1.0 - glossiness)
}

/// KHR_materials_ior's `ior` (1.5 without it). glTF allows 0 (meaning "very large", a
/// metal-like Fresnel) and values ≥ 1; others are invalid.
fn ior(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>, p: &str) -> f32 {
    let Some(ior) = m.ior() else { return 1.5 };
    if ior == 0.0 {
        ctx.warn(format!("{p}.extensions.KHR_materials_ior.ior"), "0 (infinite index) is rendered as 100");
        return 100.0;
    }
    if !(ior.is_finite() && ior >= 1.0) {
        ctx.warn(format!("{p}.extensions.KHR_materials_ior.ior"), format!("{ior} is not ≥ 1: 1.5 used"));
        return 1.5;
    }
    ior.min(100.0)
}

/// KHR_materials_dispersion's `dispersion` (20/V_d, ≥ 0), or 0 where it can have no effect:
/// it disperses the light refracted into a solid (KHR_materials_transmission with
/// KHR_materials_volume), and an index of 1 is 1 at every wavelength.
fn dispersion(
    ctx: &mut Ctx<'_>,
    m: &gltf::Material<'_>,
    p: &str,
    transmission: &TransmissionExt,
    ior: f32,
) -> f32 {
    let Some(ext) = m.extension_value("KHR_materials_dispersion") else { return 0.0 };
    let path = format!("{p}.extensions.KHR_materials_dispersion");
    let d = number_at_least(ctx, ext, "dispersion", 0.0, 0.0, &path);
    if d > 0.0 && !(transmission.factor > 0.0 && transmission.volume) {
        ctx.warn(
            path,
            "disperses light refracted into a solid: without KHR_materials_transmission and a \
             KHR_materials_volume thickness it has no effect (ignored)",
        );
        return 0.0;
    }
    if ior == 1.0 { 0.0 } else { d }
}

/// What KHR_materials_transmission and KHR_materials_volume say.
struct TransmissionExt {
    factor: f32,
    texture: Option<TextureRef>,
    volume: bool,
    absorption: Vec3,
}

fn transmission(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>, p: &str) -> TransmissionExt {
    let mut t = TransmissionExt { factor: 0.0, texture: None, volume: false, absorption: Vec3::ZERO };
    if let Some(tr) = m.transmission() {
        let f = tr.transmission_factor();
        t.factor = if f.is_nan() { 0.0 } else { f.clamp(0.0, 1.0) };
        t.texture = texture_ref(
            ctx,
            tr.transmission_texture(),
            ColorSpace::Linear,
            format!("{p}.extensions.KHR_materials_transmission.transmissionTexture"),
        );
    }
    if let Some(v) = m.volume() {
        let path = format!("{p}.extensions.KHR_materials_volume");
        if m.transmission().is_none() && m.extension_value(DIFFUSE_TRANSMISSION).is_none() {
            ctx.warn(
                path.clone(),
                "a volume without KHR_materials_transmission or _diffuse_transmission is opaque: ignored",
            );
        }
        t.volume = v.thickness_factor() > 0.0;
        if v.thickness_texture().is_some() {
            ctx.warn(path.clone(), "thicknessTexture not read: the thickness through the solid is traced");
        }
        let d = v.attenuation_distance();
        let c = Vec3::from(v.attenuation_color());
        if !(d > 0.0) || !(c.min_element() >= 0.0) || !c.is_finite() {
            ctx.warn(path, "attenuationDistance must be > 0 and attenuationColor in [0, 1]: no absorption");
        } else if d.is_finite() {
            // σ_a = −ln(c)/d; a black channel absorbs everything (+∞).
            let sigma = |c: f32| {
                if c >= 1.0 {
                    0.0
                } else if c > 0.0 {
                    -c.ln() / d
                } else {
                    f32::INFINITY
                }
            };
            t.absorption = Vec3::new(sigma(c.x), sigma(c.y), sigma(c.z));
        }
    }
    t
}

/// The normal map and its scale (1 without one).
fn normal_texture(m: &gltf::Material<'_>) -> (Option<TextureRef>, f32) {
    match m.normal_texture() {
        Some(n) => {
            let r = TextureRef {
                texture: n.texture().index() as u32,
                tex_coord: n.tex_coord(),
                color_space: ColorSpace::Linear,
                transform: None,
            };
            (Some(r), n.scale())
        }
        None => (None, 1.0),
    }
}

/// The emitted radiance factor: `emissiveFactor` × KHR_materials_emissive_strength.
fn emissive(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>, p: &str) -> Vec3 {
    let strength = m.emissive_strength().unwrap_or(1.0);
    let emissive = Vec3::from(m.emissive_factor()) * strength;
    if !(emissive.is_finite() && emissive.min_element() >= 0.0) {
        // A NaN or infinite radiance would make NaN pixels; a negative one is not light.
        ctx.warn(
            format!("{p}.emissiveFactor"),
            "negative or non-finite emission (emissiveFactor × emissiveStrength): those channels are 0",
        );
        let clean = |x: f32| if x.is_finite() && x > 0.0 { x } else { 0.0 };
        return Vec3::new(clean(emissive.x), clean(emissive.y), clean(emissive.z));
    }
    if m.emissive_factor().iter().any(|&x| x > 1.0) {
        ctx.warn(
            format!("{p}.emissiveFactor"),
            "exceeds 1 (the spec's limit; use KHR_materials_emissive_strength): used as given",
        );
    }
    emissive
}

fn alpha_mode(m: &gltf::Material<'_>) -> AlphaMode {
    match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
        gltf::material::AlphaMode::Mask => AlphaMode::Mask { cutoff: m.alpha_cutoff().unwrap_or(0.5) },
        gltf::material::AlphaMode::Blend => AlphaMode::Blend,
    }
}

/// KHR_materials_specular's factors and textures (`specularTexture` linear, its A channel;
/// `specularColorTexture` sRGB). gltf-json knows this extension, so its texture indices were
/// checked with the rest of the file.
fn specular(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>, p: &str) -> (f32, Vec3, SpecularTextures) {
    let Some(s) = m.specular() else { return (1.0, Vec3::ONE, SpecularTextures::default()) };
    let path = format!("{p}.extensions.KHR_materials_specular");
    let maps = SpecularTextures {
        specular: texture_ref(
            ctx,
            s.specular_texture(),
            ColorSpace::Linear,
            format!("{path}.specularTexture"),
        ),
        color: texture_ref(
            ctx,
            s.specular_color_texture(),
            ColorSpace::Srgb,
            format!("{path}.specularColorTexture"),
        ),
    };
    (s.specular_factor(), Vec3::from(s.specular_color_factor()), maps)
}

/// Warns about the occlusion texture and the material extensions furnace ignores.
fn warn_ignored(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>) {
    if m.occlusion_texture().is_some() {
        ctx.warn("", "occlusionTexture ignored (a path tracer computes occlusion)");
    }
}

/// A texture reference written in an extension's JSON (`{"index", "texCoord", "extensions":
/// {"KHR_texture_transform"}}`), as [`texture_ref`] reads the core's; an index out of range is
/// a warning and no texture.
fn texture_ref_json(
    ctx: &mut Ctx<'_>,
    value: Option<&gltf::json::Value>,
    textures: usize,
    space: ColorSpace,
    path: String,
) -> Option<TextureRef> {
    let v = value?;
    let index = v.get("index").and_then(gltf::json::Value::as_u64);
    let Some(index) = index.filter(|&i| (i as usize) < textures) else {
        ctx.warn(
            path,
            format!(
                "texture index {} is not one of the file's {textures} textures: ignored",
                v.get("index").map_or("(none)".to_string(), ToString::to_string)
            ),
        );
        return None;
    };
    let num = |o: &gltf::json::Value, k: &str| o.get(k).and_then(gltf::json::Value::as_f64);
    let pair = |o: &gltf::json::Value, k: &str, d: [f32; 2]| {
        o.get(k).and_then(|a| a.as_array()).filter(|a| a.len() == 2).map_or(Vec2::from(d), |a| {
            Vec2::new(
                a[0].as_f64().unwrap_or(d[0] as f64) as f32,
                a[1].as_f64().unwrap_or(d[1] as f64) as f32,
            )
        })
    };
    let tt = v.get("extensions").and_then(|e| e.get("KHR_texture_transform"));
    let transform = tt.map(|t| TextureTransform {
        offset: pair(t, "offset", [0.0, 0.0]),
        rotation: num(t, "rotation").unwrap_or(0.0) as f32,
        scale: pair(t, "scale", [1.0, 1.0]),
    });
    let tex_coord = tt.and_then(|t| num(t, "texCoord")).or_else(|| num(v, "texCoord")).unwrap_or(0.0) as u32;
    let tex_coord = read_uv_set(ctx, tex_coord, path);
    Some(TextureRef { texture: index as u32, tex_coord, color_space: space, transform })
}

/// A factor of an extension's JSON in `[0, 1]` (`default` where absent; out of range or not a
/// number: a warning and the value clamped, or the default).
fn unit_factor(ctx: &mut Ctx<'_>, ext: &gltf::json::Value, key: &str, default: f32, path: &str) -> f32 {
    match ext.get(key) {
        None => default,
        Some(v) => match v.as_f64() {
            Some(x) if (0.0..=1.0).contains(&x) => x as f32,
            Some(x) if x.is_finite() => {
                ctx.warn(format!("{path}.{key}"), format!("{x} is outside [0, 1]: clamped"));
                x.clamp(0.0, 1.0) as f32
            }
            _ => {
                ctx.warn(format!("{path}.{key}"), format!("{v} is not a number: {default} used"));
                default
            }
        },
    }
}

/// A number of an extension's JSON at least `min` (`default` where absent; below `min`: a
/// warning and `min`; not a number: a warning and the default).
fn number_at_least(
    ctx: &mut Ctx<'_>,
    ext: &gltf::json::Value,
    key: &str,
    default: f32,
    min: f32,
    path: &str,
) -> f32 {
    match ext.get(key) {
        None => default,
        Some(v) => match v.as_f64() {
            Some(x) if x.is_finite() && x >= min as f64 => x as f32,
            Some(x) if x.is_finite() => {
                ctx.warn(format!("{path}.{key}"), format!("{x} is below {min}: {min} used"));
                min
            }
            _ => {
                ctx.warn(format!("{path}.{key}"), format!("{v} is not a number: {default} used"));
                default
            }
        },
    }
}

/// KHR_materials_iridescence: the thin film on the material (`None` for a factor of 0).
fn iridescence(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>, p: &str, textures: usize) -> Option<Iridescence> {
    let ext = m.extension_value("KHR_materials_iridescence")?;
    let path = format!("{p}.extensions.KHR_materials_iridescence");
    let factor = unit_factor(ctx, ext, "iridescenceFactor", 0.0, &path);
    let ior = number_at_least(ctx, ext, "iridescenceIor", 1.3, 1.0, &path);
    let thickness_minimum = number_at_least(ctx, ext, "iridescenceThicknessMinimum", 100.0, 0.0, &path);
    let thickness_maximum = number_at_least(ctx, ext, "iridescenceThicknessMaximum", 400.0, 0.0, &path);
    if !(factor > 0.0) {
        return None;
    }
    let texture = texture_ref_json(
        ctx,
        ext.get("iridescenceTexture"),
        textures,
        ColorSpace::Linear,
        format!("{path}.iridescenceTexture"),
    );
    let thickness_texture = texture_ref_json(
        ctx,
        ext.get("iridescenceThicknessTexture"),
        textures,
        ColorSpace::Linear,
        format!("{path}.iridescenceThicknessTexture"),
    );
    Some(Iridescence { factor, texture, ior, thickness_minimum, thickness_maximum, thickness_texture })
}

/// KHR_materials_anisotropy (`None` for a strength of 0).
fn anisotropy(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>, p: &str, textures: usize) -> Option<Anisotropy> {
    let ext = m.extension_value("KHR_materials_anisotropy")?;
    let path = format!("{p}.extensions.KHR_materials_anisotropy");
    let strength = unit_factor(ctx, ext, "anisotropyStrength", 0.0, &path);
    let rotation = match ext.get("anisotropyRotation") {
        None => 0.0,
        Some(v) => match v.as_f64().filter(|r| r.is_finite()) {
            Some(r) => r as f32,
            None => {
                ctx.warn(format!("{path}.anisotropyRotation"), format!("{v} is not a number: 0 used"));
                0.0
            }
        },
    };
    if !(strength > 0.0) {
        return None;
    }
    let texture = texture_ref_json(
        ctx,
        ext.get("anisotropyTexture"),
        textures,
        ColorSpace::Linear,
        format!("{path}.anisotropyTexture"),
    );
    Some(Anisotropy { strength, rotation, texture })
}

/// KHR_materials_clearcoat and KHR_materials_sheen: the layers above the material.
fn layers(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>, p: &str, textures: usize) -> MaterialLayers {
    let mut layers = MaterialLayers::default();
    if let Some(ext) = m.extension_value("KHR_materials_clearcoat") {
        let path = format!("{p}.extensions.KHR_materials_clearcoat");
        let factor = unit_factor(ctx, ext, "clearcoatFactor", 0.0, &path);
        let roughness = unit_factor(ctx, ext, "clearcoatRoughnessFactor", 0.0, &path);
        if factor > 0.0 {
            let texture = texture_ref_json(
                ctx,
                ext.get("clearcoatTexture"),
                textures,
                ColorSpace::Linear,
                format!("{path}.clearcoatTexture"),
            );
            let roughness_texture = texture_ref_json(
                ctx,
                ext.get("clearcoatRoughnessTexture"),
                textures,
                ColorSpace::Linear,
                format!("{path}.clearcoatRoughnessTexture"),
            );
            let normal = ext.get("clearcoatNormalTexture");
            let normal_texture = texture_ref_json(
                ctx,
                normal,
                textures,
                ColorSpace::Linear,
                format!("{path}.clearcoatNormalTexture"),
            );
            let normal_scale =
                normal.and_then(|n| n.get("scale")).and_then(gltf::json::Value::as_f64).unwrap_or(1.0) as f32;
            layers.clearcoat = Some(ClearcoatLayer {
                factor,
                texture,
                roughness,
                roughness_texture,
                normal_texture,
                normal_scale,
            });
        }
    }
    if let Some(ext) = m.extension_value("KHR_materials_sheen") {
        let path = format!("{p}.extensions.KHR_materials_sheen");
        let color = match ext.get("sheenColorFactor").and_then(|c| c.as_array()) {
            Some(a)
                if a.len() == 3
                    && a.iter().all(|c| c.as_f64().is_some_and(|x| x.is_finite() && x >= 0.0)) =>
            {
                Vec3::new(
                    a[0].as_f64().unwrap_or(0.0) as f32,
                    a[1].as_f64().unwrap_or(0.0) as f32,
                    a[2].as_f64().unwrap_or(0.0) as f32,
                )
            }
            Some(_) => {
                ctx.warn(format!("{path}.sheenColorFactor"), "not three non-negative numbers: no sheen");
                Vec3::ZERO
            }
            None => Vec3::ZERO,
        };
        let roughness = unit_factor(ctx, ext, "sheenRoughnessFactor", 0.0, &path);
        if color.max_element() > 0.0 {
            let color_texture = texture_ref_json(
                ctx,
                ext.get("sheenColorTexture"),
                textures,
                ColorSpace::Srgb,
                format!("{path}.sheenColorTexture"),
            );
            let roughness_texture = texture_ref_json(
                ctx,
                ext.get("sheenRoughnessTexture"),
                textures,
                ColorSpace::Linear,
                format!("{path}.sheenRoughnessTexture"),
            );
            layers.sheen = Some(SheenLayer { color, color_texture, roughness, roughness_texture });
        }
    }
    layers
}

/// The extension's name.
const DIFFUSE_TRANSMISSION: &str = "KHR_materials_diffuse_transmission";

/// KHR_materials_diffuse_transmission: `None` without it or with `diffuseTransmissionFactor` 0.
fn diffuse_transmission(
    ctx: &mut Ctx<'_>,
    m: &gltf::Material<'_>,
    p: &str,
    textures: usize,
) -> Option<DiffuseTransmissionFactors> {
    let ext = m.extension_value(DIFFUSE_TRANSMISSION)?;
    let path = format!("{p}.extensions.{DIFFUSE_TRANSMISSION}");
    let factor = unit_factor(ctx, ext, "diffuseTransmissionFactor", 0.0, &path);
    let color = match ext.get("diffuseTransmissionColorFactor") {
        None => Vec3::ONE,
        Some(c) => match c.as_array().map(|a| a.iter().map(gltf::json::Value::as_f64).collect::<Vec<_>>()) {
            Some(a) if a.len() == 3 && a.iter().all(|x| x.is_some_and(f64::is_finite)) => {
                let a = a.iter().map(|x| x.unwrap_or(1.0) as f32).collect::<Vec<_>>();
                let c = Vec3::new(a[0], a[1], a[2]);
                let clamped = c.clamp(Vec3::ZERO, Vec3::ONE);
                if clamped != c {
                    ctx.warn(
                        format!("{path}.diffuseTransmissionColorFactor"),
                        format!("{c} is outside [0, 1]: clamped"),
                    );
                }
                clamped
            }
            _ => {
                ctx.warn(format!("{path}.diffuseTransmissionColorFactor"), "not three numbers: white used");
                Vec3::ONE
            }
        },
    };
    if !(factor > 0.0) {
        return None;
    }
    let texture = texture_ref_json(
        ctx,
        ext.get("diffuseTransmissionTexture"),
        textures,
        ColorSpace::Linear,
        format!("{path}.diffuseTransmissionTexture"),
    );
    let color_texture = texture_ref_json(
        ctx,
        ext.get("diffuseTransmissionColorTexture"),
        textures,
        ColorSpace::Srgb,
        format!("{path}.diffuseTransmissionColorTexture"),
    );
    Some(DiffuseTransmissionFactors { factor, texture, color, color_texture })
}
