//! The GGX (Trowbridge–Reitz) microfacet distribution, isotropic or anisotropic: D, Smith
//! Λ/G1/G2, and three ways to sample microfacet normals.
//!
//! * D and Smith masking: Walter, Marschner, Li & Torrance, "Microfacet Models for Refraction
//!   through Rough Surfaces", EGSR 2007; Heitz, "Understanding the Masking-Shadowing Function
//!   in Microfacet-Based BRDFs", JCGT 3(2), 2014 (separable and height-correlated G2).
//! * NDF sampling (the thesis §3.2): `tan²θm = α²·u/(1−u)`, pdf `D(ωm)·cos θm`.
//! * VNDF sampling: Heitz, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4), 2018.
//! * VNDF by spherical caps: Dupuy & Benyoub, "Sampling Visible GGX Normals with Spherical
//!   Caps", HPG 2023 — the same density as Heitz 2018, fewer operations.
//!
//! * Anisotropy: the distribution stretched by `αx` along x and `αy` along y (Heitz 2014 §5.3;
//!   KHR_materials_anisotropy's D and V with x the anisotropy direction): every formula below
//!   takes `α²x²` as `αx²x²` and `α²y²` as `αy²y²`; the samplers stretch and unstretch with
//!   `(αx, αy)`.
//!
//! All in the local shading frame, z = geometric normal. Formulas are written in forms that
//! stay finite at grazing angles: with `a(ω) = √(z² + αx²x² + αy²y²)`,
//! `Λ(ω) = (a/|z| − 1)/2` and `G1(ω) = 2|z|/(|z| + a)`, which tends to 0 (not NaN) as z → 0.

use crate::above;
use glam::{Vec2, Vec3};
use std::f32::consts::{PI, TAU};

/// The smallest roughness α used. Inputs below it (including 0, a glTF mirror) are raised to
/// it: below ~1e-4 an `f32` half vector `normalize(wo + wi)` no longer resolves the lobe (its
/// error, ~1e-7, becomes a large fraction of α, so `pdf` stops matching `sample`). A lobe of
/// α = 1e-4 is 0.006° wide, indistinguishable from a mirror at image resolution, and keeps
/// every formula here finite (D ≤ 1/(π·1e-8) ≈ 3.2e7).
pub const ALPHA_MIN: f32 = 1e-4;

/// Which Smith masking-shadowing function G2 to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Masking {
    /// `G2 = G1(ωo)·G1(ωi)` — the thesis and Mitsuba 3 (`roughconductor`).
    Separable,
    /// `G2 = 1/(1 + Λ(ωo) + Λ(ωi))` — the glTF 2.0 specification and pbrt-v4 (default).
    #[default]
    HeightCorrelated,
}

/// How the specular lobe samples microfacet normals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum SpecularSampling {
    /// The distribution of normals, `D(ωm)·cos θm` (the thesis). Wastes samples on normals the
    /// viewer cannot see and on reflections below the horizon at grazing angles.
    Ndf,
    /// Visible normals, Heitz 2018.
    Vndf,
    /// Visible normals by spherical caps, Dupuy & Benyoub 2023 (default: same density as
    /// [`SpecularSampling::Vndf`], cheaper).
    #[default]
    SphericalCaps,
}

/// A GGX distribution of roughness α (α = glTF roughness²), or `(αx, αy)` when anisotropic.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ggx {
    /// α along x (all of it when isotropic).
    alpha: f32,
    /// α along y.
    alpha_y: f32,
}

/// α clamped to `[ALPHA_MIN, 1]`, NaN → 1.
#[inline]
fn clamp_alpha(alpha: f32) -> f32 {
    if alpha.is_nan() { 1.0 } else { alpha.clamp(ALPHA_MIN, 1.0) }
}

impl Ggx {
    /// An isotropic GGX distribution; α is clamped to `[ALPHA_MIN, 1]` (NaN becomes 1). See
    /// [`ALPHA_MIN`].
    pub fn new(alpha: f32) -> Self {
        let alpha = clamp_alpha(alpha);
        Self { alpha, alpha_y: alpha }
    }

    /// An anisotropic GGX distribution of roughness `alpha_x` along the frame's x axis and
    /// `alpha_y` along its y axis, each clamped as in [`Ggx::new`].
    pub fn anisotropic(alpha_x: f32, alpha_y: f32) -> Self {
        Self { alpha: clamp_alpha(alpha_x), alpha_y: clamp_alpha(alpha_y) }
    }

    /// The roughness α in use (after clamping); α along x when anisotropic.
    pub fn alpha(&self) -> f32 {
        self.alpha
    }

    /// `(αx, αy)` in use (equal when isotropic).
    pub fn alphas(&self) -> (f32, f32) {
        (self.alpha, self.alpha_y)
    }

    /// Whether `αx ≠ αy`.
    pub fn is_anisotropic(&self) -> bool {
        self.alpha != self.alpha_y
    }

    /// The isotropic α whose directional albedo stands in for this distribution's in the
    /// lobe-selection estimate: α itself when isotropic, else the root mean square
    /// `√((αx² + αy²)/2)`, whose albedo is within 11 % of the anisotropic lobe's at the views
    /// measured (`brdf/tests/anisotropy.rs`'s energy table; strengths to 1). Not good enough
    /// for compensation: at grazing views along the rough axis the anisotropic lobe loses less
    /// than the isotropic lobe of even `min(αx, αy)`, so no isotropic table bounds its loss.
    #[inline]
    pub fn alpha_effective(&self) -> f32 {
        if !self.is_anisotropic() {
            return self.alpha;
        }
        (0.5 * (self.alpha * self.alpha + self.alpha_y * self.alpha_y)).sqrt()
    }

    /// `a(ω) = √(z² + αx²x² + αy²y²)`, the stretched length that Λ and G1 are built from.
    #[inline]
    fn a(&self, w: Vec3) -> f32 {
        if self.is_anisotropic() {
            let (ax, ay) = (self.alpha * w.x, self.alpha_y * w.y);
            return (w.z * w.z + ax * ax + ay * ay).sqrt();
        }
        let a2 = self.alpha * self.alpha;
        (w.z * w.z + a2 * (w.x * w.x + w.y * w.y)).sqrt()
    }

    /// The normal distribution `D(ωm) = 1 / (π αx αy (x²/αx² + y²/αy² + z²)²)` for a unit `ωm`
    /// (Walter et al. 2007, eq. 33, written without tan θ; Heitz 2014 eq. 81 anisotropic). 0
    /// below the horizon.
    #[inline]
    pub fn d(&self, wm: Vec3) -> f32 {
        if !(wm.z > 0.0) {
            return 0.0;
        }
        if self.is_anisotropic() {
            let (x, y) = (wm.x / self.alpha, wm.y / self.alpha_y);
            let t = x * x + y * y + wm.z * wm.z;
            return 1.0 / (PI * self.alpha * self.alpha_y * t * t);
        }
        let a2 = self.alpha * self.alpha;
        let t = (wm.x * wm.x + wm.y * wm.y) / a2 + wm.z * wm.z;
        1.0 / (PI * a2 * t * t)
    }

    /// Smith's `Λ(ω) = (−1 + √(1 + α² tan²θ))/2 = (a/|z| − 1)/2`; `+∞` at the horizon.
    #[inline]
    pub fn lambda(&self, w: Vec3) -> f32 {
        let z = w.z.abs();
        if z == 0.0 { f32::INFINITY } else { 0.5 * (self.a(w) / z - 1.0) }
    }

    /// Smith's masking `G1(ω) = 1/(1 + Λ(ω)) = 2|z|/(|z| + a(ω))`, in `[0, 1]`, 0 at the horizon.
    #[inline]
    pub fn g1(&self, w: Vec3) -> f32 {
        let z = w.z.abs();
        let den = z + self.a(w);
        if den > 0.0 { 2.0 * z / den } else { 0.0 }
    }

    /// The masking-shadowing function `G2(ωo, ωi)` of the chosen form (both directions above
    /// the horizon; 0 otherwise).
    #[inline]
    pub fn g2(&self, wo: Vec3, wi: Vec3, masking: Masking) -> f32 {
        if !(above(wo) && above(wi)) {
            return 0.0;
        }
        match masking {
            Masking::Separable => self.g1(wo) * self.g1(wi),
            Masking::HeightCorrelated => {
                // 1/(1 + Λo + Λi) = 2 zo zi / (ao zi + ai zo)
                let (ao, ai) = (self.a(wo), self.a(wi));
                2.0 * wo.z * wi.z / (ao * wi.z + ai * wo.z)
            }
        }
    }

    /// `D(ωm)·G2(ωo, ωi)/(4 zo)`: the BRDF times `cos θi` with F = 1, for the half vector
    /// `ωm` of `ωo` and `ωi`, in a form that has no 1/zo or 1/zi singularity:
    ///
    /// * separable: `D·zi / ((zo + ao)(zi + ai))`;
    /// * height-correlated: `D·zi / (2(ao·zi + ai·zo))`.
    #[inline]
    pub fn eval_cos(&self, wo: Vec3, wi: Vec3, wm: Vec3, masking: Masking) -> f32 {
        if !(above(wo) && above(wi)) {
            return 0.0;
        }
        let (ao, ai) = (self.a(wo), self.a(wi));
        let den = match masking {
            Masking::Separable => (wo.z + ao) * (wi.z + ai),
            Masking::HeightCorrelated => 2.0 * (ao * wi.z + ai * wo.z),
        };
        self.d(wm) * wi.z / den
    }

    /// Samples a microfacet normal for the view direction `wo` (above the horizon) with the
    /// chosen method from two uniform numbers.
    #[inline]
    pub fn sample_wm(&self, wo: Vec3, u: Vec2, method: SpecularSampling) -> Vec3 {
        match method {
            SpecularSampling::Ndf => self.sample_ndf(u),
            SpecularSampling::Vndf => self.sample_vndf_heitz(wo, u),
            SpecularSampling::SphericalCaps => self.sample_vndf_caps(wo, u),
        }
    }

    /// The solid-angle density of [`Ggx::sample_wm`] at `wm`:
    /// NDF `D(ωm)·cos θm`; VNDF (both methods) `G1(ωo)·max(0, ωo·ωm)·D(ωm)/cos θo`.
    #[inline]
    pub fn pdf_wm(&self, wo: Vec3, wm: Vec3, method: SpecularSampling) -> f32 {
        match method {
            SpecularSampling::Ndf => self.d(wm) * wm.z.max(0.0),
            SpecularSampling::Vndf | SpecularSampling::SphericalCaps => {
                if !above(wo) {
                    return 0.0;
                }
                // G1(wo)/zo = 2/(zo + ao): no division by a grazing zo.
                2.0 / (wo.z + self.a(wo)) * wo.dot(wm).max(0.0) * self.d(wm)
            }
        }
    }

    /// The solid-angle density of the reflected direction `ωi = reflect(ωo, ωm)` when `ωm` is
    /// sampled by `method`: `pdf_wm/(4 ωo·ωm)`, with `cos_om = ωo·ωm > 0` given by the caller.
    ///
    /// For VNDF the `ωo·ωm` factors cancel analytically: `D(ωm)·G1(ωo)/(4 cos θo) =
    /// D(ωm)/(2(cos θo + a(ωo)))`, so no rounded dot product can zero it; NDF is
    /// `D(ωm)·cos θm/(4 cos_om)`.
    #[inline]
    pub fn pdf_reflected(&self, wo: Vec3, wm: Vec3, cos_om: f32, method: SpecularSampling) -> f32 {
        if !(above(wo) && cos_om > 0.0) {
            return 0.0;
        }
        match method {
            SpecularSampling::Ndf => self.d(wm) * wm.z.max(0.0) / (4.0 * cos_om),
            SpecularSampling::Vndf | SpecularSampling::SphericalCaps => {
                self.d(wm) / (2.0 * (wo.z + self.a(wo)))
            }
        }
    }

    /// NDF sampling: `tan²θm = α²·u₀/(1 − u₀)`, `φ = 2π·u₁`; anisotropic, the α = 1 normal so
    /// drawn stretched by `(αx, αy)` (the stretch maps `D₁·cos θ` onto `D·cos θ`).
    fn sample_ndf(&self, u: Vec2) -> Vec3 {
        let a2 = if self.is_anisotropic() { 1.0 } else { self.alpha * self.alpha };
        let tan2 = a2 * u.x / (1.0 - u.x);
        let cos_theta = 1.0 / (1.0 + tan2).sqrt();
        let sin_theta = tan2.sqrt() * cos_theta;
        let (s, c) = (TAU * u.y).sin_cos();
        let wm = Vec3::new(sin_theta * c, sin_theta * s, cos_theta);
        if self.is_anisotropic() {
            Vec3::new(self.alpha * wm.x, self.alpha_y * wm.y, wm.z).normalize_or(Vec3::Z)
        } else {
            wm
        }
    }

    /// Heitz 2018, listing 1: stretch ωo to the hemisphere configuration, sample the projected
    /// disk (warped to the visible half), lift to the hemisphere, unstretch.
    fn sample_vndf_heitz(&self, wo: Vec3, u: Vec2) -> Vec3 {
        let (ax, ay) = (self.alpha, self.alpha_y);
        let vh = Vec3::new(ax * wo.x, ay * wo.y, wo.z).normalize_or(Vec3::Z);
        let lensq = vh.x * vh.x + vh.y * vh.y;
        let t1 = if lensq > 0.0 { Vec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt() } else { Vec3::X };
        let t2 = vh.cross(t1);
        let r = u.x.sqrt();
        let (s, c) = (TAU * u.y).sin_cos();
        let p1 = r * c;
        let mut p2 = r * s;
        let h = 0.5 * (1.0 + vh.z);
        p2 = (1.0 - h) * (1.0 - p1 * p1).max(0.0).sqrt() + h * p2;
        let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
        Vec3::new(ax * nh.x, ay * nh.y, nh.z.max(0.0)).normalize_or(Vec3::Z)
    }

    /// Dupuy & Benyoub 2023, listing 3: in the stretched configuration the visible normals are
    /// `c + ωo'`, with c uniform on the spherical cap `z ∈ (−ωo'.z, 1]`.
    fn sample_vndf_caps(&self, wo: Vec3, u: Vec2) -> Vec3 {
        let (ax, ay) = (self.alpha, self.alpha_y);
        let wi_std = Vec3::new(ax * wo.x, ay * wo.y, wo.z).normalize_or(Vec3::Z);
        let (s, c) = (TAU * u.x).sin_cos();
        let z = (1.0 - u.y).mul_add(1.0 + wi_std.z, -wi_std.z);
        let sin_theta = (1.0 - z * z).clamp(0.0, 1.0).sqrt();
        let wm_std = Vec3::new(sin_theta * c, sin_theta * s, z) + wi_std;
        Vec3::new(ax * wm_std.x, ay * wm_std.y, wm_std.z).normalize_or(Vec3::Z)
    }
}

/// Mirror reflection of `wo` about the unit normal `wm`: `2(ωo·ωm)ωm − ωo`.
#[inline]
pub fn reflect(wo: Vec3, wm: Vec3) -> Vec3 {
    2.0 * wo.dot(wm) * wm - wo
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::turquin::gauss_legendre;

    /// ∫ f(ω) dω over the upper hemisphere: product Gauss–Legendre in (v, φ), f64 sums.
    fn hemisphere_integral(f: impl Fn(Vec3) -> f64, n_theta: usize, n_phi: usize) -> f64 {
        // Substitute cos θ = 1 − v², v ∈ [0, 1]: dcosθ = 2v dv, which concentrates nodes at the
        // pole where sharp lobes live.
        let (vs, wv) = gauss_legendre(n_theta);
        let (ps, wp) = gauss_legendre(n_phi);
        let mut sum = 0.0;
        for (v, a) in vs.iter().zip(&wv) {
            let z = 1.0 - v * v;
            let s = (1.0 - z * z).max(0.0).sqrt();
            for (p, b) in ps.iter().zip(&wp) {
                let phi = std::f64::consts::TAU * p;
                let w = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32);
                sum += a * b * 2.0 * v * std::f64::consts::TAU * f(w);
            }
        }
        sum
    }

    #[test]
    fn d_is_normalised_projected_area() {
        // ∫ D(ωm) cos θm dωm = 1 (Walter et al. 2007, eq. 4). Tolerance 1e-3: quadrature of a
        // peaked f32 function with 400 nodes in v = √(1 − cos θ).
        for alpha in [0.02f32, 0.1, 0.3, 0.6, 1.0] {
            let g = Ggx::new(alpha);
            let i = hemisphere_integral(|w| (g.d(w) * w.z) as f64, 400, 8);
            assert!((i - 1.0).abs() < 1e-3, "alpha {alpha}: {i}");
        }
    }

    #[test]
    fn visible_normal_density_is_normalised() {
        // ∫ G1(ωo) max(0, ωo·ωm) D(ωm)/cos θo dωm = 1 (Heitz 2014, eq. 2 normalisation).
        for alpha in [0.1f32, 0.5, 1.0] {
            let g = Ggx::new(alpha);
            for theta in [0.0f32, 0.7, 1.4] {
                let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
                let i = hemisphere_integral(|w| g.pdf_wm(wo, w, SpecularSampling::Vndf) as f64, 400, 256);
                assert!((i - 1.0).abs() < 2e-3, "alpha {alpha} theta {theta}: {i}");
            }
        }
    }

    #[test]
    fn lambda_and_g1_match_the_tangent_forms() {
        // Λ = (−1 + √(1 + α² tan²θ))/2 (Walter et al. 2007); known value α = 1, θ = 45°:
        // Λ = (√2 − 1)/2, G1 = 2/(1 + √2).
        let g = Ggx::new(1.0);
        let w = Vec3::new(1.0, 0.0, 1.0).normalize();
        assert!((g.lambda(w) - (2f32.sqrt() - 1.0) / 2.0).abs() < 1e-6);
        assert!((g.g1(w) - 2.0 / (1.0 + 2f32.sqrt())).abs() < 1e-6);
        for alpha in [1e-4f32, 0.05, 0.5, 1.0] {
            let g = Ggx::new(alpha);
            for theta in [0.0f32, 0.3, 1.0, 1.5, 1.57] {
                let w = Vec3::new(theta.sin(), 0.0, theta.cos());
                let t = theta.tan() as f64;
                let lambda = (-1.0 + (1.0 + (alpha as f64).powi(2) * t * t).sqrt()) / 2.0;
                // Relative 1e-5: f32 evaluation of the same quantity by a different formula.
                assert!(((g.lambda(w) as f64 - lambda) / lambda.max(1e-3)).abs() < 1e-4, "{alpha} {theta}");
                assert!((g.g1(w) as f64 - 1.0 / (1.0 + lambda)).abs() < 1e-5, "{alpha} {theta}");
            }
            // At the horizon G1 is 0, not NaN.
            assert_eq!(g.g1(Vec3::X), 0.0);
        }
    }

    #[test]
    fn height_correlated_masks_less_than_separable() {
        // 1/(1 + Λo + Λi) ≥ 1/((1 + Λo)(1 + Λi)), equality at normal incidence on one side.
        let g = Ggx::new(0.5);
        for (a, b) in [(0.1f32, 0.2f32), (1.0, 1.2), (0.0, 1.5)] {
            let wo = Vec3::new(a.sin(), 0.0, a.cos());
            let wi = Vec3::new(-b.sin(), 0.0, b.cos());
            let hc = g.g2(wo, wi, Masking::HeightCorrelated);
            let sep = g.g2(wo, wi, Masking::Separable);
            assert!(hc >= sep - 1e-7 && hc <= 1.0, "{a} {b}: {hc} {sep}");
        }
    }

    /// Anisotropic distributions of the tests: (αx, αy).
    const ANISOTROPIC: [(f32, f32); 4] = [(0.5, 0.1), (0.05, 0.3), (1.0, 0.02), (0.3, 0.3001)];

    #[test]
    fn anisotropic_d_and_visible_normals_are_normalised() {
        // ∫ D cos θm = 1 and ∫ D_wo = 1 as above; 2048 φ nodes for the ridge of (1, 0.02), whose
        // width in φ is ~0.02/sin θ. Tolerance 2e-3: that quadrature's error.
        for (ax, ay) in ANISOTROPIC {
            let g = Ggx::anisotropic(ax, ay);
            let i = hemisphere_integral(|w| (g.d(w) * w.z) as f64, 400, 2048);
            assert!((i - 1.0).abs() < 2e-3, "({ax}, {ay}): {i}");
            for (theta, phi) in [(0.0f32, 0.0f32), (0.7, 0.4), (1.4, 2.0)] {
                let wo = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                let i = hemisphere_integral(|w| g.pdf_wm(wo, w, SpecularSampling::Vndf) as f64, 400, 2048);
                assert!((i - 1.0).abs() < 2e-3, "({ax}, {ay}) wo {wo}: {i}");
            }
        }
    }

    #[test]
    fn anisotropic_lambda_is_the_isotropic_one_of_the_projected_alpha() {
        // Heitz 2014 §5.3: Λ(ω) of (αx, αy) is the isotropic Λ of α(φ) = √(αx²cos²φ + αy²sin²φ).
        // Relative 1e-5: two f32 evaluations of one quantity.
        for (ax, ay) in ANISOTROPIC {
            let g = Ggx::anisotropic(ax, ay);
            for (theta, phi) in [(0.3f32, 0.0f32), (1.0, 0.8), (1.5, 1.5707964), (1.2, 3.0)] {
                let w = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                let (c, s) = (phi.cos(), phi.sin());
                let iso = Ggx::new((ax * ax * c * c + ay * ay * s * s).sqrt());
                assert!((g.lambda(w) - iso.lambda(w)).abs() <= 1e-5 * iso.lambda(w).max(1e-3), "{w}");
            }
        }
        // Equal αs are the isotropic distribution, bit for bit.
        let (a, b) = (Ggx::anisotropic(0.3, 0.3), Ggx::new(0.3));
        let w = Vec3::new(0.3, -0.4, 0.866).normalize();
        assert_eq!((a.d(w), a.lambda(w), a.is_anisotropic()), (b.d(w), b.lambda(w), false));
    }

    #[test]
    fn anisotropic_samplers_follow_their_density() {
        // Each sampler's normals, binned on a 24 × 24 grid in (cos θm, φ), against its pdf_wm
        // integrated over each bin, 100 000 samples; cells of expected count < 5 pooled into one.
        // Rejected above dof + 4√(2·dof) (the normal approximation's 4σ: p ≈ 3e-5 under the
        // hypothesis, for each of the 6 cases).
        use crate::turquin::gauss_legendre;
        let (nb, n) = (24usize, 100_000usize);
        for (ax, ay) in [(0.5f32, 0.1f32), (0.08, 0.4)] {
            let g = Ggx::anisotropic(ax, ay);
            let wo = Vec3::new(0.5, 0.3, 0.81).normalize();
            for method in [SpecularSampling::Ndf, SpecularSampling::Vndf, SpecularSampling::SphericalCaps] {
                let mut observed = vec![0f64; nb * nb];
                let mut state = 0x9E37_79B9_7F4A_7C15u64;
                let mut next = || {
                    state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                    ((state >> 40) as f32) / (1u64 << 24) as f32
                };
                for _ in 0..n {
                    let wm = g.sample_wm(wo, Vec2::new(next(), next()), method);
                    let (z, phi) = (wm.z.clamp(0.0, 1.0), wm.y.atan2(wm.x).rem_euclid(TAU));
                    let (i, j) = (
                        ((z * nb as f32) as usize).min(nb - 1),
                        ((phi / TAU * nb as f32) as usize).min(nb - 1),
                    );
                    observed[i * nb + j] += 1.0;
                }
                let (xs, ws) = gauss_legendre(8);
                let mut chi2 = 0.0;
                let (mut pooled_o, mut pooled_e, mut cells) = (0.0, 0.0, 0usize);
                for i in 0..nb {
                    for j in 0..nb {
                        let mut e = 0.0;
                        for (x, a) in xs.iter().zip(&ws) {
                            for (y, b) in xs.iter().zip(&ws) {
                                let z = (i as f64 + x) / nb as f64;
                                let phi = (j as f64 + y) / nb as f64 * std::f64::consts::TAU;
                                let s = (1.0 - z * z).max(0.0).sqrt();
                                let w = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32);
                                e += a * b * g.pdf_wm(wo, w, method) as f64;
                            }
                        }
                        e *= n as f64 * std::f64::consts::TAU / (nb * nb) as f64;
                        let o = observed[i * nb + j];
                        if e < 5.0 {
                            pooled_o += o;
                            pooled_e += e;
                        } else {
                            chi2 += (o - e) * (o - e) / e;
                            cells += 1;
                        }
                    }
                }
                if pooled_e > 0.0 {
                    chi2 += (pooled_o - pooled_e) * (pooled_o - pooled_e) / pooled_e.max(1.0);
                    cells += 1;
                }
                let dof = (cells - 1) as f64;
                let limit = dof + 4.0 * (2.0 * dof).sqrt();
                assert!(chi2 < limit, "({ax}, {ay}) {method:?}: chi-square {chi2} over {dof} dof");
            }
        }
    }

    #[test]
    fn alpha_is_clamped() {
        assert_eq!(Ggx::new(0.0).alpha(), ALPHA_MIN);
        assert_eq!(Ggx::new(-1.0).alpha(), ALPHA_MIN);
        assert_eq!(Ggx::new(f32::NAN).alpha(), 1.0);
        assert_eq!(Ggx::new(7.0).alpha(), 1.0);
    }
}
