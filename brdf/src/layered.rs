//! The glTF material as one layered BSDF: which lobes a shading point has, with which weights,
//! built from the material's parameters there. The CPU integrator calls [`HitBsdf::new`] at
//! every hit; `furnace-gpu`'s `layered.wgsl` (`hit_bsdf`, `hit_eval`, `hit_pdf`) is its twin.
//!
//! ## The lobes and the layering rule
//!
//! | lobe | Rust file | weight in the mixture | albedo |
//! |---|---|---|---|
//! | [`Lambert`] diffuse base | `lambert.rs` | `(1 − g)·(1 − m′)`, under the specular layer: `1 − sF·max(fr)` at the half vector | `baseColor` |
//! | [`GgxSpecular`](crate::GgxSpecular) (with [`turquin`](crate::turquin) compensation) | `specular.rs`, `ggx.rs`, `turquin.rs` | `1 − g`, merged: F0 `mix(0.04·sF·sC, baseColor, m′)`, F90 `mix(sF, 1, m′)` | Fresnel |
//! | thin film (KHR_materials_iridescence) | `iridescence.rs` | not a lobe: mixes its Fresnel into the two rows above by `i` | |
//! | [`Dielectric`] interface (smooth, rough or thin-walled) | `dielectric.rs` | `g` | tint `baseColor` |
//! | [`DiffuseTransmission`] (KHR_materials_diffuse_transmission, Lambert below) | `diffuse_transmission.rs` | `(1 − m)(1 − T)·dt`, the Lambert base's `(1 − dt)` moved to it, under the same Fresnel weight (half vector mirrored) | `dtColor` |
//! | [`Sheen`] (KHR_materials_sheen, Charlie) | `sheen.rs` | `1 − c·Fc`; scales everything below by `1 − max(sheenColor)·max(E(μo), E(μi))` | `sheenColor·E` |
//! | [`Clearcoat`] (KHR_materials_clearcoat, white GGX) | `clearcoat.rs` | `c·Fc(μo)`; scales everything below by `1 − c·Fc(μo)` | `c·Fc·E_ss` |
//!
//! with `m = clamp(metallic)`, `g = clamp(transmission)·(1 − m)` (KHR_materials_transmission:
//! only the dielectric part transmits) and the opaque rest's metallic `m′ = min(m/(1 − g), 1)`
//! (`metallic` itself when `g = 0`): glTF's `mix(dielectric(mix(diffuse, transmission, T)),
//! metal, metallic)` regrouped as `g·dielectric + (1 − g)·opaque`. The first two rows are
//! [`MetallicRoughness`] (`metallic_roughness.rs`), the mixture with the third
//! [`Transmissive`]. The diffuse transmission lobe sits beside that core: the Lambert base of
//! the opaque part keeps `(1 − dt)` of its albedo and the lobe takes `dt` of it, coloured
//! `diffuseTransmissionColor` (`dt = clamp(diffuseTransmission)`); the core and the lobe
//! together are the material the layers cover. A material without it is exactly the core.
//!
//! The layers above the material are the extensions' own rules, outermost first:
//! `coat + (1 − c·Fc)·(sheen + s·material)` with the coat's `c`, `Fc` of [`crate::clearcoat`]
//! and the sheen's scale `s` of [`Sheen::base_scale`]. A material without them is exactly the
//! material (no layer is evaluated and no sampler dimension drawn).
//!
//! A new lobe is one more Rust file (its `eval`, `sample`, `pdf`), its parameters in
//! [`LayeredParams`], its weight in [`HitBsdf::new`] and its row above.

use crate::clearcoat::Clearcoat;
use crate::dielectric::{Dielectric, Interface, ONE_BELOW, ScatterSample, Transmissive, rescale};
use crate::diffuse_transmission::DiffuseTransmission;
use crate::iridescence::ThinFilm;
use crate::lambert::Lambert;
use crate::metallic_roughness::{MetallicRoughness, MetallicRoughnessParams};
use crate::sheen::Sheen;
use crate::specular::SpecularOptions;
use crate::{Bsdf, Rgb};
use glam::{Vec2, Vec3};

/// The glTF material's parameters at one shading point (after texture lookups): what
/// [`HitBsdf::new`] builds the BSDF from. Out-of-range and NaN inputs are clamped or replaced
/// there, as [`MetallicRoughness::new`] and [`Dielectric::new`] do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayeredParams {
    /// `baseColorFactor × baseColorTexture`, linear RGB: the diffuse albedo, the metal's F0
    /// and the dielectric's tint.
    pub base_color: Rgb,
    /// `metallicFactor × texture.b`.
    pub metallic: f32,
    /// Perceptual roughness `roughnessFactor × texture.g`; α = roughness².
    pub roughness: f32,
    /// KHR_materials_specular `specularFactor`.
    pub specular_factor: f32,
    /// KHR_materials_specular `specularColorFactor`.
    pub specular_color: Rgb,
    /// KHR_materials_transmission `transmissionFactor × texture.r` (0: opaque).
    pub transmission: f32,
    /// KHR_materials_ior `ior`: the dielectric's relative index of refraction.
    pub ior: f32,
    /// KHR_materials_volume: the surface bounds a solid (otherwise a thin-walled sheet).
    pub volume: bool,
    /// KHR_materials_clearcoat `clearcoatFactor × texture.r` (0: no coat).
    pub clearcoat: f32,
    /// KHR_materials_clearcoat `clearcoatRoughnessFactor × texture.g` (perceptual).
    pub clearcoat_roughness: f32,
    /// The coat's normal in the shading frame (`Vec3::Z`: the shading normal itself).
    pub clearcoat_normal: Vec3,
    /// KHR_materials_sheen `sheenColorFactor × texture.rgb` (black: no sheen).
    pub sheen_color: Rgb,
    /// KHR_materials_sheen `sheenRoughnessFactor × texture.a`.
    pub sheen_roughness: f32,
    /// KHR_materials_iridescence `iridescenceFactor × texture.r` (0: no film).
    pub iridescence: f32,
    /// The film: `iridescenceIor` and its thickness in nm (`mix(min, max, texture.g)`).
    pub film: ThinFilm,
    /// KHR_materials_diffuse_transmission `diffuseTransmissionFactor × texture.a` (0: none).
    pub diffuse_transmission: f32,
    /// KHR_materials_diffuse_transmission `diffuseTransmissionColorFactor × texture.rgb`.
    pub diffuse_transmission_color: Rgb,
    /// KHR_materials_anisotropy's strength `anisotropyStrength × texture.b` (0: isotropic): the
    /// base's specular lobe is stretched along the shading frame's x axis, which the caller
    /// aligns with the anisotropy direction ([`MetallicRoughness::with_anisotropy`]).
    pub anisotropy: f32,
}

impl Default for LayeredParams {
    /// glTF's default material (white, metallic 1, roughness 1, opaque, no layers).
    fn default() -> Self {
        Self {
            base_color: Rgb::ONE,
            metallic: 1.0,
            roughness: 1.0,
            specular_factor: 1.0,
            specular_color: Rgb::ONE,
            transmission: 0.0,
            ior: 1.5,
            volume: false,
            clearcoat: 0.0,
            clearcoat_roughness: 0.0,
            clearcoat_normal: Vec3::Z,
            sheen_color: Rgb::ZERO,
            sheen_roughness: 0.0,
            iridescence: 0.0,
            film: ThinFilm { ior: 1.3, thickness: 400.0 },
            diffuse_transmission: 0.0,
            diffuse_transmission_color: Rgb::ONE,
            anisotropy: 0.0,
        }
    }
}

/// The material beneath the layers: the opaque glTF material, or one that transmits
/// (KHR_materials_transmission).
#[derive(Debug, Clone, Copy)]
pub enum Core {
    /// Lambert under a merged GGX lobe ([`MetallicRoughness`]).
    Opaque(MetallicRoughness),
    /// The mixture with a dielectric, and whether it bounds a solid (KHR_materials_volume).
    Transmissive(Transmissive, bool),
}

/// The layers above the material: a clear coat and a sheen, each optional (at least one).
#[derive(Debug, Clone, Copy)]
pub struct Layers {
    /// KHR_materials_clearcoat.
    pub clearcoat: Option<Clearcoat>,
    /// KHR_materials_sheen.
    pub sheen: Option<Sheen>,
}

/// The BSDF at a hit: the material ([`Core`] and its diffuse transmission) under its layers.
/// See the [module docs](self) for the layering.
#[derive(Debug, Clone, Copy)]
pub struct HitBsdf {
    /// The material beneath.
    pub core: Core,
    /// KHR_materials_diffuse_transmission's lobe beside the core, `None` without it (or where
    /// it is black).
    pub diffuse_transmission: Option<DiffuseTransmission>,
    /// The layers above it, `None` without coat or sheen.
    pub layers: Option<Layers>,
}

/// How [`HitBsdf::sample_with`] chooses between the layers and the material.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LobeSelection {
    /// In proportion to albedo estimates at ωo (what the renderers use).
    Albedo,
    /// The same probability for every present layer and the material (the naive rule).
    Uniform,
}

/// The smallest probability a present layer is sampled with: no lobe whose estimate is
/// small at this view (a coat seen head-on reflects 4 %) is starved.
pub const MIN_LAYER_PROBABILITY: f32 = 0.05;

/// The smallest probability the diffuse transmission lobe and the core beside it are each
/// sampled with, for the same reason.
pub const MIN_TRANSMISSION_PROBABILITY: f32 = 0.05;

/// A clamped factor: `[0, 1]`, NaN → 0.
#[inline]
fn unit(x: f32) -> f32 {
    if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) }
}

impl HitBsdf {
    /// The BSDF of evaluated material parameters: the glTF metallic-roughness material, mixed
    /// with a dielectric interface where it transmits, under its coat and sheen.
    #[inline]
    pub fn new(params: &LayeredParams, specular: SpecularOptions) -> Self {
        let clearcoat = (params.clearcoat > 0.0).then(|| {
            Clearcoat::new(params.clearcoat, params.clearcoat_roughness, params.clearcoat_normal, specular)
        });
        let sheen = (params.sheen_color.max_element() > 0.0)
            .then(|| Sheen::new(params.sheen_color, params.sheen_roughness));
        let layers = (clearcoat.is_some() || sheen.is_some()).then_some(Layers { clearcoat, sheen });
        let dt = unit(params.diffuse_transmission);
        // The share of the material that is the opaque dielectric: (1 − m)(1 − T), a NaN
        // metallic read as 1 as the metallic-roughness BSDF reads it.
        let metallic = if params.metallic.is_nan() { 1.0 } else { unit(params.metallic) };
        let dielectric = (1.0 - metallic) * (1.0 - unit(params.transmission));
        let diffuse_transmission = (dt > 0.0)
            .then(|| {
                let color = crate::clamp_rgb(params.diffuse_transmission_color, 1.0) * (dielectric * dt);
                DiffuseTransmission::new(color, params.volume)
            })
            .filter(|d| d.color != Rgb::ZERO);
        Self { core: Core::new(params, specular, dt), diffuse_transmission, layers }
    }

    /// The BSDF times `|cos θi|`.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        match &self.layers {
            None => self.material_eval(wo, wi),
            Some(l) => l.eval(wo, wi, self.material_eval(wo, wi)),
        }
    }

    /// The density of the non-delta part of `sample`.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.pdf_with(wo, wi, LobeSelection::Albedo)
    }

    /// [`HitBsdf::pdf`] of [`HitBsdf::sample_with`] under `selection`.
    #[inline]
    pub fn pdf_with(&self, wo: Vec3, wi: Vec3, selection: LobeSelection) -> f32 {
        match &self.layers {
            None => self.material_pdf(wo, wi),
            Some(l) => {
                let p = l.probabilities(wo, self.material_estimate(wo), selection);
                l.pdf(wo, wi, p) + p.core * self.material_pdf(wo, wi)
            }
        }
    }

    /// The material beneath the layers, times `|cos θi|`: the core plus its diffuse
    /// transmission.
    #[inline]
    fn material_eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        let core = self.core.eval(wo, wi);
        match &self.diffuse_transmission {
            None => core,
            Some(d) => {
                let (wo, wi) = self.lobe_side(wo, wi);
                core + d.eval(self.core.opaque(), wo, wi)
            }
        }
    }

    /// The material's density: `(1 − q)·core + q·transmission`, `q` the lobe's probability.
    #[inline]
    fn material_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some(d) = &self.diffuse_transmission else { return self.core.pdf(wo, wi) };
        self.mixture_pdf(d, self.transmission_probability(d, wo), wo, wi)
    }

    /// [`Self::material_pdf`] with the lobe's probability `q` given.
    #[inline]
    fn mixture_pdf(&self, d: &DiffuseTransmission, q: f32, wo: Vec3, wi: Vec3) -> f32 {
        let (wo_l, wi_l) = self.lobe_side(wo, wi);
        (1.0 - q) * self.core.pdf(wo, wi) + q * d.pdf(wo_l, wi_l)
    }

    /// The material's albedo estimate at ωo (for the layers' choice): the core's plus the
    /// diffuse transmission's.
    #[inline]
    fn material_estimate(&self, wo: Vec3) -> f32 {
        let core = self.core.albedo_estimate(wo);
        match &self.diffuse_transmission {
            None => core,
            Some(d) => core + d.albedo_estimate(self.core.opaque(), self.lobe_side(wo, wo).0),
        }
    }

    /// The probability of sampling the diffuse transmission lobe rather than the core: in
    /// proportion to their albedo estimates at ωo, each at least
    /// [`MIN_TRANSMISSION_PROBABILITY`].
    #[inline]
    fn transmission_probability(&self, d: &DiffuseTransmission, wo: Vec3) -> f32 {
        let t = d.albedo_estimate(self.core.opaque(), self.lobe_side(wo, wo).0);
        let q = t / (t + self.core.albedo_estimate(wo));
        let q = if q.is_finite() { q } else { 0.5 };
        q.clamp(MIN_TRANSMISSION_PROBABILITY, 1.0 - MIN_TRANSMISSION_PROBABILITY)
    }

    /// `(ωo, ωi)` in the frame the diffuse transmission lobe is defined in (ωo above): as
    /// given, or both mirrored where a solid's interface is seen from inside (its outward
    /// frame puts ωo below; the lobe is the same from either side).
    #[inline]
    fn lobe_side(&self, wo: Vec3, wi: Vec3) -> (Vec3, Vec3) {
        if wo.z < 0.0 && self.is_volume() {
            let m = Vec3::new(1.0, 1.0, -1.0);
            (wo * m, wi * m)
        } else {
            (wo, wi)
        }
    }

    /// Samples the material beneath the layers: the diffuse transmission lobe or the core by
    /// `uc` (drawn only with the lobe, or where the core draws it), then the mixture's pdf and
    /// weight; a delta event of the core keeps its direction with the choice divided out.
    #[inline]
    fn material_sample(&self, wo: Vec3, u: Vec2, uc: impl FnOnce() -> f32) -> Option<ScatterSample> {
        let Some(d) = &self.diffuse_transmission else { return self.core.sample(wo, u, uc) };
        let q = self.transmission_probability(d, wo);
        let uc = uc();
        let wi = if uc < q {
            let (wo_l, _) = self.lobe_side(wo, wo);
            self.lobe_side(wo, d.sample_direction(wo_l, u)?).1
        } else {
            let s = self.core.sample(wo, u, || rescale(uc, q, false))?;
            if s.delta {
                return Some(ScatterSample { weight: s.weight / (1.0 - q), ..s });
            }
            s.wi
        };
        let pdf = self.mixture_pdf(d, q, wo, wi);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let transmitted = (wi.z < 0.0) != (wo.z < 0.0);
        Some(ScatterSample {
            wi,
            weight: self.material_eval(wo, wi) / pdf,
            pdf,
            delta: false,
            transmitted,
            rest: 0.0,
        })
    }

    /// Samples a direction; the lobe number `uc` is drawn only where it decides something
    /// ([`MetallicRoughness::sample_lazy`]).
    #[inline]
    pub fn sample(&self, wo: Vec3, u: Vec2, uc: impl FnOnce() -> f32) -> Option<ScatterSample> {
        self.sample_with(wo, u, uc, LobeSelection::Albedo)
    }

    /// [`HitBsdf::sample`] with the layers chosen by `selection` (the renderers use
    /// [`LobeSelection::Albedo`]; the other rule is there to be measured against).
    #[inline]
    pub fn sample_with(
        &self,
        wo: Vec3,
        u: Vec2,
        uc: impl FnOnce() -> f32,
        selection: LobeSelection,
    ) -> Option<ScatterSample> {
        let Some(l) = &self.layers else { return self.material_sample(wo, u, uc) };
        let p = l.probabilities(wo, self.material_estimate(wo), selection);
        let uc = uc();
        let wi = if uc < p.clearcoat {
            l.clearcoat?.sample_direction(wo, u)?
        } else if uc < p.clearcoat + p.sheen {
            l.sheen?.sample(wo, 0.0, u)?.wi
        } else {
            let rest = ((uc - p.clearcoat - p.sheen) / p.core).min(ONE_BELOW);
            let s = self.material_sample(wo, u, || rest)?;
            if s.delta {
                // A delta event of the material: its weight through the layers, the choice of
                // the material divided out.
                let k = l.below_weight(wo, s.wi) / p.core;
                return Some(ScatterSample { weight: s.weight * k, ..s });
            }
            s.wi
        };
        let pdf = l.pdf(wo, wi, p) + p.core * self.material_pdf(wo, wi);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let transmitted = wi.z < 0.0;
        Some(ScatterSample { wi, weight: self.eval(wo, wi) / pdf, pdf, delta: false, transmitted, rest: 0.0 })
    }

    /// The BSDF with its clear coat's normal at `normal` (unit, in the shading frame); the
    /// same BSDF without a coat.
    #[inline]
    pub fn with_clearcoat_normal(mut self, normal: Vec3) -> Self {
        if let Some(Layers { clearcoat: Some(c), .. }) = &mut self.layers {
            *c = Clearcoat::with_normal(*c, normal);
        }
        self
    }

    /// Only delta lobes: no light sample can reach a direction.
    #[inline]
    pub fn is_delta(&self) -> bool {
        self.layers.is_none() && self.diffuse_transmission.is_none() && self.core.is_delta()
    }

    /// A thin-walled sheet or an η = 1 interface: straight passes are no events.
    #[inline]
    pub fn is_straight(&self) -> bool {
        matches!(self.core, Core::Transmissive(b, _) if b.dielectric.is_straight())
    }

    /// The interface of a solid.
    #[inline]
    pub fn is_volume(&self) -> bool {
        matches!(self.core, Core::Transmissive(_, true))
    }

    /// Light samples may arrive from behind the surface (a rough solid interface, a rough
    /// sheet, diffuse transmission).
    #[inline]
    pub fn transmits_light_samples(&self) -> bool {
        self.diffuse_transmission.is_some()
            || matches!(self.core, Core::Transmissive(b, true) if b.dielectric.interface == Interface::Rough)
            || matches!(self.core, Core::Transmissive(b, _) if b.dielectric.interface == Interface::RoughThinWalled)
    }

    /// A scattered ray that crosses the surface changes medium: the interface of a solid, by
    /// refraction or by diffuse transmission (KHR_materials_volume).
    #[inline]
    pub fn bounds_medium(&self) -> bool {
        self.is_volume() || self.diffuse_transmission.is_some_and(|d| d.volume)
    }

    /// What a shadow ray crossing a sheet (or an η = 1 interface) at cosine `cos` keeps:
    /// `g·T′·tint + (1 − g)·0`, through the layers.
    pub fn sheet_transmittance(&self, cos: f32) -> Rgb {
        let t = match self.core {
            Core::Transmissive(b, _) => b.weight * b.dielectric.shadow_transmittance(cos),
            _ => return Vec3::ZERO,
        };
        match &self.layers {
            None => t,
            // The ray enters at `cos` and leaves straight on: the layers at that direction.
            Some(l) => t * l.below_weight(Vec3::new(0.0, 0.0, cos.abs()), Vec3::new(0.0, 0.0, -cos.abs())),
        }
    }
}

impl Core {
    /// The core of `params`; with diffuse transmission `dt` (in `[0, 1]`) the Lambert base of
    /// the opaque part keeps `1 − dt` of its albedo.
    fn new(params: &LayeredParams, specular: SpecularOptions, dt: f32) -> Self {
        let mr = |metallic: f32| {
            let p = MetallicRoughnessParams {
                base_color: params.base_color,
                metallic,
                roughness: params.roughness,
                specular_factor: params.specular_factor,
                specular_color: params.specular_color,
            };
            let mut m = if params.iridescence > 0.0 {
                MetallicRoughness::new_iridescent(p, specular, params.iridescence, params.film)
            } else {
                MetallicRoughness::new(p, specular)
            };
            if dt > 0.0 {
                m.diffuse = Lambert::new(m.diffuse.albedo * (1.0 - dt));
            }
            m.with_anisotropy(params.anisotropy)
        };
        let metallic = params.metallic.clamp(0.0, 1.0);
        let g = params.transmission.clamp(0.0, 1.0) * (1.0 - metallic);
        if !(g > 0.0) {
            return Self::Opaque(mr(params.metallic));
        }
        let roughness = params.roughness.clamp(0.0, 1.0);
        // A sheet (no volume) is smooth or rough by the same rule as a solid's interface.
        let dielectric = Dielectric::new(
            params.ior,
            roughness * roughness,
            !params.volume,
            specular.masking,
            params.base_color,
        )
        .with_film(params.iridescence, params.film);
        // The opaque rest: metal m and the untransmitted dielectric (1 − m)(1 − T), renormalised.
        let opaque = mr(if g < 1.0 { (metallic / (1.0 - g)).min(1.0) } else { 0.0 });
        Self::Transmissive(Transmissive { dielectric, opaque, weight: g.min(1.0) }, params.volume)
    }

    #[inline]
    fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        match self {
            Self::Opaque(b) => b.eval(wo, wi),
            Self::Transmissive(b, _) => b.eval(wo, wi),
        }
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Self::Opaque(b) => b.pdf(wo, wi),
            Self::Transmissive(b, _) => b.pdf(wo, wi),
        }
    }

    #[inline]
    fn sample(&self, wo: Vec3, u: Vec2, uc: impl FnOnce() -> f32) -> Option<ScatterSample> {
        match self {
            Self::Opaque(b) => b.sample_lazy(wo, u, uc).map(ScatterSample::from),
            Self::Transmissive(b, _) => b.sample(wo, uc(), u),
        }
    }

    #[inline]
    fn is_delta(&self) -> bool {
        matches!(self, Self::Transmissive(b, _) if b.is_delta())
    }

    /// The opaque metallic-roughness part (whose Fresnel weight the diffuse transmission
    /// shares).
    #[inline]
    pub fn opaque(&self) -> &MetallicRoughness {
        match self {
            Self::Opaque(m) => m,
            Self::Transmissive(t, _) => &t.opaque,
        }
    }

    /// The material's albedo estimate (luminance) at `wo`, for choosing between it and the
    /// layers: the opaque lobes' estimates; a transmissive material's dielectric counts 1.
    #[inline]
    fn albedo_estimate(&self, wo: Vec3) -> f32 {
        let opaque = |m: &MetallicRoughness| {
            let (s, d) = m.albedo_estimates(wo);
            s + d
        };
        match self {
            Self::Opaque(m) => opaque(m),
            Self::Transmissive(t, _) => t.weight + (1.0 - t.weight) * opaque(&t.opaque),
        }
    }
}

/// The probabilities of sampling the coat, the sheen and the material (summing to 1).
#[derive(Debug, Clone, Copy)]
struct Probabilities {
    clearcoat: f32,
    sheen: f32,
    core: f32,
}

impl Layers {
    /// `1 − c·Fc(ωo)`: what the coat leaves to everything below it.
    #[inline]
    fn coat_rest(&self, wo: Vec3) -> f32 {
        self.clearcoat.map_or(1.0, |c| 1.0 - c.weight(wo))
    }

    /// The weight of the material beneath both layers for the pair (ωo, ωi):
    /// `(1 − c·Fc(ωo))·s(μo, μi)`.
    #[inline]
    fn below_weight(&self, wo: Vec3, wi: Vec3) -> f32 {
        let s = self.sheen.map_or(1.0, |s| s.base_scale(wo.z, wi.z));
        self.coat_rest(wo) * s
    }

    /// `coat + (1 − c·Fc)·(sheen + s·material)`, given the material's `core = eval`.
    #[inline]
    fn eval(&self, wo: Vec3, wi: Vec3, core: Rgb) -> Rgb {
        let mut below = core * self.sheen.map_or(1.0, |s| s.base_scale(wo.z, wi.z));
        if let Some(s) = &self.sheen {
            below += s.eval(wo, wi);
        }
        let mut f = below * self.coat_rest(wo);
        if let Some(c) = &self.clearcoat {
            f += c.eval(wo, wi);
        }
        f
    }

    /// The layers' part of the mixture pdf.
    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3, p: Probabilities) -> f32 {
        let mut pdf = 0.0;
        if let Some(c) = &self.clearcoat {
            pdf += p.clearcoat * c.pdf(wo, wi);
        }
        if let Some(s) = &self.sheen {
            pdf += p.sheen * s.pdf(wo, wi);
        }
        pdf
    }

    /// Lobe selection in proportion to the albedo estimates at ωo (coat `c·Fc·E_ss`, sheen
    /// `(1 − c·Fc)·lum(sheenColor)·E(μo)`, material `(1 − c·Fc)·(1 − max(sheenColor)·E(μo))`
    /// times its own estimate), each present layer at least [`MIN_LAYER_PROBABILITY`].
    #[inline]
    fn probabilities(&self, wo: Vec3, material_estimate: f32, selection: LobeSelection) -> Probabilities {
        if selection == LobeSelection::Uniform {
            let n = 1.0 + f32::from(u8::from(self.clearcoat.is_some()) + u8::from(self.sheen.is_some()));
            let p = |present: bool| if present { 1.0 / n } else { 0.0 };
            return Probabilities {
                clearcoat: p(self.clearcoat.is_some()),
                sheen: p(self.sheen.is_some()),
                core: 1.0 / n,
            };
        }
        let rest = self.coat_rest(wo);
        let c = self.clearcoat.map_or(0.0, |c| c.albedo_estimate(wo));
        let (s, scale) = match &self.sheen {
            Some(s) => (rest * s.albedo_estimate(wo.z), s.base_scale(wo.z, wo.z)),
            None => (0.0, 1.0),
        };
        let m = rest * scale * material_estimate;
        let floor = |present: bool, x: f32| if present { x.max(MIN_LAYER_PROBABILITY) } else { 0.0 };
        let total = c + s + m;
        let (c, s) = if total > 0.0 && total.is_finite() { (c / total, s / total) } else { (0.0, 0.0) };
        let c = floor(self.clearcoat.is_some(), c);
        let s = floor(self.sheen.is_some(), s);
        // The material keeps at least the floor too; the layers share the rest.
        let layers = (c + s).min(1.0 - MIN_LAYER_PROBABILITY);
        let k = if c + s > 0.0 { layers / (c + s) } else { 0.0 };
        Probabilities { clearcoat: c * k, sheen: s * k, core: 1.0 - layers }
    }
}
