//! KHR_materials_sheen: the Charlie sheen lobe (Estevez & Kulla 2017) with the visibility term
//! the extension defines, and its directional albedo `E(μ)` that scales the material beneath.
//!
//! ```text
//! f·cos θi = sheenColor · D(ωh) · V(ωo, ωi) · cos θi
//! D        = (2 + 1/α) · sin²θh^(1/(2α)) / (2π),           α = max(sheenRoughness², 1e-4)
//! V        = 1 / ((1 + Λ(cos θo) + Λ(cos θi)) · 4 cos θo cos θi)
//! Λ(c)     = exp(l(c)) for c < ½, else exp(2 l(½) − l(1 − c))   (the extension's fit l(x))
//! ```
//!
//! The layer above the base scales the base by `min(1 − max(sheenColor)·E(μo),
//! 1 − max(sheenColor)·E(μi))`, `E` the directional albedo of `D·V` (sheen colour 1): tabulated
//! over (μ, sheenRoughness) by [`generate_table`] (the extension leaves its table to the
//! renderer) as `ln E`, looked up by [`albedo`]: at low roughness `E` falls exponentially
//! away from grazing, which bilinear interpolation of `E` itself missed by up to 1e-2.
//!
//! Sampled uniformly over the hemisphere: the lobe spans the hemisphere at every roughness
//! and peaks at grazing angles, where a cosine-weighted sampler puts few samples.

use crate::{Bsdf, Lobe, Rgb, Sample, above};
use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, PI};

pub use crate::tables::SHEEN_LN_E;

/// The smallest α = sheenRoughness² (it appears as 1/α).
pub const SHEEN_ALPHA_MIN: f32 = 1e-4;

/// The sheen table's size along μ (columns) and sheen roughness (rows).
pub const SHEEN_TABLE_SIZE: usize = 64;

/// Gauss–Legendre order per axis of the quadrature that builds the table.
pub const SHEEN_QUADRATURE_ORDER: usize = 96;

/// α of a sheen roughness (perceptual, clamped to `[0, 1]`, NaN → 0).
#[inline]
pub fn alpha(roughness: f32) -> f32 {
    let r = if roughness.is_nan() { 0.0 } else { roughness.clamp(0.0, 1.0) };
    (r * r).max(SHEEN_ALPHA_MIN)
}

/// The Charlie distribution `D(cos θh)` for α = sheenRoughness².
#[inline]
pub fn d(cos_h: f32, alpha: f32) -> f32 {
    let inv = 1.0 / alpha;
    let sin2 = (1.0 - cos_h * cos_h).max(0.0);
    (2.0 + inv) * sin2.powf(0.5 * inv) * (0.5 * FRAC_1_PI)
}

/// The extension's fit `l(x)` of the sheen's Λ, its coefficients blended by `(1 − α)²`.
#[inline]
fn l(x: f32, alpha: f32) -> f32 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let mix = |a0: f32, a1: f32| a0 * (1.0 - t) + a1 * t;
    let a = mix(21.5473, 25.3245);
    let b = mix(3.82987, 3.32435);
    let c = mix(0.19823, 0.16801);
    let dd = mix(-1.97760, -1.27393);
    let e = mix(-4.32054, -4.85967);
    a / (1.0 + b * x.max(0.0).powf(c)) + dd * x + e
}

/// The sheen's `Λ(cos θ)`.
#[inline]
pub fn lambda(cos: f32, alpha: f32) -> f32 {
    let c = cos.abs();
    if c < 0.5 { l(c, alpha).exp() } else { (2.0 * l(0.5, alpha) - l(1.0 - c, alpha)).exp() }
}

/// `D·V·cos θi` for unit directions above the horizon, in a form without the `1/(cos θi)`
/// of V: `D / ((1 + Λo + Λi)·4 cos θo)`.
#[inline]
fn dv_cos(wo: Vec3, wi: Vec3, alpha: f32) -> f32 {
    let h = (wo + wi).normalize_or(Vec3::Z);
    let den = (1.0 + lambda(wo.z, alpha) + lambda(wi.z, alpha)) * 4.0 * wo.z;
    let v = d(h.z, alpha) / den;
    if v.is_finite() { v } else { 0.0 }
}

/// The directional albedo `E(μ) = ∫ D·V·cos θi dωi` of the sheen lobe (colour 1) by
/// deterministic quadrature over half vectors: `D(ωh) cos θh dωh` is a probability measure
/// (sin θh = u^(1/(1/α + 2)) maps it to the unit square), and `dωi = 4|ωo·ωh| dωh`, so
/// `E = ∫∫ V·cos θi·4|ωo·ωh| / cos θh du` over reflections that stay above the horizon.
/// Product Gauss–Legendre of `order` points per axis, accumulated in `f64`; φ over `[0, π]`
/// (the integrand is even in φ).
pub fn directional_albedo(mu: f32, roughness: f32, order: usize) -> f64 {
    let a = alpha(roughness) as f64;
    let mu = (mu as f64).clamp(1e-4, 1.0);
    let wo = [(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu];
    let (nodes, weights) = crate::turquin::gauss_legendre(order);
    let k = 1.0 / a + 2.0;
    let lam = |c: f64| lambda(c as f32, a as f32) as f64;
    let lo = lam(mu);
    let mut sum = 0.0;
    for (u1, w1) in nodes.iter().zip(&weights) {
        let sin_h = u1.powf(1.0 / k);
        let cos_h = (1.0 - sin_h * sin_h).max(0.0).sqrt();
        if cos_h <= 0.0 {
            continue;
        }
        for (u2, w2) in nodes.iter().zip(&weights) {
            let phi = std::f64::consts::PI * u2;
            let h = [sin_h * phi.cos(), sin_h * phi.sin(), cos_h];
            let oh = wo[0] * h[0] + wo[2] * h[2];
            if oh <= 0.0 {
                continue;
            }
            let mi = 2.0 * oh * h[2] - wo[2];
            if mi <= 0.0 {
                continue;
            }
            // V·cos θi = 1/((1 + Λo + Λi)·4 μo).
            let v_cos = 1.0 / ((1.0 + lo + lam(mi)) * 4.0 * mu);
            sum += w1 * w2 * v_cos * 4.0 * oh / cos_h;
        }
    }
    sum
}

/// The table's μ for column `i`: `μ = (i / 63)²` (dense near grazing).
#[inline]
pub fn table_mu(i: usize) -> f32 {
    let x = i as f32 / (SHEEN_TABLE_SIZE - 1) as f32;
    x * x
}

/// The table's sheen roughness for row `j`: `(j / 63)²` (dense at low roughness, where `E`
/// changes fastest).
#[inline]
pub fn table_roughness(j: usize) -> f32 {
    let y = j as f32 / (SHEEN_TABLE_SIZE - 1) as f32;
    y * y
}

/// The smallest `E` the table stores (its logarithm): a lobe that reflects less is black.
pub const SHEEN_E_MIN: f64 = 1e-30;

/// Regenerates [`SHEEN_LN_E`]: `ln E(table_mu(i), table_roughness(j))` at `[j][i]` (`E` at
/// least [`SHEEN_E_MIN`]).
pub fn generate_table() -> [[f32; SHEEN_TABLE_SIZE]; SHEEN_TABLE_SIZE] {
    let mut t = [[0.0f32; SHEEN_TABLE_SIZE]; SHEEN_TABLE_SIZE];
    for (j, row) in t.iter_mut().enumerate() {
        for (i, e) in row.iter_mut().enumerate() {
            let a = directional_albedo(table_mu(i), table_roughness(j), SHEEN_QUADRATURE_ORDER);
            *e = a.max(SHEEN_E_MIN).ln() as f32;
        }
    }
    t
}

/// The sheen albedo `E(μ)` at a sheen roughness (both clamped to `[0, 1]`): `exp` of the
/// bilinear interpolation of [`SHEEN_LN_E`] over (√μ, √roughness).
#[inline]
pub fn albedo(mu: f32, roughness: f32) -> f32 {
    let n = (SHEEN_TABLE_SIZE - 1) as f32;
    let x = mu.clamp(0.0, 1.0).sqrt() * n;
    let y = if roughness.is_nan() { 0.0 } else { roughness.clamp(0.0, 1.0).sqrt() } * n;
    let (i, j) = ((x as usize).min(SHEEN_TABLE_SIZE - 2), (y as usize).min(SHEEN_TABLE_SIZE - 2));
    let (fx, fy) = (x - i as f32, y - j as f32);
    let t = &SHEEN_LN_E;
    let top = t[j][i] * (1.0 - fx) + t[j][i + 1] * fx;
    let bottom = t[j + 1][i] * (1.0 - fx) + t[j + 1][i + 1] * fx;
    (top * (1.0 - fy) + bottom * fy).exp()
}

/// The sheen lobe: colour and roughness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sheen {
    /// `sheenColorFactor × sheenColorTexture`, clamped to `[0, 1]`.
    pub color: Rgb,
    /// `sheenRoughnessFactor × sheenRoughnessTexture.a`, clamped to `[0, 1]`.
    pub roughness: f32,
    alpha: f32,
}

impl Sheen {
    /// A sheen lobe (colour clamped to `[0, 1]`, roughness to `[0, 1]`, NaN → 0).
    pub fn new(color: Rgb, roughness: f32) -> Self {
        let roughness = if roughness.is_nan() { 0.0 } else { roughness.clamp(0.0, 1.0) };
        Self { color: crate::clamp_rgb(color, 1.0), roughness, alpha: alpha(roughness) }
    }

    /// `max(sheenColor)`: what scales the layer beneath by `1 − max·E`.
    #[inline]
    pub fn max_color(&self) -> f32 {
        self.color.max_element()
    }

    /// The scale of the layer beneath: `min(1 − max·E(μo), 1 − max·E(μi))`, not below 0 (the
    /// extension's fit of Λ gives `E > 1` at grazing angles for roughness ≤ 0.25, where the
    /// literal scale would be negative).
    #[inline]
    pub fn base_scale(&self, mu_o: f32, mu_i: f32) -> f32 {
        let m = self.max_color();
        let e = albedo(mu_o.abs(), self.roughness).max(albedo(mu_i.abs(), self.roughness));
        (1.0 - m * e).max(0.0)
    }

    /// The sheen's albedo estimate at μo (luminance of the colour times `E(μo)`), for lobe
    /// selection.
    #[inline]
    pub fn albedo_estimate(&self, mu_o: f32) -> f32 {
        crate::luminance(self.color) * albedo(mu_o, self.roughness)
    }
}

impl Bsdf for Sheen {
    /// `sheenColor·D·V·cos θi`; 0 unless both directions are above the horizon.
    fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if !(above(wo) && above(wi)) {
            return Rgb::ZERO;
        }
        self.color * dv_cos(wo, wi, self.alpha)
    }

    /// A uniform hemisphere sample (`pdf = 1/(2π)`); `uc` is unused.
    fn sample(&self, wo: Vec3, _uc: f32, u: Vec2) -> Option<Sample> {
        if !above(wo) {
            return None;
        }
        let z = 1.0 - u.x;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        let wi = Vec3::new(r * phi.cos(), r * phi.sin(), z);
        if !above(wi) {
            return None;
        }
        let pdf = 0.5 * FRAC_1_PI;
        Some(Sample { wi, weight: self.eval(wo, wi) / pdf, pdf, lobe: Lobe::Sheen })
    }

    /// `1/(2π)` above the horizon (for `wo` above it too), else 0.
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if !(above(wo) && above(wi)) {
            return 0.0;
        }
        0.5 * FRAC_1_PI
    }
}
