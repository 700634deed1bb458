//! Consistency of `eval`, `sample` and `pdf` with each other, for every lobe, sampling
//! method, masking form and compensation switch of `furnace-brdf`, at roughnesses down to
//! `ALPHA_MIN` and view angles down to grazing:
//!
//! * `sample` returns what it promises: `weight = eval(wo, wi)/pdf` and `pdf = pdf(wo, wi)`,
//!   to relative tolerances derived from `f32` rounding (the error model is at [`U`]);
//! * every sample is valid: `wi` finite, unit, strictly above the horizon; weight finite and
//!   nonnegative; pdf finite and positive — also for uniform numbers at the edges of `[0, 1)`
//!   and views within 0.001° of the horizon; views at or below the horizon give `None`;
//! * `pdf` integrates (by the chi-square harness's adaptive quadrature over the sphere) to the
//!   probability that `sample` returns a direction, measured by a 10⁶-sample run;
//! * `eval` without compensation is reciprocal: `eval(wo, wi)/cos θi = eval(wi, wo)/cos θo`.
//!
//! The chi-square tests (`tests/chi2.rs`) check that `sample` draws from `pdf`; these tests
//! check the bookkeeping around it, which a renderer relies on and the histogram cannot see
//! (a weight off by a constant factor, a pdf that disagrees with the sample's own).
//!
//! The configurations are the table of lobes [`LOBES`] (`furnace_tests::lobes`), which the
//! chi-square, white-furnace and GPU parity tests iterate too: each row's `consistency` gives the
//! configurations of the sample checks and their first seed, the groups of `∫ pdf` checks and
//! the configurations of the reciprocity check, so a new lobe adds a row there. (Every GGX lobe
//! and glTF material is checked for every sampling method, masking form and compensation switch,
//! at α from `ALPHA_MIN` to 1.)
//!
//! Uniform numbers come from fixed-seed [`RandomStream`]s, so every run checks the same
//! inputs. Run with `--nocapture` to see, per case, the worst error against its tolerance.
//!
//! [`pdf_is_positive_for_sampled_directions_at_grazing_views`] is the regression test of a bug
//! this file found: within about 0.01° of the horizon `pdf(wo, wi)` was 0 for some directions
//! that `sample` had returned with a positive pdf.

use crate::common;
use common::Worst;
use furnace_brdf::{Bsdf, MetallicRoughness, MetallicRoughnessParams, SpecularOptions};
use furnace_sampling::RandomStream;
use furnace_tests::chi2::ChiSquareTest;
use furnace_tests::lobes::{Config, IntegralConfig, LOBES};
use glam::{Vec2, Vec3};

/// View angles (degrees from the normal) of the strict checks, down to 0.1° above the
/// horizon.
const THETAS: [f32; 6] = [0.0, 30.0, 60.0, 80.0, 89.0, 89.9];

/// Views closer to the horizon than [`THETAS`] (0.01°, 0.001°, and `cos θ = 10⁻⁶`), where the
/// `f32` half vector of a back-scattering reflection is too short to be accurate: samples
/// must still be valid, but see [`pdf_is_positive_for_sampled_directions_at_grazing_views`].
const GRAZING_THETAS: [f32; 3] = [89.99, 89.999, 89.999_94];

/// Samples per (lobe, view direction), plus [`EDGE_UNIFORMS`].
const SAMPLES_PER_VIEW: u32 = 2_000;

/// Random view directions per lobe, in addition to [`THETAS`]: `cos θ` uniform in
/// `[cos 89.9°, 1]`, azimuth uniform.
const RANDOM_VIEWS: u32 = 16;

/// The largest `f32` below 1.
const ONE_MINUS: f32 = 1.0 - f32::EPSILON / 2.0;

/// Uniform numbers at the edges of `[0, 1)`.
const EDGE_UNIFORMS: [f32; 4] = [0.0, 0.5, 0.999, ONE_MINUS];

/// The view direction `theta_deg` from the normal at azimuth `phi`; exactly `+z` at 0°.
fn view(theta_deg: f32, phi: f32) -> Vec3 {
    if theta_deg == 0.0 {
        return Vec3::Z;
    }
    let (st, ct) = theta_deg.to_radians().sin_cos();
    let (sp, cp) = phi.sin_cos();
    Vec3::new(st * cp, st * sp, ct)
}

/// Every configuration of the sample checks of every row of [`LOBES`], in table order.
fn all_cases() -> Vec<Config> {
    LOBES.iter().flat_map(|row| (row.consistency.configs)()).collect()
}

/// `|a − b| / max(|a|, |b|)` (0 when both are 0).
fn relative_error(a: f32, b: f32) -> f32 {
    let scale = a.abs().max(b.abs());
    if scale == 0.0 { 0.0 } else { (a - b).abs() / scale }
}

/// The error model behind the tolerances of `sample` against `eval`/`pdf`.
///
/// `sample` works with the normal ωm it sampled; `eval` and `pdf` recompute the half vector
/// ωm' = normalize(ωo + ωi) from the returned `f32` direction ωi. Write `c = ωo·ωm` (the cosine
/// of the angle between the view and the microfacet; `|ωo + ωi| = 2c`) and `u = 2⁻²⁴`:
///
/// * ωi = 2(ωo·ωm)ωm − ωo carries a few `u` of rounding, so ωm' is off by an angle of about
///   `u/c` (the short sum ωo + ωi amplifies it).
/// * GGX's D has a relative slope of at most `2/α` in the angle (at `tan θm = α`), so D(ωm') is
///   off by `(2/α)·u/c` relative: this is why `pdf` and `sample`'s pdf differ most for the
///   sharpest lobes. (It cancels from `eval/pdf`, which both use ωm'.)
/// * `c' = ωo·ωm'` is a dot product of nearly perpendicular vectors when c is small: off by
///   about `u/c` absolute, `u/c²` relative. The NDF pdf `D cos θm/(4c)` and the NDF weight
///   `F·G2·c/(cos θo cos θm)` are proportional to `1/c` and `c`; the VNDF forms cancel c, but
///   Schlick's F (slope 5 in c) moves by `5u/c`.
///
/// Hence the relative error bound `u·((2/α)/c + 5/c + 1/c²)` for `pdf` and
/// `u·(5/c + 1/c²)` for the weight; the tolerances are [`SLACK`] times these plus a floor for
/// the plain rounding of the smooth factors ([`PDF_FLOOR`], [`WEIGHT_FLOOR`]). For Lambert
/// (no half vector) and for the material's weight (computed as `eval/pdf` by `sample` itself)
/// only the floor applies in practice.
const U: f32 = f32::EPSILON / 2.0;

/// Safety factor on the error bound: the constants hidden in "a few roundings". Measured
/// worst over all cases and views of the strict checks: 0.11 of the pdf tolerance and 0.085
/// of the weight tolerance, i.e. about 0.45 times the bound itself; at the views of
/// [`GRAZING_THETAS`] (0.01° and closer, not checked strictly) up to 1.1 times the bound
/// (see `--nocapture`).
const SLACK: f32 = 4.0;

/// Relative rounding of the smooth factors of the pdf (G1, cosines, the mixture weights): a
/// few dozen roundings.
const PDF_FLOOR: f32 = 1e-5;

/// Relative rounding of the weight's smooth factors (F, G2/G1, the compensation table).
const WEIGHT_FLOOR: f32 = 1e-5;

/// Relative tolerance of `sample`'s pdf against `pdf(wo, wi)`; `alpha` is the lobe's GGX α
/// (`None`: Lambert) and `c = ωo·ωm` (see [`U`]).
fn pdf_tolerance(alpha: Option<f32>, c: f32) -> f32 {
    match alpha {
        None => PDF_FLOOR,
        Some(alpha) => PDF_FLOOR + SLACK * U * ((2.0 / alpha + 5.0) / c + 1.0 / (c * c)),
    }
}

/// Relative tolerance of `sample`'s weight against `eval(wo, wi)/pdf(wo, wi)`.
fn weight_tolerance(alpha: Option<f32>, c: f32) -> f32 {
    match alpha {
        None => WEIGHT_FLOOR,
        Some(_) => WEIGHT_FLOOR + SLACK * U * (5.0 / c + 1.0 / (c * c)),
    }
}

/// The largest deviation `|‖ωi‖ − 1|` accepted for a sampled direction: 32 roundings
/// (the reflection formula and the normalisations before it leave a few).
const UNIT_TOLERANCE: f32 = 32.0 * U;

/// Which checks [`check_samples`] applies.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Checks {
    /// Validity, and weight and pdf against `eval` and `pdf`.
    All,
    /// Validity only.
    Validity,
}

/// The views of the strict checks: [`THETAS`] at azimuth 1 rad, and [`RANDOM_VIEWS`] random
/// ones from `seed`.
fn strict_views(seed: u32) -> Vec<Vec3> {
    let mut views: Vec<Vec3> = THETAS.iter().map(|&t| view(t, 1.0)).collect();
    let min_cos = 89.9f32.to_radians().cos();
    let mut rng = RandomStream::new(seed, 0, 7);
    for _ in 0..RANDOM_VIEWS {
        let z = 1.0 - (1.0 - min_cos) * rng.next_f32();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * rng.next_f32();
        views.push(Vec3::new(r * phi.cos(), r * phi.sin(), z));
    }
    views
}

/// The uniform numbers for view number `v`: every combination of [`EDGE_UNIFORMS`] for `u`
/// with `uc` ∈ {0, [`ONE_MINUS`]}, then [`SAMPLES_PER_VIEW`] random triples.
fn uniforms(seed: u32, v: u32) -> Vec<(f32, Vec2)> {
    let mut inputs = Vec::new();
    for &a in &EDGE_UNIFORMS {
        for &b in &EDGE_UNIFORMS {
            for &c in &[0.0, ONE_MINUS] {
                inputs.push((c, Vec2::new(a, b)));
            }
        }
    }
    let mut streams = [1, 2, 3].map(|d| RandomStream::new(seed, d, v));
    for _ in 0..SAMPLES_PER_VIEW {
        let uc = streams[0].next_f32();
        inputs.push((uc, Vec2::new(streams[1].next_f32(), streams[2].next_f32())));
    }
    inputs
}

/// Checks every sample of `case` from `views`; returns a description of every failure, and
/// prints the worst error / tolerance of each kind.
fn check_samples(case: &Config, views: &[Vec3], seed: u32, checks: Checks) -> Vec<String> {
    let mut failures = Vec::new();
    let (mut worst_weight, mut worst_pdf, mut worst_unit) =
        (Worst::default(), Worst::default(), Worst::default());
    let mut accepted = 0u32;
    for (v, &wo) in views.iter().enumerate() {
        for (uc, u) in uniforms(seed, v as u32) {
            let Some(s) = case.bsdf.sample(wo, uc, u) else { continue };
            accepted += 1;
            let what = || format!("{}: wo = {wo:?}, uc = {uc:?}, u = {u:?} -> {s:?}", case.label);
            let wi = s.wi;
            if !(wi.is_finite() && wi.z > 0.0) {
                failures.push(format!("wi not finite or not above the horizon: {}", what()));
                continue;
            }
            worst_unit.record((wi.length() - 1.0).abs(), UNIT_TOLERANCE, what);
            if !(s.weight.is_finite() && s.weight.min_element() >= 0.0) {
                failures.push(format!("weight not finite or negative: {}", what()));
            }
            if !(s.pdf.is_finite() && s.pdf > 0.0) {
                failures.push(format!("pdf not finite and positive: {}", what()));
                continue;
            }
            if checks == Checks::Validity {
                continue;
            }
            let pdf = case.bsdf.pdf(wo, wi);
            // c = ωo·ωm = |ωo + ωi|/2 for unit vectors: well conditioned, unlike the dot product.
            let c = 0.5 * (wo + wi).length();
            worst_pdf.record(relative_error(s.pdf, pdf), pdf_tolerance(case.alpha, c), || {
                format!("{} (pdf(wo, wi) = {pdf}, c = {c})", what())
            });
            let expected = case.bsdf.eval(wo, wi) / pdf;
            let scale = expected.abs().max(s.weight.abs()).max_element();
            let error = (s.weight - expected).abs().max_element();
            let error = if scale > 0.0 { error / scale } else { error };
            worst_weight.record(error, weight_tolerance(case.alpha, c), || {
                format!("{} (eval/pdf = {expected:?}, c = {c})", what())
            });
        }
    }
    for (label, worst) in [("weight", &worst_weight), ("pdf", &worst_pdf), ("unit", &worst_unit)] {
        if !(worst.ratio <= 1.0) {
            failures.push(format!("{label} error {:.3}x its tolerance: {}", worst.ratio, worst.what));
        }
    }
    println!(
        "{:<58} {accepted:>6} samples; worst error / tolerance: weight {:.3}, pdf {:.3}, unit {:.3}",
        case.label, worst_weight.ratio, worst_pdf.ratio, worst_unit.ratio
    );
    failures
}

/// [`check_samples`] on every case of every lobe with its [`strict_views`]; fails with every
/// failure.
#[test]
fn every_lobe_sample_matches_eval_and_pdf() {
    let failures: Vec<String> = LOBES
        .iter()
        .flat_map(|row| {
            (row.consistency.configs)()
                .iter()
                .enumerate()
                .flat_map(|(i, case)| {
                    let seed = row.consistency.seed + i as u32;
                    check_samples(case, &strict_views(seed), seed, Checks::All)
                })
                .collect::<Vec<_>>()
        })
        .collect();
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}

/// Every lobe at [`GRAZING_THETAS`]: samples are valid (weight and pdf are compared in
/// [`pdf_is_positive_for_sampled_directions_at_grazing_views`]).
#[test]
fn samples_are_valid_at_grazing_views() {
    let views: Vec<Vec3> = GRAZING_THETAS.iter().map(|&t| view(t, 1.0)).collect();
    let cases = all_cases();
    let failures: Vec<String> = cases
        .iter()
        .enumerate()
        .flat_map(|(i, case)| check_samples(case, &views, 5000 + i as u32, Checks::Validity))
        .collect();
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}

/// **Regression test.** For a view within about 0.01° of the horizon, `GgxSpecular::pdf` (and
/// so the material's pdf) used to return 0 for some directions that `sample` returned with a
/// positive pdf, while `eval` there was positive: `eval/pdf = ∞`. The half vector is recomputed as
/// `normalize(ωo + ωi)`; for a back-scattering reflection ωi ≈ −ωo the sum is short
/// (`|ωo + ωi| = 2 ωo·ωm`, here ~1e-4) and its `f32` rounding tilts the half vector enough that
/// `ωo·ωm'` comes out ≤ 0, which `pdf` treats as a back-facing microfacet — although
/// `ωo·normalize(ωo + ωi) = |ωo + ωi|/2 ≥ 0` exactly. Computing that cosine as
/// `0.5·|ωo + ωi|` fixed it (`specular.rs`, `half_vector`). (A renderer using `pdf` for MIS
/// would weight such a sample by 0 or divide by it.)
#[test]
fn pdf_is_positive_for_sampled_directions_at_grazing_views() {
    let views: Vec<Vec3> = GRAZING_THETAS.iter().map(|&t| view(t, 1.0)).collect();
    // The lobes with a microfacet part.
    let cases: Vec<Config> = all_cases().into_iter().filter(|case| case.alpha.is_some()).collect();
    let mut failures = Vec::new();
    for (i, case) in cases.iter().enumerate() {
        let mut zero = 0;
        let mut example = String::new();
        let mut total = 0;
        for (v, &wo) in views.iter().enumerate() {
            for (uc, u) in uniforms(7000 + i as u32, v as u32) {
                let Some(s) = case.bsdf.sample(wo, uc, u) else { continue };
                total += 1;
                if case.bsdf.pdf(wo, s.wi) == 0.0 {
                    zero += 1;
                    if example.is_empty() {
                        example = format!(
                            "wo = {wo:?}, uc = {uc:?}, u = {u:?} -> {s:?}; pdf(wo, wi) = 0, eval(wo, wi) = {:?}",
                            case.bsdf.eval(wo, s.wi)
                        );
                    }
                }
            }
        }
        if zero > 0 {
            failures.push(format!(
                "{}: {zero} of {total} samples have pdf(wo, wi) = 0, e.g. {example}",
                case.label
            ));
        }
    }
    assert!(failures.is_empty(), "{} cases:\n{}", failures.len(), failures.join("\n"));
}

/// A view at or below the horizon has no reflection: `sample` is `None`, `eval` and `pdf` 0.
#[test]
fn views_at_or_below_the_horizon_reflect_nothing() {
    let cases = all_cases();
    let wi = view(45.0, 2.0);
    for case in &cases {
        for wo in [Vec3::X, Vec3::new(0.6, 0.0, -0.8), -Vec3::Z, Vec3::new(0.0, 1.0, -0.0)] {
            for (uc, u) in uniforms(9000, 0).into_iter().take(64) {
                assert!(case.bsdf.sample(wo, uc, u).is_none(), "{}: wo = {wo:?}", case.label);
            }
            assert_eq!(case.bsdf.eval(wo, wi), Vec3::ZERO, "{}: wo = {wo:?}", case.label);
            assert_eq!(case.bsdf.pdf(wo, wi), 0.0, "{}: wo = {wo:?}", case.label);
            // And a light direction at or below the horizon contributes nothing.
            assert_eq!(case.bsdf.eval(wi, wo), Vec3::ZERO, "{}: wi = {wo:?}", case.label);
            assert_eq!(case.bsdf.pdf(wi, wo), 0.0, "{}: wi = {wo:?}", case.label);
        }
    }
}

// --- pdf normalisation -------------------------------------------------------------------

/// Samples of the Monte Carlo estimate of the probability that `sample` returns a direction.
const ACCEPTANCE_SAMPLES: u32 = 1_000_000;

/// The quadrature's relative tolerance: the harness's default 1e-4, and 1e-3 for α = 1e-4,
/// whose pdf has `f32` noise of about `(2/α)·u` ≈ 1e-3 even at normal incidence (a tighter
/// tolerance only chases rounding and never converges). `alpha` is the lobe's smallest GGX α
/// (`None`: no microfacet lobe).
fn quadrature_tolerance(alpha: Option<f32>) -> f64 {
    match alpha {
        Some(alpha) if alpha < 0.01 => 1e-3,
        _ => 1e-4,
    }
}

/// `∫ pdf dω` of `config` seen from `wo`, by the harness's adaptive quadrature, against the
/// fraction of [`ACCEPTANCE_SAMPLES`] samples that `sample` accepts.
///
/// Tolerance: 5 binomial standard deviations of the fraction, `5·√(p(1 − p)/n)` (at least
/// `5/n`; two-sided 5σ is a 6·10⁻⁷ chance per check, for ~150 deterministic checks) plus twice
/// the quadrature's relative tolerance (its per-interval criterion bounds the error of the
/// coarser estimate; the kept one was measured within 0.7 of the tolerance in the worst case,
/// a lobe near the pole). The quadrature must have converged in every cell, and the integral
/// must not exceed 1 by more than that quadrature allowance.
fn check_integral(name: &str, config: &Config, wo: Vec3, seed: u32) -> Result<f64, String> {
    let bsdf = config.bsdf.as_ref();
    let tolerance = quadrature_tolerance(config.alpha);
    let test = ChiSquareTest { quadrature_tolerance: tolerance, ..ChiSquareTest::default() };
    let integral = test.integrate_pdf(|wi| bsdf.pdf(wo, wi));
    let mut streams = [0, 1, 2].map(|d| RandomStream::new(seed, d, 11));
    let accepted = (0..ACCEPTANCE_SAMPLES)
        .filter(|_| {
            let uc = streams[0].next_f32();
            bsdf.sample(wo, uc, Vec2::new(streams[1].next_f32(), streams[2].next_f32())).is_some()
        })
        .count();
    let n = f64::from(ACCEPTANCE_SAMPLES);
    let fraction = accepted as f64 / n;
    let p = integral.total.clamp(0.0, 1.0);
    let allowed = 5.0 * (p * (1.0 - p) / n).sqrt().max(1.0 / n) + 2.0 * tolerance;
    let deviation = (integral.total - fraction).abs();
    println!(
        "{name:<60} integral {:.6}, accepted {fraction:.6}: deviation / allowed {:.3} ({} pdf evaluations)",
        integral.total,
        deviation / allowed,
        integral.evaluations
    );
    if integral.unconverged_cells > 0 || integral.bad_pdf_values > 0 {
        return Err(format!(
            "{name}: quadrature unconverged in {} cells (e.g. {:?}), {} bad pdf values",
            integral.unconverged_cells, integral.unconverged_examples, integral.bad_pdf_values
        ));
    }
    if !(deviation <= allowed) || integral.total > 1.0 + 2.0 * tolerance {
        return Err(format!(
            "{name}: pdf integrates to {}, but sample accepted {fraction} of {n} (allowed deviation {allowed})",
            integral.total
        ));
    }
    Ok(deviation / allowed)
}

/// Runs [`check_integral`] for every configuration and its view angles; returns every failure.
fn check_integrals(configs: &[IntegralConfig], seed: u32) -> Vec<String> {
    let mut failures = Vec::new();
    for (i, IntegralConfig { config, thetas }) in configs.iter().enumerate() {
        for (t, &theta) in thetas.iter().enumerate() {
            let label = format!("{} theta={theta}", config.label);
            let seed = seed + (i * 8 + t) as u32;
            if let Err(e) = check_integral(&label, config, view(theta, 1.0), seed) {
                failures.push(e);
            }
        }
    }
    failures
}

/// [`check_integrals`] on every group of `∫ pdf` checks of every row of [`LOBES`] (the view
/// angles of each configuration are the row's: see `furnace_tests::lobes` for the views left
/// out where the quadrature cannot resolve the lobe), the groups in parallel; fails with every
/// failure.
#[test]
fn every_lobe_pdf_integrates_to_acceptance() {
    let failures: Vec<String> = std::thread::scope(|scope| {
        let handles: Vec<_> = LOBES
            .iter()
            .flat_map(|row| row.consistency.integrals)
            .map(|group| scope.spawn(move || check_integrals(&(group.configs)(), group.seed)))
            .collect();
        handles.into_iter().flat_map(|h| h.join().expect("an integral thread panicked")).collect()
    });
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}

// --- reciprocity -----------------------------------------------------------------------------

/// Relative tolerance of reciprocity for the pair (ωo, ωi), with `c = |ωo + ωi|/2` (see [`U`]).
///
/// `eval(ωo, ωi)` and `eval(ωi, ωo)` share the half vector ωm' bit for bit (`ωo + ωi = ωi + ωo`),
/// so D and the masking denominators are identical. They differ where the code uses `ωo·ωm'`
/// versus `ωi·ωm'`: equal for the exact bisector, but ωm' is off by an angle of about `u/c`,
/// so the two cosines differ by about `2u/c`. Schlick's F (slope `5(F90 − F0)` ≤ 5 in the
/// cosine, F ≥ F0 ≥ 0.028 here) moves by `10u/c` absolute; the material's diffuse layer is
/// scaled by `1 − sF·F`, which near grazing is as small as `5c`, so its relative error is about
/// `2u/c²`. Tolerance: [`SLACK`] times `u·(10/(c·F0min) + 2/c²)` plus [`RECIPROCITY_FLOOR`].
fn reciprocity_tolerance(c: f32) -> f32 {
    const F0_MIN: f32 = 0.028;
    RECIPROCITY_FLOOR + SLACK * U * (10.0 / (c * F0_MIN) + 2.0 / (c * c))
}

/// The rounding of the divisions by the cosines and of the products (a few dozen roundings).
const RECIPROCITY_FLOOR: f32 = 5e-6;

/// Pairs of directions for the reciprocity check: random (cos θ uniform in (0, 1]) and
/// grazing (cos θ ∈ {1e-4, 1e-3, 1e-2}) ones in both roles.
fn direction_pairs(seed: u32) -> Vec<(Vec3, Vec3)> {
    let mut rng = RandomStream::new(seed, 0, 13);
    let mut random_direction = |z: Option<f32>| {
        let z = z.unwrap_or_else(|| 1.0 - rng.next_f32());
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * rng.next_f32();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    };
    let mut pairs = Vec::new();
    for _ in 0..4000 {
        pairs.push((random_direction(None), random_direction(None)));
    }
    for z in [1e-4, 1e-3, 1e-2] {
        for _ in 0..200 {
            pairs.push((random_direction(Some(z)), random_direction(None)));
            pairs.push((random_direction(Some(z)), random_direction(Some(z))));
        }
    }
    pairs
}

/// `eval(ωo, ωi)/cos θi = eval(ωi, ωo)/cos θo` (the BRDF itself is symmetric) for every
/// reciprocity configuration of every row of [`LOBES`] (Lambert, GGX with both maskings, every
/// material), all without compensation (Turquin's factor depends on `cos θo` alone and is not
/// reciprocal).
#[test]
fn eval_is_reciprocal_without_compensation() {
    let cases: Vec<Config> = LOBES.iter().flat_map(|row| (row.consistency.reciprocal)()).collect();
    let pairs = direction_pairs(1);
    let mut failures = Vec::new();
    for case in &cases {
        let mut worst = Worst::default();
        let mut nonzero = 0;
        for &(wo, wi) in &pairs {
            let forward = case.bsdf.eval(wo, wi) / wi.z;
            let backward = case.bsdf.eval(wi, wo) / wo.z;
            if !(forward.is_finite() && backward.is_finite()) {
                failures.push(format!("{}: not finite for wo = {wo:?}, wi = {wi:?}", case.label));
                continue;
            }
            let scale = forward.abs().max(backward.abs()).max_element();
            if scale > 0.0 {
                nonzero += 1;
                let error = (forward - backward).abs().max_element() / scale;
                let c = 0.5 * (wo + wi).length();
                worst.record(error, reciprocity_tolerance(c), || {
                    format!("wo = {wo:?}, wi = {wi:?}, c = {c}: {forward:?} vs {backward:?}")
                });
            }
        }
        println!("{:<40} {nonzero:>5} nonzero pairs; worst error / tolerance {:.3}", case.label, worst.ratio);
        if !(worst.ratio <= 1.0) {
            failures
                .push(format!("{}: error {:.3}x the tolerance at {}", case.label, worst.ratio, worst.what));
        }
    }
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}

/// Where a lobe's albedo estimate at μo vanishes while the lobe does not, the sample must still
/// carry the whole BSDF: `weight = eval(wo, wi)/pdf(wo, wi)`. The lobe-choice probability is
/// estimated from the lobes' albedos *at μo*: with specularFactor 1 the diffuse scale
/// `1 − F(μo)` rounds to 0 below μo ≈ 1e-8, and with F0 = 0 < F90 the specular estimate is 0 at
/// μo = 1. A probability of exactly 1 (or 0) there made `sample` return the other lobe's own
/// sample, whose weight leaves out a lobe that `eval` still has: energy lost at grazing views.
/// Views: μo from 1 down to 1e-12 (still above MIN_COS). Tolerance 1e-3 relative: f32 rounding
/// of eval/pdf is ~1e-6; the bug's error is the whole diffuse lobe (tens of percent).
#[test]
fn samples_carry_both_lobes_when_a_lobe_estimate_vanishes() {
    let cases = [
        (
            "specularFactor 1, dielectric",
            MetallicRoughnessParams {
                base_color: Vec3::splat(0.8),
                metallic: 0.0,
                roughness: 0.5,
                specular_factor: 1.0,
                specular_color: Vec3::ONE,
            },
        ),
        (
            "F0 = 0 < F90 (specularColor 0)",
            MetallicRoughnessParams {
                base_color: Vec3::splat(0.8),
                metallic: 0.0,
                roughness: 0.5,
                specular_factor: 1.0,
                specular_color: Vec3::ZERO,
            },
        ),
    ];
    let mut failures = Vec::new();
    let mut rng = RandomStream::new(0, 0, 7);
    for (name, params) in cases {
        for options in [SpecularOptions::default(), SpecularOptions::mitsuba()] {
            let bsdf = MetallicRoughness::new(params, options);
            for mu in [1.0f32, 0.5, 1e-3, 1e-6, 1e-8, 1e-10, 1e-12] {
                let wo = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
                for _ in 0..256 {
                    let (uc, u) = (rng.next_f32(), Vec2::new(rng.next_f32(), rng.next_f32()));
                    let Some(s) = bsdf.sample(wo, uc, u) else { continue };
                    let want = bsdf.eval(wo, s.wi) / bsdf.pdf(wo, s.wi);
                    let err = ((s.weight - want).abs() / want.abs().max(Vec3::splat(1e-6))).max_element();
                    if !(err < 1e-3) {
                        failures.push(format!(
                            "{name}, {options:?}: μo = {mu:e}, wi = {}: weight {} but eval/pdf {want} \
                             (p_spec {})",
                            s.wi,
                            s.weight,
                            bsdf.specular_probability(wo)
                        ));
                        break;
                    }
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} cases where weight ≠ eval/pdf:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
