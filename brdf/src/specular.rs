//! The GGX specular reflection lobe with Schlick Fresnel and optional Turquin compensation.

use crate::fresnel::schlick;
use crate::ggx::{Ggx, Masking, SpecularSampling, reflect};
use crate::iridescence::Iridescence;
use crate::{Bsdf, Lobe, Rgb, Sample, above, turquin};
use glam::{Vec2, Vec3};

/// Model switches of the specular lobe: masking form, sampling method, energy compensation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SpecularOptions {
    /// Separable or height-correlated G2 (default height-correlated, as glTF specifies).
    pub masking: Masking,
    /// NDF, VNDF or spherical-cap VNDF sampling (default spherical caps).
    pub sampling: SpecularSampling,
    /// Turquin 2019 energy compensation (default on).
    pub compensation: bool,
}

impl Default for SpecularOptions {
    fn default() -> Self {
        Self { masking: Masking::default(), sampling: SpecularSampling::default(), compensation: true }
    }
}

impl SpecularOptions {
    /// Mitsuba 3's `roughconductor` model: separable masking, no compensation (what the
    /// independent references in `tests/data/references` were rendered with).
    pub fn mitsuba() -> Self {
        Self { masking: Masking::Separable, compensation: false, ..Self::default() }
    }
}

/// GGX microfacet reflection (Walter et al. 2007) with Schlick's Fresnel
/// `F = F0 + (F90 − F0)(1 − ωo·ωm)^5` (mixed with a thin film's where the material is
/// iridescent, [`crate::iridescence`]) and, when enabled, Turquin's compensation factor
/// `1 + F0·(1/E_ss(μo, α) − 1)`, F0 then being the Fresnel weight at `ωo·ωm = 1`.
///
/// `eval` includes the cosine: `F·D·G2/(4 cos θo)` (times the compensation factor).
/// The sample weight is `eval/pdf` in the closed forms that never divide by D:
/// NDF `F·G2·(ωo·ωm)/(cos θo·cos θm)`, VNDF `F·G2/G1(ωo)` (the thesis §3.2; Heitz 2018).
/// The pdf is in solid angle: `pdf_wm/(4 ωo·ωm)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GgxSpecular {
    /// The microfacet distribution.
    pub ggx: Ggx,
    /// Fresnel reflectance at normal incidence, per channel.
    pub f0: Rgb,
    /// Fresnel reflectance at grazing incidence (1 for a plain Schlick model).
    pub f90: Rgb,
    /// Model switches.
    pub options: SpecularOptions,
    /// KHR_materials_iridescence: the film whose Fresnel is mixed into Schlick's, with the
    /// compensation's F0 (the mixed Fresnel at `ωo·ωm = 1`). `None`: plain Schlick.
    pub iridescence: Option<(Iridescence, Rgb)>,
}

impl GgxSpecular {
    /// A specular lobe of roughness α (clamped, see [`crate::ggx::ALPHA_MIN`]) with F90 = 1;
    /// F0 is clamped to `[0, 1]` per channel (NaN → 0).
    pub fn new(alpha: f32, f0: Rgb, options: SpecularOptions) -> Self {
        Self {
            ggx: Ggx::new(alpha),
            f0: crate::clamp_rgb(f0, 1.0),
            f90: Rgb::ONE,
            options,
            iridescence: None,
        }
    }

    /// The lobe with a thin film's Fresnel mixed in (`factor` 0: unchanged).
    pub fn with_iridescence(mut self, iridescence: Iridescence) -> Self {
        if iridescence.factor > 0.0 {
            let f0 = iridescence.mix(schlick(self.f0, self.f90, 1.0), 1.0);
            self.iridescence = Some((iridescence, f0));
        }
        self
    }

    /// The Fresnel weight at `ωo·ωm = cos_om`.
    #[inline]
    pub fn fresnel(&self, cos_om: f32) -> Rgb {
        let f = schlick(self.f0, self.f90, cos_om);
        match &self.iridescence {
            None => f,
            Some((film, _)) => film.mix(f, cos_om),
        }
    }

    /// The Turquin factor for the view direction `wo` (1 when compensation is off, and for an
    /// anisotropic lobe: the isotropic tables do not bound its loss, see
    /// [`Ggx::alpha_effective`]; its multiple scattering is lost, docs/stability.md).
    #[inline]
    pub fn compensation(&self, wo: Vec3) -> Rgb {
        if self.options.compensation && !self.ggx.is_anisotropic() {
            let f0 = self.iridescence.map_or(self.f0, |(_, f0)| f0);
            turquin::compensation(f0, wo.z, self.ggx.alpha(), self.options.masking)
        } else {
            Rgb::ONE
        }
    }
}

/// The half vector `ωm = (ωo + ωi)/|ωo + ωi|` and `ωo·ωm`, or `None` when the sum vanishes.
///
/// `ωo·ωm` is computed as `|ωo + ωi|/2` (equal for unit vectors), never negative: the dot
/// product with the rounded half vector of a back-scattering pair `ωi ≈ −ωo` at grazing views
/// can come out ≤ 0, which made `pdf` return 0 for directions `sample` had just produced
/// (found by `tests/consistency.rs`).
#[inline]
fn half_vector(wo: Vec3, wi: Vec3) -> Option<(Vec3, f32)> {
    let h = wo + wi;
    let len = h.length();
    if !(len > 0.0) {
        return None;
    }
    Some((h / len, 0.5 * len))
}

impl GgxSpecular {
    /// The direction part of [`Bsdf::sample`] for `wo` above the horizon: `(ωi, ωm, ωo·ωm, pdf)`,
    /// or `None` exactly when `sample` returns `None`. Without the weight (G2, G1, Fresnel,
    /// compensation), for callers that only need the direction.
    #[inline]
    pub(crate) fn sample_reflection(&self, wo: Vec3, u: Vec2) -> Option<(Vec3, Vec3, f32, f32)> {
        let method = self.options.sampling;
        let wm = self.ggx.sample_wm(wo, u, method);
        let cos_om = wo.dot(wm);
        if !(cos_om > 0.0) {
            return None; // NDF sampled a back-facing microfacet
        }
        let wi = reflect(wo, wm);
        if !above(wi) {
            return None; // reflected below the horizon
        }
        let pdf = self.ggx.pdf_reflected(wo, wm, cos_om, method);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some((wi, wm, cos_om, pdf))
    }
}

impl Bsdf for GgxSpecular {
    fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if !(above(wo) && above(wi)) {
            return Rgb::ZERO;
        }
        let Some((wm, cos_om)) = half_vector(wo, wi) else {
            return Rgb::ZERO;
        };
        let f = self.fresnel(cos_om);
        f * self.ggx.eval_cos(wo, wi, wm, self.options.masking) * self.compensation(wo)
    }

    #[inline]
    fn sample(&self, wo: Vec3, _uc: f32, u: Vec2) -> Option<Sample> {
        if !above(wo) {
            return None;
        }
        let method = self.options.sampling;
        let (wi, wm, cos_om, pdf) = self.sample_reflection(wo, u)?;
        let g2 = self.ggx.g2(wo, wi, self.options.masking);
        let throughput = match method {
            SpecularSampling::Ndf => g2 * cos_om / (wo.z * wm.z),
            SpecularSampling::Vndf | SpecularSampling::SphericalCaps => g2 / self.ggx.g1(wo),
        };
        let weight = self.fresnel(cos_om) * throughput * self.compensation(wo);
        Some(Sample { wi, weight, pdf, lobe: Lobe::Specular })
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if !(above(wo) && above(wi)) {
            return 0.0;
        }
        let Some((wm, cos_om)) = half_vector(wo, wi) else {
            return 0.0;
        };
        self.ggx.pdf_reflected(wo, wm, cos_om, self.options.sampling)
    }
}
