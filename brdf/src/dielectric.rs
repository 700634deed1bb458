//! Dielectric interfaces — glass, water, thin sheets — with the exact unpolarised Fresnel
//! reflectance, and the glTF material that mixes one with the opaque metallic-roughness BSDF
//! (KHR_materials_transmission).
//!
//! * Smooth: mirror reflection with probability R, Snell refraction with 1 − R (delta lobes).
//! * Rough: the microfacet BSDF of Walter, Marschner, Li & Torrance, "Microfacet Models for
//!   Refraction through Rough Surfaces", EGSR 2007, with GGX, Smith masking (separable or
//!   height-correlated, the same form for both lobes as pbrt-v4), sampled by visible normals
//!   (Heitz 2018's distribution, drawn with Dupuy & Benyoub's spherical caps) of the side `wo`
//!   is on, then reflection or refraction chosen by F at the sampled normal (as Mitsuba 3's
//!   `roughdielectric` with `sample_visible`).
//! * Thin-walled: a sheet that reflects R′ = 2R/(1 + R) and lets T′ = 1 − R′ pass straight
//!   through (the sum of its inner reflections taken with the unpolarised R; Mitsuba's
//!   `thindielectric`).
//! * Rough thin-walled: a sheet whose faces are GGX microfacets. It reflects the rough lobe of
//!   the reflection model, weighted R′ at the microfacet, and transmits the same lobe mirrored
//!   through the sheet's plane, weighted T′ (a sheet of parallel rough faces: the light that
//!   crosses it leaves as the mirror image of what the first face reflects, as the thin-walled
//!   modes of Autodesk Standard Surface and Enterprise PBR model it). Sampled by visible
//!   normals of the side `wo` is on, then reflection or transmission by R′ at that normal.
//!
//! A thin film on the interface (KHR_materials_iridescence, [`Dielectric::with_film`]) makes the
//! reflectance a colour, `R = (1 − i)·R_exact + i·film(cos θ outside)` per channel, as the
//! extension's `rgb_mix` weighs the dielectric's layers: reflection takes `R`, transmission
//! `1 − max(R)`; reflection is chosen with probability `max(R)`. The film is taken at the
//! cosine on the outside (index 1) of the interface from either side, so the interface stays
//! symmetric as the exact Fresnel term is.
//!
//! Unlike the reflection models, a dielectric sees both hemispheres: the local frame's z is the
//! surface's **outward** normal (the side of index 1), `wo` may be on either side, and which
//! side it is on decides the relative index. Radiance is the transported quantity: light
//! refracted from index n_l into n_v carries (n_v / n_l)² of its radiance (the radiance-mode
//! BSDF: on a path from a camera in air to lights in air the factors cancel).

use crate::ggx::{ALPHA_MIN, Ggx, Masking, SpecularSampling, reflect};
use crate::iridescence::{self, ThinFilm};
use crate::metallic_roughness::MetallicRoughness;
use crate::{Bsdf, Rgb, clamp_rgb};
use glam::{Vec2, Vec3};

/// The exact unpolarised Fresnel reflectance of a dielectric interface and the refracted
/// cosine ([`fresnel_dielectric`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fresnel {
    /// `R = (r_s² + r_p²)/2`; 1 under total internal reflection.
    pub reflectance: f32,
    /// The refracted direction's cosine to the normal, of the sign opposite to `cos_i`'s
    /// (0 under total internal reflection).
    pub cos_t: f32,
    /// `n_t / n_i`: the index beyond the interface over the index on the incident side.
    pub eta_it: f32,
    /// `n_i / n_t = 1 / eta_it`.
    pub eta_ti: f32,
}

/// The exact unpolarised Fresnel reflectance for a direction at cosine `cos_i` to the normal
/// of an interface between index 1 (the side the normal points to) and index `eta` (the
/// other): `cos_i > 0` comes from the outside, `cos_i < 0` from inside.
///
/// `r_s = (cos θi − η′ cos θt)/(cos θi + η′ cos θt)`, `r_p = (η′ cos θi − cos θt)/(η′ cos θi +
/// cos θt)`, η′ = n_t/n_i; at grazing incidence R = 1, at `eta` = 1 exactly R = 0 and the ray
/// goes on (`cos_t = −cos_i`).
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> Fresnel {
    let outside = cos_i >= 0.0;
    let (eta_it, eta_ti) = if outside { (eta, 1.0 / eta) } else { (1.0 / eta, eta) };
    if eta == 1.0 {
        return Fresnel { reflectance: 0.0, cos_t: -cos_i, eta_it, eta_ti };
    }
    let ci = cos_i.abs().min(1.0);
    // Snell: sin²θt = η_ti² sin²θi.
    let cos_t2 = 1.0 - eta_ti * eta_ti * (1.0 - ci * ci);
    if !(cos_t2 > 0.0) {
        return Fresnel { reflectance: 1.0, cos_t: 0.0, eta_it, eta_ti };
    }
    let ct = cos_t2.sqrt();
    let rs = (ci - eta_it * ct) / (ci + eta_it * ct);
    let rp = (eta_it * ci - ct) / (eta_it * ci + ct);
    let reflectance = (0.5 * (rs * rs + rp * rp)).clamp(0.0, 1.0);
    Fresnel { reflectance, cos_t: if outside { -ct } else { ct }, eta_it, eta_ti }
}

/// The reflectance `R′ = 2R/(1 + R)` of a thin-walled sheet of index `eta` at cosine `cos_i`
/// (either side); it transmits `1 − R′`.
#[inline]
pub fn thin_reflectance(cos_i: f32, eta: f32) -> f32 {
    let r = fresnel_dielectric(cos_i.abs(), eta).reflectance;
    2.0 * r / (1.0 + r)
}

/// The kind of interface a [`Dielectric`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Interface {
    /// α below [`ALPHA_MIN`]: mirror reflection and Snell refraction (delta lobes).
    Smooth,
    /// GGX microfacets (Walter et al. 2007).
    Rough,
    /// A smooth thin-walled sheet: reflection R′, straight transmission T′ (delta lobes).
    ThinWalled,
    /// A rough thin-walled sheet: the GGX reflection weighted R′ and its mirror image through
    /// the sheet weighted T′.
    RoughThinWalled,
}

/// A sampled direction of a [`Dielectric`] or [`Transmissive`] BSDF.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScatterSample {
    /// The sampled direction towards the light, unit, on either side.
    pub wi: Vec3,
    /// `eval/pdf` per channel (for a delta event: its weight, the event's probability divided
    /// out).
    pub weight: Rgb,
    /// The solid-angle pdf for a non-delta sample; for a delta event the probability with which
    /// the dielectric chose that event (within a [`Transmissive`] mixture, not times its weight).
    pub pdf: f32,
    /// A delta event: no light sample can reach `wi` (no MIS).
    pub delta: bool,
    /// `wi` is on the other side of the interface (refraction, or the pass through a sheet).
    pub transmitted: bool,
    /// What is left of `uc` after the choices it made, rescaled to `[0, 1)`: independent of
    /// them, so a path that passes straight through a sheet (no scattering event) can reuse it
    /// for the next choice at the same event.
    pub rest: f32,
}

impl From<crate::Sample> for ScatterSample {
    /// A reflection model's sample: non-delta, reflected, no lobe number left over.
    fn from(s: crate::Sample) -> Self {
        Self { wi: s.wi, weight: s.weight, pdf: s.pdf, delta: false, transmitted: false, rest: 0.0 }
    }
}

/// `uc` rescaled after the choice `uc < p` (`taken`): uniform in `[0, 1)` again.
#[inline]
pub fn rescale(uc: f32, p: f32, taken: bool) -> f32 {
    let r = if taken { uc / p } else { (uc - p) / (1.0 - p) };
    if r.is_finite() { r.clamp(0.0, ONE_BELOW) } else { 0.0 }
}

/// A dielectric interface between index 1 (outside, the side the local z points to) and
/// index `eta` (inside). See the [module docs](self).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dielectric {
    /// Inside over outside index, in `[ETA_MIN, ETA_MAX]`.
    pub eta: f32,
    /// The microfacet distribution (used when [`Interface::Rough`] or
    /// [`Interface::RoughThinWalled`]).
    pub ggx: Ggx,
    /// Smooth, rough or thin-walled.
    pub interface: Interface,
    /// The masking-shadowing form of the rough interface.
    pub masking: Masking,
    /// Multiplies transmitted light (glTF: the base colour tints transmission).
    pub tint: Rgb,
    /// A thin film on the interface: its weight `i` in `(0, 1]` and the film
    /// ([`Dielectric::with_film`]); `None`: the exact Fresnel reflectance alone.
    pub film: Option<(f32, ThinFilm)>,
}

/// The smallest relative index a [`Dielectric`] takes (inputs are clamped).
pub const ETA_MIN: f32 = 1e-2;
/// The largest relative index a [`Dielectric`] takes.
pub const ETA_MAX: f32 = 1e2;

impl Dielectric {
    /// An interface of relative index `eta` (NaN → 1.5, clamped to `[ETA_MIN, ETA_MAX]`) and
    /// roughness `alpha` (α = glTF roughness²): smooth below [`ALPHA_MIN`] (and for NaN ≤ 0) or
    /// at η = 1, else rough with α clamped to 1; `thin_walled` makes it a sheet, smooth or rough
    /// by the same rule.
    /// `tint` is clamped to `[0, 1]` (NaN → 0).
    pub fn new(eta: f32, alpha: f32, thin_walled: bool, masking: Masking, tint: Rgb) -> Self {
        let eta = if eta.is_nan() { 1.5 } else { eta.clamp(ETA_MIN, ETA_MAX) };
        // At η = 1 exactly the interface is invisible whatever α (every microfacet refracts
        // straight through, a delta the microfacet form cannot represent).
        let rough = alpha >= ALPHA_MIN && eta != 1.0;
        let interface = match (thin_walled, rough) {
            (true, true) => Interface::RoughThinWalled,
            (true, false) => Interface::ThinWalled,
            (false, true) => Interface::Rough,
            (false, false) => Interface::Smooth,
        };
        Self { eta, ggx: Ggx::new(alpha), interface, masking, tint: clamp_rgb(tint, 1.0), film: None }
    }

    /// The interface under a thin film (KHR_materials_iridescence) of weight `factor` (clamped
    /// to `[0, 1]`, NaN → 0: no film), index `film.ior` (`[0.01, 100]`, NaN → 1.3) and
    /// thickness `film.thickness` nm (`[0, 10⁶]`, NaN → 0), over the interface's own F0
    /// `((η − 1)/(η + 1))²`. An interface of η = 1 (invisible, straight through) takes none.
    pub fn with_film(mut self, factor: f32, film: ThinFilm) -> Self {
        let factor = if factor.is_nan() { 0.0 } else { factor.clamp(0.0, 1.0) };
        if factor > 0.0 && self.eta != 1.0 {
            let ior = if film.ior.is_nan() { 1.3 } else { film.ior.clamp(0.01, 100.0) };
            let thickness = if film.thickness.is_nan() { 0.0 } else { film.thickness.clamp(0.0, 1.0e6) };
            self.film = Some((factor, ThinFilm { ior, thickness }));
        }
        self
    }

    /// The reflectance per channel for the exact Fresnel record `fr` at `cos_i` (either side):
    /// `fr.reflectance` in every channel without a film; under one (1 − i)·R + i·film at the
    /// outside cosine, and 1 under total internal reflection.
    #[inline]
    pub fn reflectance(&self, fr: &Fresnel, cos_i: f32) -> Rgb {
        let Some((i, film)) = self.film else { return Rgb::splat(fr.reflectance) };
        if fr.cos_t == 0.0 {
            return Rgb::ONE; // total internal reflection (or a grazing ray)
        }
        let c_out = if cos_i >= 0.0 { cos_i.min(1.0) } else { fr.cos_t.abs() };
        let f0 = self.film_f0();
        (1.0 - i) * fr.reflectance + i * iridescence::fresnel(film, Rgb::splat(f0), c_out)
    }

    /// The F0 the film lies on, `((η − 1)/(η + 1))²`.
    #[inline]
    fn film_f0(&self) -> f32 {
        let r = (self.eta - 1.0) / (self.eta + 1.0);
        r * r
    }

    /// A thin-walled sheet's reflectance per channel at `cos_i`: R′ in every channel without a
    /// film; under one (1 − i)·R′ + i·film(|cos_i|).
    #[inline]
    pub fn thin_reflectance_rgb(&self, cos_i: f32) -> Rgb {
        let r = thin_reflectance(cos_i, self.eta);
        let Some((i, film)) = self.film else { return Rgb::splat(r) };
        let f0 = self.film_f0();
        (1.0 - i) * r + i * iridescence::fresnel(film, Rgb::splat(f0), cos_i.abs().min(1.0))
    }

    /// Whether every lobe is a delta (smooth or smooth thin-walled): `eval` and `pdf` are 0.
    #[inline]
    pub fn is_delta(&self) -> bool {
        !matches!(self.interface, Interface::Rough | Interface::RoughThinWalled)
    }

    /// The BSDF times `|cos θi|`, per channel: 0 for delta interfaces.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if self.interface == Interface::RoughThinWalled {
            let Some(m) = self.sheet_microfacet(wo, wi) else { return Rgb::ZERO };
            let rgb = self.thin_reflectance_rgb(m.cos_oh);
            let f = self.ggx.d(m.h) * self.g2_over_cos_o(wo, wi) * 0.25;
            return if m.transmitted { self.tint * ((1.0 - rgb.max_element()) * f) } else { rgb * f };
        }
        if self.interface != Interface::Rough {
            return Rgb::ZERO;
        }
        let Some(m) = self.microfacet(wo, wi) else { return Rgb::ZERO };
        let d = self.ggx.d(m.h);
        let fr = fresnel_dielectric(m.cos_oh, self.eta);
        let r = self.reflectance(&fr, m.cos_oh);
        let g_over_co = self.g2_over_cos_o(wo, wi);
        if m.reflect {
            r * (d * g_over_co * 0.25)
        } else {
            let den = m.cos_oh + m.eta_it * m.cos_ih;
            let f = (m.cos_oh * m.cos_ih).abs() * (1.0 - r.max_element()) * d * g_over_co / (den * den);
            if f.is_finite() { self.tint * f } else { Rgb::ZERO }
        }
    }

    /// The solid-angle density of [`Dielectric::sample`] at `wi`: 0 for delta interfaces.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if self.interface == Interface::RoughThinWalled {
            let Some(m) = self.sheet_microfacet(wo, wi) else { return 0.0 };
            let p = self.thin_reflectance_rgb(m.cos_oh).max_element();
            // Visible normals of wo's side over 4|wo·h|: the reflection's, then the choice.
            let pdf = 2.0 / (wo.z.abs() + self.ggx_a(wo)) * self.ggx.d(m.h) * 0.25;
            let pdf = pdf * if m.transmitted { 1.0 - p } else { p };
            return if pdf.is_finite() { pdf } else { 0.0 };
        }
        if self.interface != Interface::Rough {
            return 0.0;
        }
        let Some(m) = self.microfacet(wo, wi) else { return 0.0 };
        let fr = fresnel_dielectric(m.cos_oh, self.eta);
        let p_reflect = self.reflectance(&fr, m.cos_oh).max_element();
        // Visible normals of the side wo is on: G1(wo)·|wo·h|·D(h)/|cos θo|, G1/|cos| = 2/(|z| + a).
        let d_vis_over_cos_oh = 2.0 / (wo.z.abs() + self.ggx_a(wo)) * self.ggx.d(m.h);
        let pdf = if m.reflect {
            // pdf_h · F / (4|wo·h|)
            d_vis_over_cos_oh * p_reflect * 0.25
        } else {
            let den = m.cos_oh + m.eta_it * m.cos_ih;
            d_vis_over_cos_oh
                * m.cos_oh.abs()
                * (1.0 - p_reflect)
                * (m.eta_it * m.eta_it * m.cos_ih.abs() / (den * den))
        };
        if pdf.is_finite() { pdf } else { 0.0 }
    }

    /// Samples `wi` from `uc` (reflection or transmission) and `u` (the microfacet normal of a
    /// rough interface). `None` when `wo` lies in the interface's plane or a rough sample lands
    /// on the wrong side.
    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<ScatterSample> {
        if !(wo.z != 0.0) || !wo.is_finite() {
            return None;
        }
        match self.interface {
            Interface::Smooth => {
                let fr = fresnel_dielectric(wo.z, self.eta);
                let r = self.reflectance(&fr, wo.z);
                let p = r.max_element();
                Some(if uc < p {
                    ScatterSample {
                        wi: Vec3::new(-wo.x, -wo.y, wo.z),
                        weight: if self.film.is_some() { r / p } else { Rgb::ONE },
                        pdf: p,
                        delta: true,
                        transmitted: false,
                        rest: rescale(uc, p, true),
                    }
                } else {
                    let wi = Vec3::new(-fr.eta_ti * wo.x, -fr.eta_ti * wo.y, fr.cos_t);
                    ScatterSample {
                        wi,
                        weight: self.tint * (fr.eta_ti * fr.eta_ti),
                        pdf: 1.0 - p,
                        delta: true,
                        transmitted: true,
                        rest: rescale(uc, p, false),
                    }
                })
            }
            Interface::ThinWalled => {
                let rgb = self.thin_reflectance_rgb(wo.z);
                let r = rgb.max_element();
                Some(if uc < r {
                    ScatterSample {
                        wi: Vec3::new(-wo.x, -wo.y, wo.z),
                        weight: if self.film.is_some() { rgb / r } else { Rgb::ONE },
                        pdf: r,
                        delta: true,
                        transmitted: false,
                        rest: rescale(uc, r, true),
                    }
                } else {
                    ScatterSample {
                        wi: -wo,
                        weight: self.tint,
                        pdf: 1.0 - r,
                        delta: true,
                        transmitted: true,
                        rest: rescale(uc, r, false),
                    }
                })
            }
            Interface::RoughThinWalled => {
                let flip = if wo.z > 0.0 { 1.0 } else { -1.0 };
                let h = self.ggx.sample_wm(wo * flip, u, SpecularSampling::SphericalCaps) * flip;
                let cos_oh = wo.dot(h);
                let r = reflect(wo, h);
                if !(cos_oh > 0.0) || !(r.z * flip > 0.0) {
                    return None;
                }
                let rgb = self.thin_reflectance_rgb(cos_oh);
                let p = rgb.max_element();
                let transmitted = uc >= p;
                // The transmitted direction: the reflection mirrored through the sheet.
                let wi = if transmitted { Vec3::new(r.x, r.y, -r.z) } else { r }.normalize_or_zero();
                let pdf = self.pdf(wo, wi);
                if !(pdf > 0.0) {
                    return None;
                }
                // eval/pdf: G2/G1(wo), tinted when transmitted; under a film the colour over
                // the probability max(R′).
                let w = self.g2_over_g1(wo, wi);
                let weight = if transmitted {
                    self.tint * w
                } else if self.film.is_some() {
                    rgb * (w / p)
                } else {
                    Rgb::splat(w)
                };
                let rest = rescale(uc, p, !transmitted);
                Some(ScatterSample { wi, weight, pdf, delta: false, transmitted, rest })
            }
            Interface::Rough => {
                let flip = if wo.z > 0.0 { 1.0 } else { -1.0 };
                let h = self.ggx.sample_wm(wo * flip, u, SpecularSampling::SphericalCaps);
                let cos_oh = wo.dot(h);
                let fr = fresnel_dielectric(cos_oh, self.eta);
                let r = self.reflectance(&fr, cos_oh);
                let p = r.max_element();
                let (wi, transmitted) = if uc < p {
                    (reflect(wo, h), false)
                } else {
                    // Mitsuba's refract: h·(cos_oh·η_ti + cos_t) − wo·η_ti.
                    (h * (cos_oh * fr.eta_ti + fr.cos_t) - wo * fr.eta_ti, true)
                };
                // Reflection stays on wo's side, refraction crosses.
                if (wi.z * flip > 0.0) == transmitted || wi.z == 0.0 {
                    return None;
                }
                let wi = wi.normalize_or_zero();
                let pdf = self.pdf(wo, wi);
                if !(pdf > 0.0) {
                    return None;
                }
                // eval/pdf in closed form: G2/G1(wo), times η_ti² and the tint when refracted.
                let mut weight = self.g2_over_g1(wo, wi);
                if transmitted {
                    let eta_ti = if wo.z > 0.0 { 1.0 / self.eta } else { self.eta };
                    weight *= eta_ti * eta_ti;
                }
                let weight = if transmitted {
                    self.tint * weight
                } else if self.film.is_some() {
                    // The film's colour at the sampled normal over the probability max(R).
                    r * (weight / p)
                } else {
                    Rgb::splat(weight)
                };
                let rest = rescale(uc, p, !transmitted);
                Some(ScatterSample { wi, weight, pdf, delta: false, transmitted, rest })
            }
        }
    }

    /// The fraction a shadow ray crossing this surface at cosine `cos` keeps: T′ = 1 − R′ times
    /// the tint for a thin-walled sheet, the tint for an interface of η = 1 (invisible); 0 for
    /// a rough sheet (its transmission is a lobe: light crosses it by scattering, found by
    /// light samples from behind it) and for any other interface of a solid (it blocks shadow
    /// rays, as Mitsuba's `volpath` does).
    pub fn shadow_transmittance(&self, cos: f32) -> Rgb {
        match self.interface {
            Interface::ThinWalled => self.tint * (1.0 - self.thin_reflectance_rgb(cos).max_element()),
            Interface::Smooth if self.eta == 1.0 => self.tint,
            _ => Rgb::ZERO,
        }
    }

    /// Whether a transmitted ray goes on undeviated (a thin-walled sheet, or η = 1): the pass
    /// is no scattering event.
    #[inline]
    pub fn is_straight(&self) -> bool {
        self.interface == Interface::ThinWalled || (self.interface == Interface::Smooth && self.eta == 1.0)
    }

    /// `a(ω) = √(z² + α²(x² + y²))`.
    #[inline]
    fn ggx_a(&self, w: Vec3) -> f32 {
        let a2 = self.ggx.alpha() * self.ggx.alpha();
        (w.z * w.z + a2 * (w.x * w.x + w.y * w.y)).sqrt()
    }

    /// `G2(wo, wi)/G1(wo)`: the weight of a visible-normal sample before its Fresnel and tint
    /// (0 where G1 is).
    #[inline]
    fn g2_over_g1(&self, wo: Vec3, wi: Vec3) -> f32 {
        let g1o = self.ggx.g1(wo);
        let g = self.g2_over_cos_o(wo, wi) * wo.z.abs();
        if g1o > 0.0 { g / g1o } else { 0.0 }
    }

    /// `G2(wo, wi)/|cos θo|` of the chosen masking form, with no 1/cos singularity:
    /// separable `2/(|zo| + ao) · G1(wi)`, height-correlated `2|zi|/(ao|zi| + ai|zo|)`.
    #[inline]
    fn g2_over_cos_o(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (zo, zi) = (wo.z.abs(), wi.z.abs());
        let (ao, ai) = (self.ggx_a(wo), self.ggx_a(wi));
        let r = match self.masking {
            Masking::Separable => 2.0 / (zo + ao) * (2.0 * zi / (zi + ai)),
            Masking::HeightCorrelated => 2.0 * zi / (ao * zi + ai * zo),
        };
        if r.is_finite() { r } else { 0.0 }
    }

    /// A rough sheet's microfacet normal for `wo` and `wi` (on either side): the half vector of
    /// `wo` and `wi` mirrored to `wo`'s side, oriented to that side, with `wo·h`; `None` where
    /// the BSDF is 0 (a direction in the plane, a normal seen from behind).
    #[inline]
    fn sheet_microfacet(&self, wo: Vec3, wi: Vec3) -> Option<SheetMicrofacet> {
        let (zo, zi) = (wo.z, wi.z);
        if zo == 0.0 || zi == 0.0 || !(zo.is_finite() && zi.is_finite()) {
            return None;
        }
        let transmitted = (zo > 0.0) != (zi > 0.0);
        let wr = if transmitted { Vec3::new(wi.x, wi.y, -wi.z) } else { wi };
        let h = (wo + wr).normalize_or_zero();
        if h == Vec3::ZERO {
            return None;
        }
        // D is read on the upper hemisphere: the normal of wo's side, turned up.
        let h = if h.z < 0.0 { -h } else { h };
        let cos_oh = wo.dot(h);
        if !(cos_oh * zo > 0.0 && wr.dot(h) * zo > 0.0) {
            return None;
        }
        Some(SheetMicrofacet { h, cos_oh, transmitted })
    }

    /// The microfacet normal joining `wo` and `wi` and its cosines, or `None` where the BSDF is
    /// 0 (a direction in the plane, a normal that either direction sees from behind).
    #[inline]
    fn microfacet(&self, wo: Vec3, wi: Vec3) -> Option<Microfacet> {
        let (zo, zi) = (wo.z, wi.z);
        if zo == 0.0 || zi == 0.0 || !(zo.is_finite() && zi.is_finite()) {
            return None;
        }
        let reflect = (zo > 0.0) == (zi > 0.0);
        let eta_it = if zo > 0.0 { self.eta } else { 1.0 / self.eta };
        let h = if reflect { wo + wi } else { wo + wi * eta_it };
        let h = h.normalize_or_zero();
        if h == Vec3::ZERO {
            return None;
        }
        let h = if h.z < 0.0 { -h } else { h };
        let (cos_oh, cos_ih) = (wo.dot(h), wi.dot(h));
        // Smith's side condition: each direction sees the microfacet from the side it is on.
        if !(cos_oh * zo > 0.0 && cos_ih * zi > 0.0) {
            return None;
        }
        Some(Microfacet { h, cos_oh, cos_ih, reflect, eta_it })
    }
}

struct SheetMicrofacet {
    h: Vec3,
    cos_oh: f32,
    transmitted: bool,
}

struct Microfacet {
    h: Vec3,
    cos_oh: f32,
    cos_ih: f32,
    reflect: bool,
    eta_it: f32,
}

/// The glTF material with KHR_materials_transmission at one shading point: with weight
/// `g = transmission·(1 − metallic)` a [`Dielectric`], otherwise the opaque
/// [`MetallicRoughness`] (whose metallic is then `metallic / (1 − g)`: glTF's
/// `mix(dielectric(mix(diffuse, transmission, T)), metal, metallic)` regrouped).
///
/// `eval = g·dielectric + (1 − g)·opaque`, `pdf` the same mixture; `sample` picks the part by
/// `uc` (rescaled to `[0, 1)` for the part's own choice). The opaque part reflects only on the
/// outside (z > 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transmissive {
    /// The interface.
    pub dielectric: Dielectric,
    /// The opaque rest.
    pub opaque: MetallicRoughness,
    /// `g`, the probability of the dielectric, in `(0, 1]`.
    pub weight: f32,
}

impl Transmissive {
    /// Whether both parts are delta (a pure smooth or thin dielectric): no light sample can
    /// find a direction.
    #[inline]
    pub fn is_delta(&self) -> bool {
        self.weight >= 1.0 && self.dielectric.is_delta()
    }

    /// `g·dielectric + (1 − g)·opaque`, times `|cos θi|`.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        let g = self.weight;
        let mut f = Rgb::ZERO;
        if !self.dielectric.is_delta() {
            f += g * self.dielectric.eval(wo, wi);
        }
        if g < 1.0 {
            f += (1.0 - g) * self.opaque.eval(wo, wi);
        }
        f
    }

    /// The density of the non-delta parts of `sample`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let g = self.weight;
        let mut p = 0.0;
        if !self.dielectric.is_delta() {
            p += g * self.dielectric.pdf(wo, wi);
        }
        if g < 1.0 {
            p += (1.0 - g) * self.opaque.pdf(wo, wi);
        }
        p
    }

    /// Samples a part by `uc`, then a direction from it; non-delta samples are weighted by the
    /// whole mixture (one-sample MIS).
    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<ScatterSample> {
        let g = self.weight;
        if g >= 1.0 {
            return self.dielectric.sample(wo, uc, u);
        }
        let s = if uc < g {
            let s = self.dielectric.sample(wo, rescale(uc, g, true), u)?;
            if s.delta {
                return Some(s);
            }
            s
        } else {
            ScatterSample::from(self.opaque.sample(wo, rescale(uc, g, false), u)?)
        };
        let pdf = self.pdf(wo, s.wi);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(ScatterSample { weight: self.eval(wo, s.wi) / pdf, pdf, ..s })
    }
}

/// The largest `f32` below 1: a rescaled uniform number stays in `[0, 1)`.
pub const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;
