//! KHR_materials_iridescence: a thin dielectric film on the material, whose interference
//! colours the specular reflection. The extension replaces the Fresnel weights of the
//! metallic-roughness material (dielectric and metal alike) by
//!
//! ```text
//! F_dielectric → (1 − i)·F_dielectric + i·film(1, ηf, sF·f0, d, cos θ)
//! F_metal      → (1 − i)·F_metal      + i·film(1, ηf, baseColor, d, cos θ)
//! ```
//!
//! with `i` = iridescenceFactor × texture.r, `ηf` = iridescenceIor, `d` the film's thickness in
//! nanometres and `film` the extension's `evalIridescence`: Belcour & Barla's airy summation
//! ("A Practical Extension to Microfacet Theory for the Modeling of Varying Iridescence", ACM
//! TOG 36(4), 2017) as the extension writes it: Schlick reflectances at both interfaces, the
//! base's index from its F0, the first two Fourier terms of the spectral integral against the
//! CIE sensitivities (Gaussian fits), to Rec. 709.
//!
//! `cos θ` is `ωo·ωm`, the angle at which every Fresnel term of the material is evaluated
//! (reciprocal; the Khronos sample viewer takes `n·ωo`). The diffuse base beneath the
//! dielectric is weighted by `1 − max(F_dielectric)` with the iridescent weight, as the
//! extension's `fresnel_mix` says.

use crate::Rgb;
use glam::Vec3;
use std::f32::consts::PI;

/// A thin film: its index of refraction and thickness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThinFilm {
    /// `iridescenceIor`, the film's index of refraction (outside: 1).
    pub ior: f32,
    /// The film's thickness in nanometres.
    pub thickness: f32,
}

/// The XYZ → linear Rec. 709 matrix of the extension, row by row.
const XYZ_TO_REC709: [Vec3; 3] = [
    Vec3::new(3.2404542, -1.5371385, -0.4985314),
    Vec3::new(-0.969266, 1.8760108, 0.041556),
    Vec3::new(0.0556434, -0.2040259, 1.0572252),
];

/// The extension's `evalSensitivity`: the Fourier transform of the CIE XYZ sensitivities
/// (three Gaussians and a second x lobe) at optical path difference `opd` (nm), phase-shifted
/// per channel by `shift`, normalised and turned to Rec. 709.
#[inline]
pub fn sensitivity(opd: f32, shift: Rgb) -> Rgb {
    let phase = 2.0 * PI * opd * 1.0e-9;
    let val = Vec3::new(5.4856e-13, 4.4201e-13, 5.2481e-13);
    let pos = Vec3::new(1.6810e+06, 1.7953e+06, 2.2084e+06);
    let var = Vec3::new(4.3278e+09, 9.3046e+09, 6.6121e+09);
    let cos = Vec3::new(
        (pos.x * phase + shift.x).cos(),
        (pos.y * phase + shift.y).cos(),
        (pos.z * phase + shift.z).cos(),
    );
    let e = -(phase * phase) * var;
    let gauss = Vec3::new(e.x.exp(), e.y.exp(), e.z.exp());
    let mut xyz = val * (2.0 * PI * var).map(f32::sqrt) * cos * gauss;
    xyz.x += 9.7470e-14
        * (2.0 * PI * 4.5282e+09f32).sqrt()
        * (2.2399e+06 * phase + shift.x).cos()
        * (-4.5282e+09 * phase * phase).exp();
    xyz /= 1.0685e-7;
    Vec3::new(XYZ_TO_REC709[0].dot(xyz), XYZ_TO_REC709[1].dot(xyz), XYZ_TO_REC709[2].dot(xyz))
}

/// Schlick's reflectance with F90 = 1.
#[inline]
fn schlick1(r0: f32, cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    r0 + (1.0 - r0) * (m2 * m2 * m)
}

/// The extension's `evalIridescence(1, film.ior, cos θ1, film.thickness, base_f0)`: the
/// reflectance of the film over a base of normal-incidence reflectance `base_f0`, seen from air
/// at `cos θ1` (its absolute value, clamped to 1).
///
/// Written as the extension's GLSL, clamped to `[0, 1]` (the text clamps below only; its
/// truncated sum overshoots 1 near grazing over bright bases, up to 1.28 for F0 0.8, film
/// index 1.5, 325 nm: a reflectance above 1 would create energy), with two changes that keep
/// every input finite: the base's
/// Schlick reflectance `((η3 − ηf)/(η3 + ηf))²` with `η3 = (1 + s)/(1 − s)`, `s = √(F0 + 10⁻⁴)`,
/// is computed as `((1 + s − ηf(1 − s))/(1 + s + ηf(1 − s)))²` (the same number without the
/// division by `1 − s`, which is 0 for a white metal), and `η3 < ηf` as the sign test it
/// amounts to. Total internal reflection in the film (ηf < 1 at grazing) reflects everything.
pub fn fresnel(film: ThinFilm, base_f0: Rgb, cos_theta1: f32) -> Rgb {
    let c1 = cos_theta1.abs().min(1.0);
    let eta = film.ior;
    let sin2_sq = (1.0 / eta) * (1.0 / eta) * (1.0 - c1 * c1);
    let cos2_sq = 1.0 - sin2_sq;
    if !(cos2_sq >= 0.0) {
        return Rgb::ONE;
    }
    let c2 = cos2_sq.sqrt();
    // First interface, air → film.
    let r0 = ((eta - 1.0) / (eta + 1.0)) * ((eta - 1.0) / (eta + 1.0));
    let r12 = schlick1(r0, c1);
    let t121 = 1.0 - r12;
    let phi12 = if eta < 1.0 { PI } else { 0.0 };
    let phi21 = PI - phi12;
    // Second interface, film → base, per channel.
    let s = (base_f0 + 1.0e-4).map(f32::sqrt);
    let m5 = {
        let m = (1.0 - c2).clamp(0.0, 1.0);
        let m2 = m * m;
        m2 * m2 * m
    };
    let channel = |s: f32| {
        let (a, b) = (1.0 + s, eta * (1.0 - s));
        let r = (a - b) / (a + b);
        let r1 = r * r;
        let r23 = r1 + (1.0 - r1) * m5;
        // η3 < ηf: with η3 = a/(1 − s), for s < 1 that is a < b; for s > 1 η3 is negative.
        let below = if s < 1.0 { a < b } else { s > 1.0 };
        (r23, if below { PI } else { 0.0 })
    };
    let (rx, px) = channel(s.x);
    let (ry, py) = channel(s.y);
    let (rz, pz) = channel(s.z);
    let r23 = Vec3::new(rx, ry, rz);
    let phi = phi21 + Vec3::new(px, py, pz);
    let opd = 2.0 * eta * film.thickness * c2;
    // The airy sum's first terms, integrated against the sensitivities.
    let r123 = (r12 * r23).clamp(Vec3::splat(1.0e-5), Vec3::splat(0.9999));
    let sqrt_r123 = r123.map(f32::sqrt);
    let rs = t121 * t121 * r23 / (1.0 - r123);
    let mut i = r12 + rs;
    let mut cm = rs - t121;
    for m in 1..=2 {
        cm *= sqrt_r123;
        let sm = 2.0 * sensitivity(m as f32 * opd, m as f32 * phi);
        i += cm * sm;
    }
    i.clamp(Vec3::ZERO, Vec3::ONE)
}

/// A material's iridescence at a shading point: the film and its weight, and the two Fresnel
/// bases it is evaluated over (the merged specular lobe of [`crate::MetallicRoughness`] mixes
/// them by `metallic`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Iridescence {
    /// `i`, in `(0, 1]`.
    pub factor: f32,
    /// The film.
    pub film: ThinFilm,
    /// The dielectric's base F0, `sF·min(f0·specularColor, 1)`.
    pub f0_dielectric: Rgb,
    /// The metal's base F0, `baseColor`.
    pub f0_metal: Rgb,
    /// `metallic`, the share of the metal.
    pub metallic: f32,
}

impl Iridescence {
    /// The film's reflectance over the dielectric, `film(1, ηf, sF·f0, d, cos)`.
    #[inline]
    pub fn dielectric(&self, cos: f32) -> Rgb {
        fresnel(self.film, self.f0_dielectric, cos)
    }

    /// The merged lobe's iridescent Fresnel: `(1 − i)·plain + i·mix(film over the
    /// dielectric, film over the metal, metallic)`, each film term evaluated only where its
    /// weight is not 0.
    #[inline]
    pub fn mix(&self, plain: Rgb, cos: f32) -> Rgb {
        let m = self.metallic;
        let mut film = Rgb::ZERO;
        if m < 1.0 {
            film += (1.0 - m) * self.dielectric(cos);
        }
        if m > 0.0 {
            film += m * fresnel(self.film, self.f0_metal, cos);
        }
        (1.0 - self.factor) * plain + self.factor * film
    }
}
