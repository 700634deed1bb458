//! KHR_materials_clearcoat: a white GGX reflection of index 1.5 on top of the material,
//! weighted as the extension's `fresnel_coat` layering does:
//!
//! ```text
//! coated = (1 − c·Fc)·material + c·Fc·D(α_c)·V(α_c),   Fc = 0.04 + 0.96·(1 − |ωo·n_c|)⁵
//! ```
//!
//! with `c = clearcoatFactor × texture.r`, `α_c = (clearcoatRoughness × texture.g)²` and `n_c`
//! the coat's normal (its own normal map, else the unperturbed shading normal). The Fresnel
//! term depends on the view alone (the extension's choice; not reciprocal). Sampled by the
//! GGX lobe's own method (visible normals by default).

use crate::frame::Frame;
use crate::specular::{GgxSpecular, SpecularOptions};
use crate::{Bsdf, Lobe, Rgb, Sample, above};
use glam::{Vec2, Vec3};

/// The coat's Fresnel weight at the view cosine `|ωo·n_c|`: Schlick with F0 = 0.04 (index
/// 1.5), F90 = 1.
#[inline]
pub fn fresnel(cos_o: f32) -> f32 {
    let m = (1.0 - cos_o.abs().min(1.0)).max(0.0);
    let m2 = m * m;
    0.04 + 0.96 * (m2 * m2 * m)
}

/// The clear coat at one shading point, in the base's shading frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clearcoat {
    /// `clearcoatFactor × texture.r`, in `[0, 1]`.
    pub factor: f32,
    /// The coat's GGX lobe with F = 1 (`f0 = f90 = 1`, no compensation).
    pub lobe: GgxSpecular,
    /// The coat's normal in the base's frame, or `None` where it is the base's normal (z).
    pub frame: Option<Frame>,
}

impl Clearcoat {
    /// A coat of `factor` (clamped to `[0, 1]`, NaN → 0) and perceptual `roughness` (α =
    /// roughness², clamped as GGX clamps it), whose normal in the base's frame is `normal`
    /// (unit; `Vec3::Z` for the base's own). `options` gives the masking form and sampling
    /// method; compensation never applies to the coat.
    pub fn new(factor: f32, roughness: f32, normal: Vec3, options: SpecularOptions) -> Self {
        let factor = if factor.is_nan() { 0.0 } else { factor.clamp(0.0, 1.0) };
        let r = if roughness.is_nan() { 0.0 } else { roughness.clamp(0.0, 1.0) };
        let mut lobe = GgxSpecular::new(r * r, Rgb::ONE, SpecularOptions { compensation: false, ..options });
        lobe.f90 = Rgb::ONE;
        Self { factor, lobe, frame: None }.with_normal(normal)
    }

    /// The same coat with its normal at `normal` in the base's frame (unit; `Vec3::Z` for the
    /// base's own).
    pub fn with_normal(self, normal: Vec3) -> Self {
        let frame = (normal != Vec3::Z && normal.is_finite() && normal.length_squared() > 0.0)
            .then(|| Frame::new(normal.normalize()));
        Self { frame, ..self }
    }

    /// `c·Fc(|ωo·n_c|)`: the coat's weight, and `1 −` it the weight of what lies beneath.
    #[inline]
    pub fn weight(&self, wo: Vec3) -> f32 {
        let cos_o = match self.frame {
            Some(f) => wo.dot(f.z),
            None => wo.z,
        };
        self.factor * fresnel(cos_o)
    }

    /// `D·V·cos θi` of the coat's lobe (without its weight), in the coat's frame.
    #[inline]
    fn lobe_eval(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self.frame {
            Some(f) => self.lobe.eval(f.to_local(wo), f.to_local(wi)).x,
            None => self.lobe.eval(wo, wi).x,
        }
    }

    /// The coat lobe's sampling density.
    #[inline]
    pub fn lobe_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self.frame {
            Some(f) => self.lobe.pdf(f.to_local(wo), f.to_local(wi)),
            None => self.lobe.pdf(wo, wi),
        }
    }

    /// A direction from the coat lobe (in the base's frame).
    #[inline]
    pub fn sample_direction(&self, wo: Vec3, u: Vec2) -> Option<Vec3> {
        match self.frame {
            Some(f) => {
                let (wi, ..) = self.lobe.sample_reflection(f.to_local(wo), u)?;
                Some(f.to_world(wi))
            }
            None => Some(self.lobe.sample_reflection(wo, u)?.0),
        }
    }

    /// The coat's albedo estimate at `wo` for lobe selection: `c·Fc·E_ss(μo, α_c)`.
    #[inline]
    pub fn albedo_estimate(&self, wo: Vec3) -> f32 {
        let mu = match self.frame {
            Some(f) => wo.dot(f.z),
            None => wo.z,
        };
        if !(mu > 0.0) {
            return 0.0;
        }
        self.weight(wo) * crate::turquin::e_ss(mu, self.lobe.ggx.alpha(), self.lobe.options.masking)
    }
}

impl Bsdf for Clearcoat {
    /// `c·Fc(|ωo·n_c|)·D·V·cos θi`; 0 unless both directions are above the base's horizon
    /// and the coat's.
    fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if !(above(wo) && above(wi)) {
            return Rgb::ZERO;
        }
        Rgb::splat(self.weight(wo) * self.lobe_eval(wo, wi))
    }

    fn sample(&self, wo: Vec3, _uc: f32, u: Vec2) -> Option<Sample> {
        if !above(wo) {
            return None;
        }
        let wi = self.sample_direction(wo, u)?;
        if !above(wi) {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(Sample { wi, weight: self.eval(wo, wi) / pdf, pdf, lobe: Lobe::Clearcoat })
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if !(above(wo) && above(wi)) {
            return 0.0;
        }
        self.lobe_pdf(wo, wi)
    }
}
