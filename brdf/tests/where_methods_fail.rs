//! Where the three ways of sampling the GGX lobe fail, measured rather than asserted from
//! folklore: NDF sampling (the thesis §3.2), VNDF (Heitz 2018) and VNDF by spherical caps
//! (Dupuy & Benyoub 2023), on a white lobe (F = 1, height-correlated G2, no compensation).
//!
//! For θo ∈ {0, 30, 60, 80, 85, 89, 89.9}° and α ∈ {0.02, 0.1, 0.3, 1}, 2¹⁶ Owen-scrambled Sobol
//! points per configuration (the same points for every method), it measures:
//!
//! * the fraction of samples `sample` rejects (`None`), split for NDF into back-facing
//!   microfacets (ωo·ωm ≤ 0: the NDF proposes normals the viewer cannot see) and reflections
//!   below the horizon (the only way VNDF can fail);
//! * the variance and the maximum of the throughput weight (None counted as 0), i.e. the
//!   per-sample variance of the albedo estimator and its firefly risk.
//!
//! Asserted (what must hold, with why):
//!
//! 1. VNDF and caps weights are ≤ 1 (to 4 ulp): with F = 1 the weight is `G2/G1(ωo)`, and both
//!    G2 forms are ≤ G1(ωo) (`G1(ωo)·G1(ωi)` trivially; `1/(1+Λo+Λi) ≤ 1/(1+Λo)`).
//! 2. VNDF/caps rejection ≤ `1 − E(μo, α)`: E = 𝔼[G2/G1 · 1{accepted}] ≤ P(accepted), since the
//!    weight is ≤ 1. So VNDF can only lose samples where single scattering loses energy — none
//!    at normal incidence on a smooth surface, and at most 1 − E for rough grazing views (E by
//!    quadrature, height-correlated, the larger of the two forms; rejection does not depend
//!    on the masking form).
//! 3. VNDF/caps rejection ≤ NDF rejection and VNDF/caps weight variance ≤ NDF weight variance,
//!    up to sampling error (4σ of each estimate): at θo = 0 the two densities and weights are
//!    identical (`G1(z) = 1`), so only sampling noise separates them there.
//! 4. All three estimators agree with the quadrature albedo (4σ + 1e-3 for the quadrature).
//!
//! The table is printed and written to `target/test-output/brdf/where_methods_fail.md`.

use crate::common;
use common::write_output;
use furnace_brdf::ggx::reflect;
use furnace_brdf::turquin::directional_albedo;
use furnace_brdf::{Bsdf, GgxSpecular, Masking, Rgb, SpecularOptions, SpecularSampling};
use furnace_sampling::{OwenSobol, Sampler};
use glam::{Vec2, Vec3};
use std::fmt::Write as _;

const N: u32 = 1 << 16;
const THETAS_DEG: [f64; 7] = [0.0, 30.0, 60.0, 80.0, 85.0, 89.0, 89.9];
const ALPHAS: [f32; 4] = [0.02, 0.1, 0.3, 1.0];
const METHODS: [SpecularSampling; 3] =
    [SpecularSampling::Ndf, SpecularSampling::Vndf, SpecularSampling::SphericalCaps];

/// What one method did on one configuration.
#[derive(Debug, Default, Clone, Copy)]
struct Stats {
    /// Fraction of `None`.
    rejected: f64,
    /// Of which: back-facing microfacet (`ωo·ωm ≤ 0`).
    backfacing: f64,
    /// Of which: reflected below the horizon.
    below: f64,
    /// Mean weight (the albedo estimate), its variance, the variance's standard error, the max.
    mean: f64,
    var: f64,
    var_se: f64,
    max: f64,
}

impl Stats {
    /// Standard error of the mean (i.i.d. formula: conservative for scrambled Sobol).
    fn mean_se(&self) -> f64 {
        (self.var / N as f64).sqrt()
    }
    /// Binomial standard error of the rejection fraction.
    fn rejected_se(&self) -> f64 {
        (self.rejected * (1.0 - self.rejected) / N as f64).sqrt()
    }
}

fn measure(alpha: f32, theta_deg: f64, method: SpecularSampling, scramble: u32) -> Stats {
    let lobe = GgxSpecular::new(
        alpha,
        Rgb::ONE,
        SpecularOptions { masking: Masking::HeightCorrelated, sampling: method, compensation: false },
    );
    let t = theta_deg.to_radians();
    let wo = Vec3::new(t.sin() as f32, 0.0, t.cos() as f32);
    let sampler = OwenSobol::new(1234);
    let mut s = Stats::default();
    let mut weights = Vec::with_capacity(N as usize);
    for i in 0..N {
        let [u0, u1] = sampler.value_2d(scramble, i, 0);
        let u = Vec2::new(u0, u1);
        let w = match lobe.sample(wo, 0.5, u) {
            Some(smp) => smp.weight.x as f64,
            None => {
                s.rejected += 1.0;
                let wm = lobe.ggx.sample_wm(wo, u, method);
                if !(wo.dot(wm) > 0.0) {
                    s.backfacing += 1.0;
                } else if !(reflect(wo, wm).z > 0.0) {
                    s.below += 1.0;
                }
                0.0
            }
        };
        weights.push(w);
    }
    let n = N as f64;
    s.rejected /= n;
    s.backfacing /= n;
    s.below /= n;
    s.mean = weights.iter().sum::<f64>() / n;
    s.var = weights.iter().map(|w| (w - s.mean).powi(2)).sum::<f64>() / (n - 1.0);
    let m4 = weights.iter().map(|w| (w - s.mean).powi(4)).sum::<f64>() / n;
    s.var_se = ((m4 - s.var * s.var).max(0.0) / n).sqrt();
    s.max = weights.iter().fold(0.0, |a, &b| a.max(b));
    s
}

#[test]
fn rejection_and_weight_variance_per_method() {
    let mut rows = vec![];
    let mut failures = vec![];
    // Summary for the low-α, grazing corner (the firefly risk).
    let mut firefly = String::new();
    for (ai, &alpha) in ALPHAS.iter().enumerate() {
        for (ti, &theta) in THETAS_DEG.iter().enumerate() {
            let scramble = (ai * THETAS_DEG.len() + ti) as u32;
            let [ndf, vndf, caps] = METHODS.map(|m| measure(alpha, theta, m, scramble));
            let mu = theta.to_radians().cos() as f32;
            let e = directional_albedo(mu, alpha, Masking::HeightCorrelated, 96);
            rows.push(format!(
                "| {alpha} | {theta} | {e:.4} | {:.4} ({:.4} back, {:.4} below) | {:.4} | {:.4} | {:.4} / {:.4} / {:.4} | {:.3e} | {:.3e} | {:.3e} | {:.1} | {:.3} | {:.3} | {:.2} |",
                ndf.rejected,
                ndf.backfacing,
                ndf.below,
                vndf.rejected,
                caps.rejected,
                ndf.mean,
                vndf.mean,
                caps.mean,
                ndf.var,
                vndf.var,
                caps.var,
                ndf.max,
                vndf.max,
                caps.max,
                if vndf.var > 0.0 { ndf.var / vndf.var } else { f64::NAN },
            ));
            if alpha <= 0.1 && theta >= 85.0 {
                let _ = writeln!(
                    firefly,
                    "α = {alpha}, θo = {theta}°: max weight NDF {:.1} vs VNDF {:.3}, variance NDF {:.2e} vs VNDF {:.2e}",
                    ndf.max, vndf.max, ndf.var, vndf.var
                );
            }
            let name = |m: &str| format!("α = {alpha}, θo = {theta}°, {m}");
            // Every NDF rejection is classified (back-facing or below the horizon), and VNDF
            // never proposes a back-facing normal.
            if (ndf.backfacing + ndf.below - ndf.rejected).abs() > 0.5 / N as f64 {
                failures.push(format!("{}: unclassified rejections", name("NDF")));
            }
            for (m, v) in [("VNDF", &vndf), ("caps", &caps)] {
                if v.backfacing > 0.0 {
                    failures.push(format!("{}: {} back-facing microfacets", name(m), v.backfacing));
                }
                // 1. weights ≤ 1 (4 ulp of f32 rounding in G2/G1).
                if v.max > 1.0 + 4.0 * f32::EPSILON as f64 {
                    failures.push(format!("{}: weight {} > 1 with F = 1", name(m), v.max));
                }
                // 2. rejection ≤ 1 − E, up to 4σ (binomial) and the quadrature's 1e-3.
                if v.rejected > (1.0 - e) + 4.0 * v.rejected_se() + 1e-3 {
                    failures.push(format!("{}: rejects {:.4} > 1 − E = {:.4}", name(m), v.rejected, 1.0 - e));
                }
                // 3. no worse than NDF, up to 4σ of both estimates.
                if v.rejected > ndf.rejected + 4.0 * (v.rejected_se() + ndf.rejected_se()) {
                    failures.push(format!(
                        "{}: rejects {:.4} > NDF {:.4}",
                        name(m),
                        v.rejected,
                        ndf.rejected
                    ));
                }
                if v.var > ndf.var + 4.0 * (v.var_se + ndf.var_se) {
                    failures.push(format!(
                        "{}: weight variance {:.3e} > NDF {:.3e}",
                        name(m),
                        v.var,
                        ndf.var
                    ));
                }
            }
            // 4. unbiased: each mean within 4σ of the quadrature albedo (+1e-3 quadrature).
            for (m, v) in [("NDF", &ndf), ("VNDF", &vndf), ("caps", &caps)] {
                if (v.mean - e).abs() > 4.0 * v.mean_se() + 1e-3 {
                    failures.push(format!(
                        "{}: mean weight {:.5} ± {:.1e} vs E = {e:.5}",
                        name(m),
                        v.mean,
                        v.mean_se()
                    ));
                }
            }
        }
    }
    let text = format!(
        "# Where GGX sampling methods fail\n\n\
         White GGX (F = 1), height-correlated G2, no compensation; 2^16 Owen-Sobol points per row, \
         the same for each method. E = quadrature albedo. Weight statistics count None as 0.\n\n\
         | α | θo (°) | E | NDF rejected (back-facing, below horizon) | VNDF rejected | caps rejected | mean weight NDF / VNDF / caps | var NDF | var VNDF | var caps | max NDF | max VNDF | max caps | var NDF / var VNDF |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n{}\n\n## Firefly risk (α ≤ 0.1, θo ≥ 85°)\n\n{firefly}",
        rows.join("\n")
    );
    println!("{text}");
    let path = write_output("where_methods_fail.md", &text);
    assert!(failures.is_empty(), "{failures:#?}\n(table in {})\n{text}", path.display());
}
