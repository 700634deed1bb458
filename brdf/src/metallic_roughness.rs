//! The glTF 2.0 metallic-roughness material (with KHR_materials_specular): a Lambertian base
//! under a GGX specular layer, mixed with a GGX conductor by `metallic`.

use crate::fresnel::schlick;
use crate::iridescence::{Iridescence, ThinFilm};
use crate::lambert::Lambert;
use crate::specular::{GgxSpecular, SpecularOptions};
use crate::{Bsdf, Lobe, Rgb, Sample, above, clamp_rgb};
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

/// Parameters of a glTF metallic-roughness material at one shading point (after texture
/// lookups). Out-of-range and NaN inputs are clamped/replaced when the BSDF is built.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MetallicRoughnessParams {
    /// `baseColorFactor × baseColorTexture`, linear RGB in `[0, 1]`.
    pub base_color: Rgb,
    /// `metallicFactor × texture.b`, in `[0, 1]`.
    pub metallic: f32,
    /// Perceptual roughness `roughnessFactor × texture.g`, in `[0, 1]`; α = roughness².
    pub roughness: f32,
    /// KHR_materials_specular `specularFactor` (default 1).
    pub specular_factor: f32,
    /// KHR_materials_specular `specularColorFactor` (default 1, may exceed 1).
    pub specular_color: Rgb,
}

impl Default for MetallicRoughnessParams {
    /// glTF's defaults: white, fully metallic, fully rough, default specular.
    fn default() -> Self {
        Self {
            base_color: Rgb::ONE,
            metallic: 1.0,
            roughness: 1.0,
            specular_factor: 1.0,
            specular_color: Rgb::ONE,
        }
    }
}

/// The glTF metallic-roughness BSDF, as the glTF 2.0 specification (Appendix B) and
/// KHR_materials_specular define it, with the two layers merged into one GGX lobe:
///
/// ```text
/// dielectric = (1 − sF·max(fr))·diffuse + sF·fr·specular,  fr = Schlick(f0d, 1, ωo·ωm),
///              f0d = min(0.04·specularColor, 1)
/// metal      = Schlick(baseColor, 1, ωo·ωm)·specular
/// material   = mix(dielectric, metal, metallic)
///   ⇒ specular lobe F0 = mix(0.04·sF·sC, baseColor, metallic), F90 = mix(sF, 1, metallic);
///     diffuse albedo = baseColor·(1 − metallic), scaled by (1 − sF·max(fr)) at the half vector.
/// ```
///
/// `eval` includes the cosine. `sample` picks the specular lobe with probability
/// `p = Fs/(Fs + Fd)` from Fresnel-weighted albedo estimates at `μo` (specular `lum(F(μo))`,
/// times `E_ss` without compensation; diffuse `lum(albedo)·(1 − sF·max(fr(μo)))`), clamped to
/// `[0.05, 0.95]` when both lobes are present so neither is starved; the returned pdf is the
/// mixture `p·pdf_spec + (1 − p)·pdf_diffuse` (one-sample MIS, also what [`Bsdf::pdf`]
/// returns) and the weight `eval/pdf`. A lobe that is exactly zero is never sampled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MetallicRoughness {
    /// The Lambertian base, albedo `baseColor·(1 − metallic)` (before the Fresnel weighting).
    pub diffuse: Lambert,
    /// The merged specular lobe.
    pub specular: GgxSpecular,
    /// `sF`: scales the dielectric layer's Fresnel, and so the diffuse attenuation.
    specular_factor: f32,
    /// `min(0.04·specularColor, 1)`: the dielectric F0 before `sF`.
    f0_dielectric: Rgb,
}

fn sanitize(x: f32, lo: f32, hi: f32, default: f32) -> f32 {
    if x.is_nan() { default } else { x.clamp(lo, hi) }
}

/// Rec. 709 luminance ([`furnace_sampling::LUMINANCE`]).
#[inline]
pub fn luminance(c: Rgb) -> f32 {
    c.dot(Rgb::from_array(furnace_sampling::LUMINANCE))
}

impl MetallicRoughness {
    /// Builds the BSDF from glTF parameters and model switches.
    pub fn new(params: MetallicRoughnessParams, options: SpecularOptions) -> Self {
        let base = clamp_rgb(params.base_color, 1.0);
        let metallic = sanitize(params.metallic, 0.0, 1.0, 1.0);
        let roughness = sanitize(params.roughness, 0.0, 1.0, 1.0);
        let sf = sanitize(params.specular_factor, 0.0, 1.0, 1.0);
        let sc = clamp_rgb(params.specular_color, f32::MAX);
        let f0_dielectric = (0.04 * sc).min(Rgb::ONE);
        let f0 = (f0_dielectric * sf).lerp(base, metallic);
        let f90 = Rgb::splat(sf + (1.0 - sf) * metallic);
        let mut specular = GgxSpecular::new(roughness * roughness, f0, options);
        specular.f90 = f90;
        Self { diffuse: Lambert::new(base * (1.0 - metallic)), specular, specular_factor: sf, f0_dielectric }
    }

    /// The material with an anisotropic specular lobe (KHR_materials_anisotropy) of strength
    /// `s` (clamped to `[0, 1]`, NaN → 0: isotropic): `αx = mix(α, 1, s²)` along the shading
    /// frame's x axis, which the caller aligns with the anisotropy direction, and `αy = α`.
    pub fn with_anisotropy(mut self, strength: f32) -> Self {
        let s = sanitize(strength, 0.0, 1.0, 0.0);
        if s > 0.0 {
            let (alpha, s2) = (self.specular.ggx.alpha(), s * s);
            self.specular.ggx = crate::ggx::Ggx::anisotropic(alpha * (1.0 - s2) + s2, alpha);
        }
        self
    }

    /// The material under a thin film (KHR_materials_iridescence) of weight `factor`
    /// (clamped to `[0, 1]`, NaN → 0: no film), index `film.ior` (clamped to `[0.01, 100]`,
    /// NaN → 1.3) and thickness `film.thickness` nm (clamped to `[0, 10⁶]`, NaN → 0): the
    /// Fresnel weights of both the dielectric and the metal mix in the film's
    /// ([`crate::iridescence`]).
    pub fn new_iridescent(
        params: MetallicRoughnessParams,
        options: SpecularOptions,
        factor: f32,
        film: ThinFilm,
    ) -> Self {
        let mut m = Self::new(params, options);
        let factor = sanitize(factor, 0.0, 1.0, 0.0);
        if factor > 0.0 {
            let film = ThinFilm {
                ior: sanitize(film.ior, 0.01, 100.0, 1.3),
                thickness: sanitize(film.thickness, 0.0, 1.0e6, 0.0),
            };
            m.specular = m.specular.with_iridescence(Iridescence {
                factor,
                film,
                f0_dielectric: m.f0_dielectric * m.specular_factor,
                f0_metal: clamp_rgb(params.base_color, 1.0),
                metallic: sanitize(params.metallic, 0.0, 1.0, 1.0),
            });
        }
        m
    }

    /// `sF` as the constructor sanitised it (`[0, 1]`, NaN → 1): scales the dielectric layer's
    /// Fresnel, and so the diffuse attenuation. With [`Self::f0_dielectric`], `diffuse` and
    /// `specular`, the whole record a GPU twin uploads.
    pub fn specular_factor(&self) -> f32 {
        self.specular_factor
    }

    /// `min(0.04·specularColor, 1)` with specularColor clamped to `[0, f32::MAX]` (NaN → 0): the
    /// dielectric layer's F0 before `sF`.
    pub fn f0_dielectric(&self) -> Rgb {
        self.f0_dielectric
    }

    /// The diffuse attenuation `1 − sF·max(fr(cos θd))` of the dielectric layer (also the
    /// diffuse transmission lobe's); under a film `1 − max((1 − i)·sF·fr + i·film(cos θd))`.
    #[inline]
    pub(crate) fn diffuse_scale(&self, cos_theta_d: f32) -> f32 {
        if let Some((film, _)) = &self.specular.iridescence {
            let fr = schlick(self.f0_dielectric, Rgb::ONE, cos_theta_d) * self.specular_factor;
            let fw = (1.0 - film.factor) * fr + film.factor * film.dielectric(cos_theta_d);
            return 1.0 - fw.max_element();
        }
        if self.specular_factor == 0.0 {
            return 1.0; // `1 − 0·fr`, fr finite: the same value without the Fresnel term
        }
        let fr = schlick(self.f0_dielectric, Rgb::ONE, cos_theta_d);
        1.0 - self.specular_factor * fr.max_element()
    }

    /// The albedo estimates (luminance) of the specular and diffuse lobes at `wo` that lobe
    /// selection weighs them by: specular `lum(F(μo))`, times `E_ss` without compensation (or
    /// when anisotropic, uncompensated, at [`crate::Ggx::alpha_effective`]);
    /// diffuse `lum(albedo)·(1 − sF·max(fr(μo)))`.
    #[inline]
    pub fn albedo_estimates(&self, wo: Vec3) -> (f32, f32) {
        let mu = wo.z.clamp(0.0, 1.0);
        let mut spec = luminance(self.specular.fresnel(mu));
        if !self.specular.options.compensation || self.specular.ggx.is_anisotropic() {
            spec *=
                crate::turquin::e_ss(mu, self.specular.ggx.alpha_effective(), self.specular.options.masking);
        }
        (spec, luminance(self.diffuse.albedo) * self.diffuse_scale(mu))
    }

    /// The probability of sampling the specular lobe for view direction `wo`.
    pub fn specular_probability(&self, wo: Vec3) -> f32 {
        let (spec, diff) = self.albedo_estimates(wo);
        if !(diff > 0.0) {
            // Only a diffuse lobe that is zero everywhere may go unsampled. With specularFactor 1
            // the estimate `1 − F(μo)` rounds to 0 below μo ≈ 1e-8 although `eval`'s diffuse
            // term (scaled at the half vector) is not: sampling only the specular lobe there
            // dropped that energy (tests/consistency.rs,
            // samples_carry_both_lobes_when_a_lobe_estimate_vanishes).
            return if self.diffuse.albedo == Rgb::ZERO { 1.0 } else { 0.95 };
        }
        if !(spec > 0.0) {
            return 0.0;
        }
        (spec / (spec + diff)).clamp(0.05, 0.95)
    }

    /// Whether the specular lobe is exactly zero (`F0 = F90 = 0`: metallic 0 with
    /// `specularFactor` 0, a plain Lambert surface). Its Fresnel factor is then `+0` and its
    /// `eval` `+0` (every other factor is finite), so skipping it changes no bit of a result.
    #[inline]
    fn specular_is_zero(&self) -> bool {
        self.specular.f0 == Rgb::ZERO && self.specular.f90 == Rgb::ZERO && self.specular.iridescence.is_none()
    }

    /// [`Bsdf::sample`] with the lobe-choice number `uc ∈ [0, 1)` drawn only when it decides
    /// something: `uc()` is called only if both lobes can be chosen (`0 < p < 1`). The result is
    /// that of `sample(wo, uc(), u)`. A path tracer saves a sampler dimension at every Lambert or
    /// pure-metal hit this way (samplers are addressable: skipping a dimension changes no other).
    #[inline]
    pub fn sample_lazy(&self, wo: Vec3, u: Vec2, uc: impl FnOnce() -> f32) -> Option<Sample> {
        if !above(wo) {
            return None;
        }
        let p = self.specular_probability(wo);
        if p >= 1.0 {
            return self.specular.sample(wo, 0.0, u); // the GGX lobe ignores uc
        }
        // With p = 0, `uc < p` is false for every uc ∈ [0, 1).
        let specular = p > 0.0 && uc() < p;
        self.sample_mixture(wo, p, specular, u)
    }

    /// The two-lobe part of `sample` once the lobe is chosen (`p < 1`).
    #[inline]
    fn sample_mixture(&self, wo: Vec3, p: f32, specular: bool, u: Vec2) -> Option<Sample> {
        let (wi, lobe) = if specular {
            // Only the direction: the weight is formed below from the mixture.
            (self.specular.sample_reflection(wo, u)?.0, Lobe::Specular)
        } else {
            // Lambert's sample ignores uc.
            (self.diffuse.sample(wo, 0.0, u)?.wi, Lobe::Diffuse)
        };
        let pdf = self.mixture_pdf(p, wo, wi);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(Sample { wi, weight: self.eval(wo, wi) / pdf, pdf, lobe })
    }

    /// `p·pdf_spec + (1 − p)·pdf_diffuse`; with `p = 0` exactly `pdf_diffuse` (the specular
    /// pdf is finite, so `0·pdf_spec = +0`), without evaluating the specular pdf.
    #[inline]
    fn mixture_pdf(&self, p: f32, wo: Vec3, wi: Vec3) -> f32 {
        if p == 0.0 {
            return self.diffuse.pdf(wo, wi);
        }
        p * self.specular.pdf(wo, wi) + (1.0 - p) * self.diffuse.pdf(wo, wi)
    }

    fn eval_diffuse(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if self.diffuse.albedo == Rgb::ZERO || !(above(wo) && above(wi)) {
            return Rgb::ZERO;
        }
        if self.specular_factor == 0.0 && self.specular.iridescence.is_none() {
            // diffuse_scale is exactly 1: no half vector needed.
            return self.diffuse.albedo * (FRAC_1_PI * wi.z * 1.0);
        }
        let wm = (wo + wi).normalize_or(Vec3::Z);
        self.diffuse.albedo * (FRAC_1_PI * wi.z * self.diffuse_scale(wo.dot(wm)))
    }
}

impl Bsdf for MetallicRoughness {
    /// `(diffuse + specular)·cos θi`.
    fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if self.specular_is_zero() {
            // `d + (+0) = d`: the zero lobe is not evaluated.
            return self.eval_diffuse(wo, wi);
        }
        self.eval_diffuse(wo, wi) + self.specular.eval(wo, wi)
    }

    fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<Sample> {
        if !above(wo) {
            return None;
        }
        let p = self.specular_probability(wo);
        if p >= 1.0 {
            return self.specular.sample(wo, uc, u);
        }
        self.sample_mixture(wo, p, uc < p, u)
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let p = self.specular_probability(wo);
        if p >= 1.0 {
            return self.specular.pdf(wo, wi);
        }
        self.mixture_pdf(p, wo, wi)
    }
}
