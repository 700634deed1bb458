//! A chi-square goodness-of-fit test for direction sampling routines: does a sampler draw
//! directions with the density that its pdf claims?
//!
//! This is the test of Mitsuba 3 (`src/python/python/chi2.py`, class `ChiSquareTest`) and of
//! pbrt (`src/pbrt/bsdfs_test.cpp` in pbrt-v4, after pbrt-v3's chi-square tests of its BSDFs;
//! both descend from Wenzel Jakob's chi-square test in Mitsuba 0.5). One harness serves any pair
//! of a sampler and a pdf: the warps of this crate, and BSDF sampling routines later.
//!
//! ## Method
//!
//! 1. **Grid.** The sphere is divided into `cos_theta_res × phi_res` cells, uniform in
//!    `cos θ ∈ [−1, 1]` and `φ ∈ [0, 2π)`. The map `(cos θ, φ) → ω` has Jacobian 1, so every cell
//!    has the same solid angle `4π / (cos_theta_res · phi_res)`.
//! 2. **Observed counts.** `sample_count` triples `(u, uc)` of uniform numbers come from a
//!    fixed-seed [`RandomStream`] inside the harness; each sampled direction is counted in
//!    its cell. A sampler may reject (return `None`); rejections are counted in an extra
//!    *rejection cell*.
//! 3. **Expected counts.** The pdf (solid-angle measure) is integrated over every cell and
//!    multiplied by `sample_count`. The integral is **adaptive** (default): a nested
//!    Gauss–Legendre rule, outer in `cos θ`, inner in `φ`, each bisecting its interval until
//!    the rule on the interval and on its two halves agree to the relative tolerance
//!    `quadrature_tolerance` (see [Adaptive quadrature](#adaptive-quadrature)); with
//!    `quadrature_tolerance = 0` it is one fixed tensor rule of `quadrature_order` points per
//!    axis. The rejection cell expects `sample_count · (1 − ∫pdf)`: a sampler whose pdf
//!    integrates to less than one must return `None` with exactly the missing probability.
//! 4. **Pooling.** Pearson's statistic is unreliable for cells with small expected counts, so,
//!    as in pbrt and Mitsuba, cells are sorted by expected count and every cell expecting fewer
//!    than `min_expected` (5) is merged into one pooled cell; if the pool still expects fewer
//!    than `min_expected`, the next-smallest cells are added until it does not. Cells that
//!    expect nothing and observe nothing are skipped. (The rejection cell is pooled like any
//!    other; its expectation `1 − ∫pdf` carries the quadrature's rounding.)
//! 5. **Statistic.** `χ² = Σ (observed − expected)² / expected` over the remaining cells and the
//!    pool, with `dof = cells − 1` (the total is fixed; the pdf has no fitted parameters). The
//!    p-value is `Q(dof/2, χ²/2)`, the regularized upper incomplete gamma function
//!    ([`chi_square_p_value`]).
//! 6. **Decision.** The test fails if `p < threshold`. The threshold is the **Šidák
//!    correction** of the significance level `α` for a family of `n` independent tests,
//!    `1 − (1 − α)^(1/n)`, so that the chance of *any* false failure among the `n` tests is
//!    `α` ([`sidak_threshold`]).
//!
//! Independently of the statistic, a test fails outright (as in Mitsuba and pbrt) if
//!
//! * any sample is not a finite unit vector;
//! * any sample lands where the pdf is `0` (or not finite);
//! * any grid cell observes samples although its integrated pdf is `0` (Mitsuba: "found
//!   samples in a cell with expected frequency 0"; pbrt tolerates `10⁻⁵·sample_count` such
//!   samples, this harness none);
//! * the pdf is negative or not finite anywhere the quadrature looks;
//! * the pdf integrates to more than `max_pdf_integral` (default `1.001`; Mitsuba uses `1.1`).
//!   A pdf that is uniformly a little too large is nearly invisible to the statistic — an
//!   excess of 0.1% at 10⁶ samples adds about 1 to `χ²` — but the quadrature sees it.
//!
//! On failure, [`ChiSquareResult`]'s `Display` ([`ChiSquareResult::report`]) prints the
//! statistics, the problems found, the worst cells and the observed, expected and residual
//! tables (aggregated to a readable size), and [`ChiSquareResult::write_tables`] writes the
//! full-resolution tables as text, CSV and a PPM image.
//!
//! ## Choosing the resolution
//!
//! Keep `cos_theta_res` even, so that the horizon `cos θ = 0` — where hemispherical pdfs jump
//! or have a kink — is a cell edge and the quadrature stays accurate. (*Deviation from
//! Mitsuba*, whose default resolution is odd, 101, so that the horizon runs through the middle
//! of a cell, and which integrates each cell by the trapezoid rule; here the Gauss–Legendre
//! nodes lie strictly inside the cells, so an edge on the horizon is never evaluated.)
//!
//! ## Adaptive quadrature
//!
//! A pdf much narrower than a cell (a GGX lobe of roughness 0.02 is about 2° wide, a default
//! cell about 3° × 3°, and the lobe of normal incidence is a thin ring of `1 − cos θ ≈ 10⁻³`
//! inside the top row) defeats any fixed rule: five nodes per axis miss or over-weight the
//! peak and the expected counts are wrong by far more than the statistic tolerates. Mitsuba
//! 0.5's chi-square test therefore integrated every cell with an adaptive cubature (its
//! `NDIntegrator`, at most 10⁵ evaluations per cell). Here each cell is integrated as
//! `∫ dz ∫ dφ pdf`, each one-dimensional integral by recursive adaptive bisection: on an
//! interval, the `quadrature_order`-point Gauss–Legendre estimate of the whole is compared
//! with the sum of the estimates of its two halves; the interval is accepted when they differ
//! by at most `max(quadrature_tolerance · |halves|, floor)`, and otherwise both halves are
//! refined in turn. The sum of the halves is kept (the more accurate of the two): the
//! tolerance estimates the error of the coarser estimate, and the kept one's is usually far
//! smaller (the worst seen, a GGX lobe of roughness 0.02 half a degree from the pole, was
//! 0.7 of the tolerance). Nesting the axes lets each refine only where it must (a lobe at the
//! pole is sharp in `cos θ` alone) and makes a jump along a curve cost `O(depth)`, not
//! `O(2^depth)`.
//!
//! * Both axes use the same relative tolerance, `quadrature_tolerance` (default `10⁻⁴`). It
//!   must stay above the relative noise of the pdf's own evaluation at `f32` directions, or
//!   the bisection chases rounding: GGX at grazing angles computes its half vector
//!   `normalize(ωo + ωi)` from a short sum, whose rounding moves a sharp lobe's value by a few
//!   `10⁻⁵` (roughness 0.02 to 0.6 at 89°) up to `10⁻²` (roughness `10⁻⁴` at 89°).
//! * The absolute floor is `quadrature_tolerance` expected *counts* per cell (i.e.
//!   `quadrature_tolerance / sample_count` of probability; the φ integrals get it divided by the
//!   cell's `cos θ` width), halved at each bisection, so that cells in the far tail of a pdf,
//!   which expect ≪ 1 sample, stop early.
//! * For a nonnegative pdf a relative tolerance per interval is a relative tolerance for the
//!   cell. An error `δ = r·e` in the expected count `e` of every cell biases `χ²` by about
//!   `Σ δ²/e = r²·sample_count`: 0.01 at the default `r = 10⁻⁴` and 10⁶ samples, nothing
//!   beside the statistic's standard deviation `√(2·dof)` (≈ 90 for the default grid).
//! * Bisection stops at intervals of `2⁻²³` (in `cos θ`, or radians of `φ`: about the
//!   rounding of an `f32` direction), at `max_subdivision_depth` levels per axis (default 30),
//!   or when a cell has used `max_cell_evaluations` pdf evaluations (default 200 000); such
//!   cells are counted in [`ChiSquareResult::unconverged_cells`] and named in the report. Their
//!   expected counts may be wrong — badly so when the budget ran out, since the remaining
//!   intervals then keep unrefined estimates of a sharp peak — so a test that must trust its
//!   expected counts should also require `unconverged_cells == 0`. Causes: a tolerance below
//!   the pdf's `f32` noise (raise it), a peak narrower than `2⁻²³` in `cos θ` (a GGX lobe of
//!   roughness `10⁻⁴` at normal incidence, `1 − cos θ ≈ 2·10⁻⁸`), or a jump of the pdf inside
//!   a cell (the relative criterion cannot converge at a jump, though the error there,
//!   `jump × 2⁻²³ ×` the cell's width, is negligible).
//! * Like any adaptive rule it refines only where its estimates disagree: a needle much
//!   narrower than the node spacing on top of a smooth background can be missed by every
//!   node and go unnoticed (a GGX lobe of roughness `10⁻⁴` next to the pole over a diffuse
//!   lobe: nodes there are ~0.03 rad apart in θ). Lobes with tails, alone, are found.
//!
//! Smooth pdfs converge at the first comparison: three rules per axis, `9 · quadrature_order²`
//! evaluations per cell instead of `quadrature_order²`, about 1.8 million evaluations for
//! the default grid; sharp lobes add a few percent. A test of 10⁶ BSDF samples then spends
//! about as long integrating as sampling.
//!
//! ## Example
//!
//! ```
//! use furnace_tests::chi2::ChiSquareTest;
//! use furnace_sampling::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
//!
//! let test = ChiSquareTest { sample_count: 100_000, ..ChiSquareTest::default() };
//! let result = test.run(|u, _uc| Some(square_to_cosine_hemisphere(u)), cosine_hemisphere_pdf);
//! assert!(result.passed, "{result}");
//! ```

use furnace_sampling::RandomStream;
use glam::{Vec2, Vec3};
use std::cell::{Cell, RefCell};
use std::f64::consts::{PI, TAU};
use std::fmt::{self, Write as _};
use std::io::{self, Write as _};
use std::path::{Path, PathBuf};

/// How many examples of each kind of problem a result keeps for its report.
const MAX_EXAMPLES: usize = 5;

/// Configuration of a chi-square test of a direction sampler against its pdf.
///
/// All fields are public; start from [`Default`] and override what you need:
///
/// ```
/// # use furnace_tests::chi2::ChiSquareTest;
/// let test = ChiSquareTest { test_count: 4, seed: 7, ..ChiSquareTest::default() };
/// assert!((test.threshold() - 0.002_509).abs() < 1e-6);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ChiSquareTest {
    /// Number of cells in `cos θ ∈ [−1, 1]` (default 64). Keep it even so that the horizon is a
    /// cell edge.
    pub cos_theta_res: usize,
    /// Number of cells in `φ ∈ [0, 2π)` (default 128, twice `cos_theta_res`, as pbrt's
    /// `phiRes = 2·thetaRes`).
    pub phi_res: usize,
    /// Number of samples drawn (default 1 000 000).
    pub sample_count: usize,
    /// Significance level `α` for the whole family of `test_count` tests (default 0.01).
    pub significance: f64,
    /// Number of tests in the family, for the Šidák correction (default 1).
    pub test_count: usize,
    /// Cells expecting fewer samples than this are pooled (default 5).
    pub min_expected: f64,
    /// Gauss–Legendre points per axis and interval for the pdf integral (default 5: exact for
    /// polynomials of degree ≤ 9 in each of `cos θ` and `φ`).
    pub quadrature_order: usize,
    /// Relative tolerance of the adaptive per-cell integration of the pdf (default `1e-4`),
    /// see [Adaptive quadrature](self#adaptive-quadrature). `0` selects one fixed tensor rule
    /// of `quadrature_order²` points per cell (no error control).
    pub quadrature_tolerance: f64,
    /// Most bisections per axis of the adaptive integration (default 30; intervals narrower
    /// than `2⁻²³` are never bisected, which for the default grid is reached first).
    pub max_subdivision_depth: usize,
    /// Most pdf evaluations of the adaptive integration per cell (default 200 000); a cell
    /// that needs more stops refining and counts as unconverged.
    pub max_cell_evaluations: usize,
    /// Seed of the harness's uniform number generator (default 0).
    pub seed: u32,
    /// A sampled direction `w` must satisfy `|‖w‖ − 1| ≤ normalization_tolerance`
    /// (default 1e-3).
    pub normalization_tolerance: f32,
    /// The test fails if `∫ pdf dω` exceeds this (default 1.001: well above the quadrature
    /// error for smooth pdfs, well below what the statistic alone would notice).
    pub max_pdf_integral: f64,
}

impl Default for ChiSquareTest {
    fn default() -> Self {
        Self {
            cos_theta_res: 64,
            phi_res: 128,
            sample_count: 1_000_000,
            significance: 0.01,
            test_count: 1,
            min_expected: 5.0,
            quadrature_order: 5,
            quadrature_tolerance: 1e-4,
            max_subdivision_depth: 30,
            max_cell_evaluations: 200_000,
            seed: 0,
            normalization_tolerance: 1e-3,
            max_pdf_integral: 1.001,
        }
    }
}

impl ChiSquareTest {
    /// The Šidák-corrected threshold on the p-value: `1 − (1 − significance)^(1/test_count)`.
    pub fn threshold(&self) -> f64 {
        sidak_threshold(self.significance, self.test_count)
    }

    /// Runs the test.
    ///
    /// * `sample(u, uc)` maps uniform numbers `u ∈ [0, 1)²` and `uc ∈ [0, 1)` (for a discrete
    ///   choice, e.g. a BSDF lobe) to a unit direction, or `None` when it rejects the sample.
    /// * `pdf(w)` is the density of `sample` with respect to **solid angle**, for any unit `w`.
    ///   Its integral over the sphere is the probability that `sample` returns `Some`.
    ///
    /// # Panics
    ///
    /// If a resolution, `sample_count`, `test_count` or `quadrature_order` is zero, or
    /// `significance` is not in `(0, 1)`.
    pub fn run<S, P>(&self, mut sample: S, pdf: P) -> ChiSquareResult
    where
        S: FnMut(Vec2, f32) -> Option<Vec3>,
        P: Fn(Vec3) -> f32,
    {
        assert!(self.cos_theta_res > 0 && self.phi_res > 0, "empty grid");
        assert!(self.sample_count > 0, "sample_count must be positive");
        assert!(self.test_count > 0, "test_count must be positive");
        assert!(self.significance > 0.0 && self.significance < 1.0, "significance must be in (0, 1)");

        let cells = self.cos_theta_res * self.phi_res;
        let mut problems = Vec::new();

        // Observed counts.
        let mut observed = vec![0_u64; cells];
        let mut rejected_observed = 0_u64;
        let mut invalid_samples = 0_u64;
        let mut zero_pdf_samples = 0_u64;
        // Three independent counter-based streams (this crate's RandomStream, period 2^32 each):
        // independent uniform numbers, as the multinomial model of the test assumes.
        let mut streams = [0, 1, 2].map(|d| RandomStream::new(0, d, self.seed));
        for index in 0..self.sample_count {
            let u = Vec2::new(streams[0].next_f32(), streams[1].next_f32());
            let uc = streams[2].next_f32();
            let Some(w) = sample(u, uc) else {
                rejected_observed += 1;
                continue;
            };
            if !w.is_finite() || (w.length() - 1.0).abs() > self.normalization_tolerance {
                invalid_samples += 1;
                if invalid_samples as usize <= MAX_EXAMPLES {
                    problems.push(format!(
                        "sample #{index} (u = {u}, uc = {uc}) is not a finite unit vector: \
                         w = {w}, |w| = {}",
                        w.length()
                    ));
                }
                continue;
            }
            let density = pdf(w);
            if !(density > 0.0 && density.is_finite()) {
                zero_pdf_samples += 1;
                if zero_pdf_samples as usize <= MAX_EXAMPLES {
                    problems.push(format!(
                        "sample #{index} (u = {u}, uc = {uc}) landed where pdf = {density}: \
                         w = {w}"
                    ));
                }
            }
            observed[self.cell_of(w)] += 1;
        }

        // Expected counts.
        let integrals = self.integrate_pdf(&pdf);
        problems.extend(integrals.problems);
        let bad_pdf_values = integrals.bad_pdf_values;
        let n = self.sample_count as f64;
        let expected: Vec<f64> = integrals.cells.iter().map(|p| p * n).collect();
        let pdf_integral = integrals.total;
        let rejected_expected = (n * (1.0 - pdf_integral)).max(0.0);

        // Samples in cells that expect none (the pdf at the samples themselves was positive,
        // or they were counted above): the quadrature found no support there.
        let mut zero_expected_cells = 0;
        for (i, (&o, &e)) in observed.iter().zip(&expected).enumerate() {
            if o > 0 && e <= 0.0 {
                zero_expected_cells += 1;
                if zero_expected_cells <= MAX_EXAMPLES {
                    let (row, col) = (i / self.phi_res, i % self.phi_res);
                    problems.push(format!(
                        "cell ({row}, {col}) observed {o} samples but its integrated pdf is 0"
                    ));
                }
            }
        }
        if zero_expected_cells > 0 {
            problems.push(format!(
                "{zero_expected_cells} cells in all observed samples but expected none (if the \
                 pdf is positive there, its support is narrower than the quadrature resolves: \
                 lower quadrature_tolerance, or raise quadrature_order or the grid resolution)"
            ));
        }
        if pdf_integral > self.max_pdf_integral {
            problems.push(format!(
                "the pdf integrates to {pdf_integral} > {} over the sphere",
                self.max_pdf_integral
            ));
        }

        // Pearson's statistic over the grid cells and the rejection cell.
        let mut table: Vec<(f64, f64)> =
            observed.iter().zip(&expected).map(|(&o, &e)| (o as f64, e)).collect();
        table.push((rejected_observed as f64, rejected_expected));
        let pearson = pooled_chi_square(&table, self.min_expected);
        let dof = pearson.terms.saturating_sub(1);
        let p_value = if dof > 0 {
            chi_square_p_value(pearson.chi2, dof)
        } else {
            problems.push(format!(
                "too few degrees of freedom ({} cells after pooling): refine the grid or \
                 draw more samples",
                pearson.terms
            ));
            f64::NAN
        };
        if invalid_samples > 0 {
            problems.push(format!("{invalid_samples} samples in all were not unit vectors"));
        }
        if zero_pdf_samples > 0 {
            problems.push(format!("{zero_pdf_samples} samples in all landed where pdf = 0"));
        }

        let threshold = self.threshold();
        let passed = invalid_samples == 0
            && zero_pdf_samples == 0
            && zero_expected_cells == 0
            && bad_pdf_values == 0
            && pdf_integral <= self.max_pdf_integral
            && p_value.is_finite()
            && p_value >= threshold;

        ChiSquareResult {
            chi2: pearson.chi2,
            dof,
            p_value,
            threshold,
            passed,
            significance: self.significance,
            test_count: self.test_count,
            cos_theta_res: self.cos_theta_res,
            phi_res: self.phi_res,
            sample_count: self.sample_count,
            min_expected: self.min_expected,
            observed,
            expected,
            rejected_observed,
            rejected_expected,
            pdf_integral,
            pdf_evaluations: integrals.evaluations,
            quadrature_tolerance: self.quadrature_tolerance,
            unconverged_cells: integrals.unconverged_cells,
            unconverged_examples: integrals.unconverged_examples,
            pooled_cells: pearson.pooled_cells,
            zero_expected_cells,
            invalid_samples,
            zero_pdf_samples,
            bad_pdf_values,
            problems,
        }
    }

    /// The cell (row-major, `cos θ` row times `phi_res` plus `φ` column) containing `w`.
    fn cell_of(&self, w: Vec3) -> usize {
        let z = f64::from(w.z).clamp(-1.0, 1.0);
        let row = (((z + 1.0) * 0.5 * self.cos_theta_res as f64) as usize).min(self.cos_theta_res - 1);
        let mut phi = f64::from(w.y).atan2(f64::from(w.x));
        if phi < 0.0 {
            phi += TAU;
        }
        let col = ((phi / TAU * self.phi_res as f64) as usize).min(self.phi_res - 1);
        row * self.phi_res + col
    }

    /// `∫ pdf dω` over every cell of the grid, exactly as [`run`](Self::run) computes its
    /// expected counts (divided by `sample_count`): adaptive nested Gauss–Legendre in
    /// `(cos θ, φ)` (Jacobian 1), or the fixed tensor rule when `quadrature_tolerance` is 0.
    /// Negative or non-finite pdf values count as 0 and are reported.
    ///
    /// Also useful by itself, to check that a pdf integrates to the probability that its
    /// sampler returns a direction.
    ///
    /// # Panics
    ///
    /// If a resolution or `quadrature_order` is zero, or `quadrature_tolerance` is negative or
    /// NaN.
    pub fn integrate_pdf<P: Fn(Vec3) -> f32>(&self, pdf: P) -> CellIntegrals {
        assert!(self.cos_theta_res > 0 && self.phi_res > 0, "empty grid");
        assert!(self.quadrature_order > 0, "quadrature_order must be positive");
        assert!(self.quadrature_tolerance >= 0.0, "quadrature_tolerance must be nonnegative");

        let rule = gauss_legendre(self.quadrature_order);
        let dz = 2.0 / self.cos_theta_res as f64;
        let dphi = TAU / self.phi_res as f64;

        let evaluations = Cell::new(0_u64);
        let bad = Cell::new(0_u64);
        let problems = RefCell::new(Vec::new());
        // The pdf at (z, φ) on the sphere (r = sin θ), in f64; bad values count as 0.
        let density = |z: f64, r: f64, phi: f64| -> f64 {
            evaluations.set(evaluations.get() + 1);
            let w = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
            let d = pdf(w);
            if d >= 0.0 && d.is_finite() {
                f64::from(d)
            } else {
                bad.set(bad.get() + 1);
                if bad.get() as usize <= MAX_EXAMPLES {
                    problems.borrow_mut().push(format!("pdf is negative or not finite: pdf({w}) = {d}"));
                }
                0.0
            }
        };
        let sin_theta = |z: f64| ((1.0 - z) * (1.0 + z)).max(0.0).sqrt();

        // The absolute floor of a cell, in probability: `quadrature_tolerance` expected counts.
        let floor = self.quadrature_tolerance / self.sample_count.max(1) as f64;
        let mut unconverged_cells = 0;
        let mut unconverged_examples = Vec::new();
        let mut integrals = Vec::with_capacity(self.cos_theta_res * self.phi_res);
        for row in 0..self.cos_theta_res {
            let z0 = -1.0 + row as f64 * dz;
            let z1 = if row + 1 == self.cos_theta_res { 1.0 } else { z0 + dz };
            for col in 0..self.phi_res {
                let phi0 = col as f64 * dphi;
                let phi1 = phi0 + dphi;
                if self.quadrature_tolerance == 0.0 {
                    let sum = gauss_legendre_on(&rule, z0, z1, &mut |z| {
                        let r = sin_theta(z);
                        gauss_legendre_on(&rule, phi0, phi1, &mut |phi| density(z, r, phi))
                    });
                    integrals.push(sum);
                    continue;
                }
                let budget_end = evaluations.get().saturating_add(self.max_cell_evaluations as u64);
                let exhausted = || evaluations.get() >= budget_end;
                let unconverged = Cell::new(false);
                let bisection = Bisection {
                    rule: &rule,
                    relative: self.quadrature_tolerance,
                    max_depth: self.max_subdivision_depth,
                    exhausted: &exhausted,
                    unconverged: &unconverged,
                };
                // The inner integrals' error enters the outer one multiplied by dz.
                let inner_floor = floor / (z1 - z0);
                let sum = bisection.integrate(
                    &|z| {
                        let r = sin_theta(z);
                        bisection.integrate(&|phi| density(z, r, phi), phi0, phi1, inner_floor)
                    },
                    z0,
                    z1,
                    floor,
                );
                if unconverged.get() {
                    unconverged_cells += 1;
                    if unconverged_examples.len() < MAX_EXAMPLES {
                        unconverged_examples.push((row, col));
                    }
                }
                integrals.push(sum);
            }
        }
        let bad_pdf_values = bad.get();
        let mut problems = problems.into_inner();
        if bad_pdf_values > 0 {
            problems
                .push(format!("{bad_pdf_values} quadrature points in all had a negative or non-finite pdf"));
        }
        CellIntegrals {
            total: integrals.iter().sum(),
            cells: integrals,
            bad_pdf_values,
            unconverged_cells,
            unconverged_examples,
            evaluations: evaluations.get(),
            problems,
        }
    }
}

/// The integral of a pdf over the cells of a [`ChiSquareTest`]'s grid
/// ([`ChiSquareTest::integrate_pdf`]).
#[derive(Clone, Debug)]
pub struct CellIntegrals {
    /// `∫_cell pdf dω` per cell, row-major as [`ChiSquareResult`]'s tables.
    pub cells: Vec<f64>,
    /// `∫ pdf dω` over the sphere: the sum of `cells`.
    pub total: f64,
    /// Number of evaluations where the pdf was negative or not finite (counted as 0).
    pub bad_pdf_values: u64,
    /// Number of cells whose adaptive integration stopped at `max_subdivision_depth` or
    /// `max_cell_evaluations` before meeting its tolerance.
    pub unconverged_cells: usize,
    /// `(row, col)` of the first few unconverged cells.
    pub unconverged_examples: Vec<(usize, usize)>,
    /// Number of pdf evaluations in all.
    pub evaluations: u64,
    /// Descriptions of the bad pdf values met (a few examples and a count).
    pub problems: Vec<String>,
}

/// `∫_a^b f` by the Gauss–Legendre `rule` (nodes and weights on `[−1, 1]`).
fn gauss_legendre_on(rule: &[(f64, f64)], a: f64, b: f64, f: &mut dyn FnMut(f64) -> f64) -> f64 {
    let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
    half * rule.iter().map(|&(x, w)| w * f(mid + half * x)).sum::<f64>()
}

/// The narrowest interval the adaptive quadrature bisects, in `cos θ` or in radians of `φ`:
/// `2⁻²³`, about two `f32` roundings of a direction's unit-size components. Refining further
/// mostly measures the rounding of the `f32` directions the pdf is evaluated at, so an
/// interval this narrow that has not converged is accepted and its cell counted as
/// unconverged: the tolerance is below what the pdf's own `f32` evaluation resolves.
const MIN_WIDTH: f64 = 1.0 / (1u64 << 23) as f64;

/// One-dimensional adaptive integration by bisection (see
/// [Adaptive quadrature](self#adaptive-quadrature)).
#[derive(Clone, Copy)]
struct Bisection<'a> {
    /// Gauss–Legendre nodes and weights on `[−1, 1]`.
    rule: &'a [(f64, f64)],
    /// Relative tolerance per interval.
    relative: f64,
    /// Most bisection levels.
    max_depth: usize,
    /// Whether the cell's evaluation budget is spent.
    exhausted: &'a dyn Fn() -> bool,
    /// Set when an interval is accepted without meeting the tolerance.
    unconverged: &'a Cell<bool>,
}

impl Bisection<'_> {
    /// `∫_a^b f` to the relative tolerance, with the absolute floor `floor` for the interval.
    fn integrate(&self, f: &dyn Fn(f64) -> f64, a: f64, b: f64, floor: f64) -> f64 {
        let whole = gauss_legendre_on(self.rule, a, b, &mut |x| f(x));
        self.refine(f, a, b, whole, floor, 0)
    }

    /// Compares `whole` (the rule on `[a, b]`) with the rule on the two halves; keeps the
    /// halves if they agree, else refines each half with half the floor.
    fn refine(&self, f: &dyn Fn(f64) -> f64, a: f64, b: f64, whole: f64, floor: f64, depth: usize) -> f64 {
        let m = 0.5 * (a + b);
        let left = gauss_legendre_on(self.rule, a, m, &mut |x| f(x));
        let right = gauss_legendre_on(self.rule, m, b, &mut |x| f(x));
        let halves = left + right;
        if (halves - whole).abs() <= (self.relative * halves.abs()).max(floor) {
            return halves;
        }
        if depth + 1 >= self.max_depth || b - a <= MIN_WIDTH || (self.exhausted)() {
            self.unconverged.set(true);
            return halves;
        }
        self.refine(f, a, m, left, 0.5 * floor, depth + 1)
            + self.refine(f, m, b, right, 0.5 * floor, depth + 1)
    }
}

/// The outcome of [`ChiSquareTest::run`]: the statistic, the decision, and the tables a human
/// needs when it fails.
///
/// Tables are row-major: cell `(row, col)` is at `row * phi_res + col`, with row `i` covering
/// `cos θ ∈ [−1 + 2i/cos_theta_res, −1 + 2(i+1)/cos_theta_res)` and column `j` covering
/// `φ ∈ [2πj/phi_res, 2π(j+1)/phi_res)`.
#[derive(Clone, Debug)]
pub struct ChiSquareResult {
    /// Pearson's statistic after pooling.
    pub chi2: f64,
    /// Degrees of freedom: cells (after pooling) minus one.
    pub dof: usize,
    /// Probability of a statistic at least this large if the sampler matches the pdf,
    /// `Q(dof/2, χ²/2)`; NaN when `dof == 0`.
    pub p_value: f64,
    /// The Šidák-corrected threshold: the test fails if `p_value < threshold`.
    pub threshold: f64,
    /// Whether the test passed: `p_value ≥ threshold` and no problems (invalid samples,
    /// samples where the pdf is 0, samples in cells that expect none, negative or non-finite
    /// pdf values, a pdf integrating to more than the configured maximum).
    pub passed: bool,
    /// The family-wise significance level `α` that was asked for.
    pub significance: f64,
    /// The number of tests in the family (Šidák correction).
    pub test_count: usize,
    /// Number of cells in `cos θ`.
    pub cos_theta_res: usize,
    /// Number of cells in `φ`.
    pub phi_res: usize,
    /// Number of samples drawn (including rejected and invalid ones).
    pub sample_count: usize,
    /// The pooling threshold on expected counts.
    pub min_expected: f64,
    /// Observed counts per cell (row-major, see the type's docs).
    pub observed: Vec<u64>,
    /// Expected counts per cell: `sample_count · ∫_cell pdf dω`.
    pub expected: Vec<f64>,
    /// Number of samples the sampler rejected (`None`).
    pub rejected_observed: u64,
    /// Expected number of rejections, `sample_count · max(0, 1 − ∫ pdf dω)`.
    pub rejected_expected: f64,
    /// `∫ pdf dω` over the sphere, by quadrature.
    pub pdf_integral: f64,
    /// Number of pdf evaluations the quadrature made.
    pub pdf_evaluations: u64,
    /// The relative tolerance of the adaptive quadrature (0: the fixed rule was used).
    pub quadrature_tolerance: f64,
    /// Number of cells whose adaptive integration stopped at a limit before it converged
    /// (see [Adaptive quadrature](self#adaptive-quadrature)). Not a failure by itself, but
    /// their expected counts may be inaccurate; the report names a few.
    pub unconverged_cells: usize,
    /// `(row, col)` of the first few unconverged cells.
    pub unconverged_examples: Vec<(usize, usize)>,
    /// Number of table entries (cells, and the rejection cell) merged into the pool.
    pub pooled_cells: usize,
    /// Number of grid cells that observed samples but expect none (the quadrature found the
    /// pdf zero there). A failure.
    pub zero_expected_cells: usize,
    /// Number of samples that were not finite unit vectors (not binned).
    pub invalid_samples: u64,
    /// Number of samples where the pdf was `0` or not finite.
    pub zero_pdf_samples: u64,
    /// Number of quadrature points where the pdf was negative or not finite.
    pub bad_pdf_values: u64,
    /// Human-readable descriptions of the problems found (a few examples of each kind).
    pub problems: Vec<String>,
}

impl ChiSquareResult {
    /// The observed and expected counts of cell `(row, col)` (`cos θ` row, `φ` column).
    pub fn cell(&self, row: usize, col: usize) -> (u64, f64) {
        let i = row * self.phi_res + col;
        (self.observed[i], self.expected[i])
    }

    /// A text report: the verdict and statistics, the problems, the worst cells, and the
    /// observed, expected and residual `(o − e)/√e` tables, aggregated to at most 16 × 16
    /// blocks (rows from `cos θ = +1` at the top to `−1` at the bottom, columns in `φ`).
    /// [`ChiSquareResult::write_tables`] writes the tables at full resolution.
    pub fn report(&self) -> String {
        let mut out = String::new();
        self.write_summary(&mut out);
        let row_block = self.cos_theta_res.div_ceil(16);
        let col_block = self.phi_res.div_ceil(16);
        self.write_table(&mut out, TableKind::Observed, row_block, col_block);
        self.write_table(&mut out, TableKind::Expected, row_block, col_block);
        self.write_table(&mut out, TableKind::Residual, row_block, col_block);
        out
    }

    /// For tests: returns if the test passed; otherwise writes the tables under `dir`
    /// ([`write_tables`](Self::write_tables)) and panics with the report and where the tables
    /// are, which is what a human needs to see.
    ///
    /// # Panics
    /// If the test failed.
    pub fn assert_passed(&self, name: &str, dir: &Path) {
        if let Err(message) = self.check(name, dir) {
            panic!("{message}");
        }
    }

    /// [`assert_passed`](Self::assert_passed) without the panic, for a test that runs several
    /// configurations and reports every failure: `Ok` if the test passed; otherwise writes the
    /// tables under `dir` and returns the message that `assert_passed` panics with.
    pub fn check(&self, name: &str, dir: &Path) -> Result<(), String> {
        if self.passed {
            return Ok(());
        }
        let written = match self.write_tables(dir, name) {
            Ok(paths) => format!("tables written to {}", paths[0].display()),
            Err(err) => format!("could not write the tables: {err}"),
        };
        Err(format!("{name}: chi-square test failed ({written})\n{self}"))
    }

    /// Writes the report and the full-resolution tables under `dir` (created if needed):
    ///
    /// * `<name>.txt` — [`report`](Self::report) followed by the observed, expected and
    ///   residual tables at full resolution;
    /// * `<name>.csv` — one line per cell: indices, `cos θ` and `φ` ranges, observed, expected,
    ///   residual;
    /// * `<name>.ppm` — an image of three panels side by side, `φ` to the right and `cos θ`
    ///   upward: observed and expected counts on a common grey scale, and the residual
    ///   `(o − e)/√e` in red (more samples than expected) and blue (fewer), saturating at
    ///   ±5; cells that observe samples but expect none are green.
    ///
    /// Returns the paths written, the `.txt` first.
    pub fn write_tables(&self, dir: &Path, name: &str) -> io::Result<Vec<PathBuf>> {
        std::fs::create_dir_all(dir)?;
        let txt = dir.join(format!("{name}.txt"));
        let csv = dir.join(format!("{name}.csv"));
        let ppm = dir.join(format!("{name}.ppm"));

        let mut text = self.report();
        text.push_str("\nFull-resolution tables follow.\n");
        self.write_table(&mut text, TableKind::Observed, 1, 1);
        self.write_table(&mut text, TableKind::Expected, 1, 1);
        self.write_table(&mut text, TableKind::Residual, 1, 1);
        std::fs::write(&txt, text)?;

        let mut lines = String::from(
            "cos_theta_index,phi_index,cos_theta_min,cos_theta_max,phi_min,phi_max,\
             observed,expected,residual\n",
        );
        for row in 0..self.cos_theta_res {
            let (z0, z1) = self.cos_theta_range(row, 1);
            for col in 0..self.phi_res {
                let (p0, p1) = self.phi_range(col, 1);
                let (o, e) = self.cell(row, col);
                let _ = writeln!(lines, "{row},{col},{z0},{z1},{p0},{p1},{o},{e},{}", residual(o as f64, e));
            }
        }
        let _ = writeln!(
            lines,
            "rejected,,,,,,{},{},{}",
            self.rejected_observed,
            self.rejected_expected,
            residual(self.rejected_observed as f64, self.rejected_expected)
        );
        std::fs::write(&csv, lines)?;

        self.write_ppm(&ppm)?;
        Ok(vec![txt, csv, ppm])
    }

    fn write_summary(&self, out: &mut String) {
        let verdict = if self.passed { "PASSED" } else { "FAILED" };
        let _ = writeln!(out, "chi-square test {verdict}");
        let _ = writeln!(
            out,
            "  chi2 = {:.3}, dof = {}, p-value = {:.6e}, threshold = {:.6e} \
             (alpha = {}, Sidak-corrected over {} tests)",
            self.chi2, self.dof, self.p_value, self.threshold, self.significance, self.test_count
        );
        let _ = writeln!(
            out,
            "  samples: {} drawn, {} rejected (expected {:.1}), {} invalid, {} where pdf = 0",
            self.sample_count,
            self.rejected_observed,
            self.rejected_expected,
            self.invalid_samples,
            self.zero_pdf_samples
        );
        let _ = writeln!(
            out,
            "  integral of pdf over the sphere: {:.6}; grid {} (cos theta) x {} (phi); \
             {} cells pooled (expected < {}); {} cells observed samples but expected none",
            self.pdf_integral,
            self.cos_theta_res,
            self.phi_res,
            self.pooled_cells,
            self.min_expected,
            self.zero_expected_cells
        );
        if self.quadrature_tolerance > 0.0 {
            let _ = writeln!(
                out,
                "  quadrature: adaptive, relative tolerance {:e}, {} pdf evaluations, {} cells \
                 unconverged{}",
                self.quadrature_tolerance,
                self.pdf_evaluations,
                self.unconverged_cells,
                if self.unconverged_examples.is_empty() {
                    String::new()
                } else {
                    format!(
                        " (e.g. {:?}; their expected counts may be inaccurate)",
                        self.unconverged_examples
                    )
                }
            );
        } else {
            let _ = writeln!(out, "  quadrature: fixed rule, {} pdf evaluations", self.pdf_evaluations);
        }
        if !self.problems.is_empty() {
            let _ = writeln!(out, "  problems:");
            for problem in &self.problems {
                let _ = writeln!(out, "    - {problem}");
            }
        }

        // The cells that deviate most, in units of the expected standard deviation.
        let mut worst: Vec<(usize, f64)> = self
            .observed
            .iter()
            .zip(&self.expected)
            .enumerate()
            .filter(|&(_, (&o, &e))| o > 0 || e > 0.0)
            .map(|(i, (&o, &e))| (i, residual(o as f64, e)))
            .collect();
        worst.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        let _ = writeln!(out, "  largest deviations (o - e)/sqrt(e):");
        for &(i, r) in worst.iter().take(8) {
            let (row, col) = (i / self.phi_res, i % self.phi_res);
            let (z0, z1) = self.cos_theta_range(row, 1);
            let (p0, p1) = self.phi_range(col, 1);
            let _ = writeln!(
                out,
                "    cell ({row:>3}, {col:>3}): cos theta [{z0:+.4}, {z1:+.4}), \
                 phi [{:.2}, {:.2}) deg: observed {}, expected {:.2}, residual {r:+.2}",
                p0.to_degrees(),
                p1.to_degrees(),
                self.observed[i],
                self.expected[i]
            );
        }
    }

    /// Appends a table of `kind`, summing blocks of `row_block × col_block` cells, with
    /// `cos θ = +1` at the top.
    fn write_table(&self, out: &mut String, kind: TableKind, row_block: usize, col_block: usize) {
        let rows = self.cos_theta_res.div_ceil(row_block);
        let cols = self.phi_res.div_ceil(col_block);
        let title = match kind {
            TableKind::Observed => "observed counts",
            TableKind::Expected => "expected counts",
            TableKind::Residual => "residual (o - e)/sqrt(e)",
        };
        let _ = writeln!(
            out,
            "\n{title} ({rows} rows in cos theta, top = +1; {cols} columns in phi, \
             left = 0 deg; each entry sums {row_block} x {col_block} cells)"
        );
        let _ = write!(out, "{:>17}", "cos theta \\ phi");
        for c in 0..cols {
            let (p0, _) = self.phi_range(c, col_block);
            let _ = write!(out, " {:>9.1}", p0.to_degrees());
        }
        let _ = writeln!(out);
        for r in (0..rows).rev() {
            let (z0, z1) = self.cos_theta_range(r, row_block);
            let _ = write!(out, "[{z0:+.3},{z1:+.3})");
            for c in 0..cols {
                let (mut o, mut e) = (0.0, 0.0);
                for row in r * row_block..((r + 1) * row_block).min(self.cos_theta_res) {
                    for col in c * col_block..((c + 1) * col_block).min(self.phi_res) {
                        let (co, ce) = self.cell(row, col);
                        o += co as f64;
                        e += ce;
                    }
                }
                let _ = match kind {
                    TableKind::Observed => write!(out, " {o:>9.0}"),
                    TableKind::Expected => write!(out, " {e:>9.1}"),
                    TableKind::Residual => write!(out, " {:>+9.2}", residual(o, e)),
                };
            }
            let _ = writeln!(out);
        }
    }

    /// `[cos θ₀, cos θ₁)` of block `index` of `block` rows.
    fn cos_theta_range(&self, index: usize, block: usize) -> (f64, f64) {
        let dz = 2.0 / self.cos_theta_res as f64;
        let z0 = -1.0 + (index * block) as f64 * dz;
        let z1 = (-1.0 + ((index + 1) * block) as f64 * dz).min(1.0);
        (z0, z1)
    }

    /// `[φ₀, φ₁)` in radians of block `index` of `block` columns.
    fn phi_range(&self, index: usize, block: usize) -> (f64, f64) {
        let dphi = TAU / self.phi_res as f64;
        let p0 = (index * block) as f64 * dphi;
        let p1 = (((index + 1) * block) as f64 * dphi).min(TAU);
        (p0, p1)
    }

    /// The three-panel image described in [`write_tables`](Self::write_tables).
    fn write_ppm(&self, path: &Path) -> io::Result<()> {
        let scale = (512 / self.phi_res).max(1);
        let gap = 4;
        let panel_w = self.phi_res * scale;
        let height = self.cos_theta_res * scale;
        let width = 3 * panel_w + 2 * gap;
        let max_count = self
            .observed
            .iter()
            .map(|&o| o as f64)
            .chain(self.expected.iter().copied())
            .fold(0.0_f64, f64::max)
            .max(1.0);
        let grey = |v: f64| -> [u8; 3] {
            let g = (255.0 * (v / max_count).clamp(0.0, 1.0)).round() as u8;
            [g, g, g]
        };

        let mut pixels = vec![255_u8; width * height * 3];
        for y in 0..height {
            let row = self.cos_theta_res - 1 - y / scale; // cos θ = +1 at the top
            for x in 0..panel_w {
                let col = x / scale;
                let (o, e) = self.cell(row, col);
                let o = o as f64;
                let residual_rgb = if e <= 0.0 && o > 0.0 {
                    [0, 255, 0]
                } else {
                    let r = (residual(o, e) / 5.0).clamp(-1.0, 1.0);
                    let red = (255.0 * r.max(0.0)).round() as u8;
                    let blue = (255.0 * (-r).max(0.0)).round() as u8;
                    [red, 0, blue]
                };
                for (panel, rgb) in [grey(o), grey(e), residual_rgb].into_iter().enumerate() {
                    let px = panel * (panel_w + gap) + x;
                    let at = (y * width + px) * 3;
                    pixels[at..at + 3].copy_from_slice(&rgb);
                }
            }
        }
        let mut file = io::BufWriter::new(std::fs::File::create(path)?);
        write!(file, "P6\n{width} {height}\n255\n")?;
        file.write_all(&pixels)?;
        file.flush()
    }
}

impl fmt::Display for ChiSquareResult {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.report())
    }
}

/// Which table [`ChiSquareResult::write_table`] prints.
#[derive(Clone, Copy)]
enum TableKind {
    Observed,
    Expected,
    Residual,
}

/// `(o − e)/√e`, the signed contribution of a cell in units of its expected standard
/// deviation; `±∞` when `e = 0` and `o > 0`, `0` when both are `0`.
fn residual(o: f64, e: f64) -> f64 {
    if e > 0.0 {
        (o - e) / e.sqrt()
    } else if o > 0.0 {
        f64::INFINITY
    } else {
        0.0
    }
}

/// Pearson's statistic of a table after pooling.
#[derive(Debug, PartialEq)]
struct Pearson {
    /// `Σ (o − e)² / e` over the terms.
    chi2: f64,
    /// Number of terms: unpooled cells plus one for the pool, if any.
    terms: usize,
    /// Number of cells merged into the pool.
    pooled_cells: usize,
}

/// Pearson's `χ²` of `(observed, expected)` pairs, pooling small cells (pbrt's scheme): cells
/// are visited by increasing expected count; cells with `o = e = 0` are skipped; a cell
/// expecting less than `min_expected` joins the pool, and so do further cells while the pool
/// expects less than `min_expected`; the pool is one more term. A pool that expects nothing
/// but observes samples gives `χ² = ∞`.
fn pooled_chi_square(table: &[(f64, f64)], min_expected: f64) -> Pearson {
    let mut sorted: Vec<(f64, f64)> = table.iter().copied().filter(|&(o, e)| o > 0.0 || e > 0.0).collect();
    sorted.sort_by(|a, b| a.1.total_cmp(&b.1));

    let (mut chi2, mut terms, mut pooled_cells) = (0.0, 0, 0);
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for (o, e) in sorted {
        if e < min_expected || (pooled_cells > 0 && pool_e < min_expected) {
            pool_o += o;
            pool_e += e;
            pooled_cells += 1;
        } else {
            chi2 += (o - e) * (o - e) / e;
            terms += 1;
        }
    }
    if pooled_cells > 0 {
        chi2 += if pool_e > 0.0 { (pool_o - pool_e) * (pool_o - pool_e) / pool_e } else { f64::INFINITY };
        terms += 1;
    }
    Pearson { chi2, terms, pooled_cells }
}

/// The Šidák-corrected per-test significance level for a family of `test_count` independent
/// tests with family-wise level `alpha`: `1 − (1 − α)^(1/n)`, computed as
/// `−expm1(ln1p(−α) / n)` to keep precision for small `α`.
pub fn sidak_threshold(alpha: f64, test_count: usize) -> f64 {
    -((-alpha).ln_1p() / test_count as f64).exp_m1()
}

/// The p-value of a chi-square statistic: `P[X ≥ chi2]` for `X ~ χ²(dof)`, which is the
/// regularized upper incomplete gamma function `Q(dof/2, chi2/2)`.
///
/// NaN for `dof = 0`; `1` for `chi2 ≤ 0`; `0` for `chi2 = ∞`.
pub fn chi_square_p_value(chi2: f64, dof: usize) -> f64 {
    if dof == 0 {
        return f64::NAN;
    }
    regularized_gamma_q(0.5 * dof as f64, 0.5 * chi2)
}

/// The regularized upper incomplete gamma function `Q(a, x) = Γ(a, x) / Γ(a)`, in `f64`.
///
/// Numerical Recipes (Press et al., 3rd ed., §6.2): for `x < a + 1` the series
/// `P(a, x) = e^{−x} x^a / Γ(a) · Σₙ xⁿ / (a (a+1) ⋯ (a+n))` and `Q = 1 − P` (here `P ≲ ½`, so
/// the subtraction loses nothing); otherwise the continued fraction
/// `Q(a, x) = e^{−x} x^a / Γ(a) · 1/(x + 1 − a − 1·(1 − a)/(x + 3 − a − 2·(2 − a)/(x + 5 − a − ⋯)))`
/// by the modified Lentz method. Both need `O(√a)` iterations; the limit is generous (10⁵) so
/// that `a` of several thousand (histograms with thousands of cells) converges to a relative
/// `1e-15`. `ln Γ` is [`ln_gamma`].
///
/// Returns NaN for `a ≤ 0` or NaN input, `1` for `x ≤ 0`, `0` for `x = ∞`.
pub fn regularized_gamma_q(a: f64, x: f64) -> f64 {
    const EPS: f64 = 1e-16;
    const TINY: f64 = 1e-300;
    const MAX_ITER: usize = 100_000;
    if a.is_nan() || x.is_nan() || a <= 0.0 {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 1.0;
    }
    if x == f64::INFINITY {
        return 0.0;
    }
    // e^{−x} x^a / Γ(a), in logarithms.
    let prefactor = (-x + a * x.ln() - ln_gamma(a)).exp();
    if x < a + 1.0 {
        let mut term = 1.0 / a;
        let mut sum = term;
        let mut ap = a;
        for _ in 0..MAX_ITER {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * EPS {
                break;
            }
        }
        1.0 - sum * prefactor
    } else {
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / TINY;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..MAX_ITER {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < TINY {
                d = TINY;
            }
            c = b + an / c;
            if c.abs() < TINY {
                c = TINY;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < EPS {
                break;
            }
        }
        prefactor * h
    }
}

/// `ln Γ(x)` for `x > 0`: the Lanczos approximation with `g = 7` and nine coefficients
/// (relative error about `1e-15`), with the reflection `Γ(x) Γ(1 − x) = π / sin(πx)` for
/// `x < ½`.
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const COEFFICIENTS: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut series = COEFFICIENTS[0];
    for (i, &c) in COEFFICIENTS.iter().enumerate().skip(1) {
        series += c / (x + i as f64);
    }
    let t = x + G + 0.5;
    0.5 * TAU.ln() + (x + 0.5) * t.ln() - t + series.ln()
}

/// Nodes and weights of the `n`-point Gauss–Legendre rule on `[−1, 1]` (exact for polynomials
/// of degree `≤ 2n − 1`), by Newton's method on `Pₙ` from the Tricomi initial guesses.
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            for _ in 0..100 {
                let (p, dp) = legendre(n, x);
                let dx = p / dp;
                x -= dx;
                if dx.abs() < 1e-15 {
                    break;
                }
            }
            let (_, dp) = legendre(n, x);
            (x, 2.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

/// `(Pₙ(x), Pₙ'(x))` by the three-term recurrence
/// `k Pₖ = (2k − 1) x Pₖ₋₁ − (k − 1) Pₖ₋₂` and `Pₙ' = n (x Pₙ − Pₙ₋₁) / (x² − 1)`.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut prev, mut p) = (1.0, x);
    for k in 2..=n {
        let k = k as f64;
        let next = ((2.0 * k - 1.0) * x * p - (k - 1.0) * prev) / k;
        prev = p;
        p = next;
    }
    if n == 0 {
        return (1.0, 0.0);
    }
    (p, n as f64 * (x * p - prev) / (x * x - 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use furnace_sampling::warp::{
        cosine_hemisphere_pdf, square_to_cosine_hemisphere, square_to_uniform_hemisphere,
        uniform_hemisphere_pdf,
    };
    use std::f32::consts::FRAC_1_PI;

    /// Number of statistical tests in this module that are expected to pass; the Šidák
    /// correction keeps the family-wise false-failure rate at 1%.
    const PASSING_TESTS: usize = 5;

    fn harness(seed: u32) -> ChiSquareTest {
        ChiSquareTest { seed, test_count: PASSING_TESTS, ..ChiSquareTest::default() }
    }

    /// Uniform on the whole sphere: `z = 1 − 2u.x`, `φ = 2π·u.y`; pdf `1/(4π)`.
    fn square_to_uniform_sphere(u: Vec2) -> Vec3 {
        let z = 1.0 - 2.0 * u.x;
        let r = ((1.0 - z) * (1.0 + z)).max(0.0).sqrt();
        let (sin, cos) = (std::f32::consts::TAU * u.y).sin_cos();
        Vec3::new(r * cos, r * sin, z)
    }

    fn uniform_sphere_pdf(_: Vec3) -> f32 {
        0.25 * FRAC_1_PI
    }

    #[test]
    fn passes_cosine_hemisphere() {
        let result = harness(1).run(|u, _| Some(square_to_cosine_hemisphere(u)), cosine_hemisphere_pdf);
        assert!(result.passed, "{result}");
        assert!((result.pdf_integral - 1.0).abs() < 1e-6, "{result}");
    }

    #[test]
    fn passes_uniform_hemisphere() {
        let result = harness(2).run(|u, _| Some(square_to_uniform_hemisphere(u)), uniform_hemisphere_pdf);
        assert!(result.passed, "{result}");
    }

    #[test]
    fn passes_uniform_sphere() {
        let result = harness(3).run(|u, _| Some(square_to_uniform_sphere(u)), uniform_sphere_pdf);
        assert!(result.passed, "{result}");
        // Every cell expects the same count (≈ 122), far above the pooling threshold; only the
        // rejection cell, which expects `n·(1 − ∫pdf)` ≈ 0 up to `f32` rounding, may be pooled
        // (together with one grid cell).
        assert!(result.pooled_cells <= 2, "{result}");
        assert!(result.dof >= 64 * 128 - 1, "{result}");
    }

    /// A sampler that rejects 30% of its samples (chosen by `uc`) with a pdf that integrates
    /// to 0.7 passes; the same sampler with the full pdf fails on the missing mass.
    #[test]
    fn rejection_is_missing_mass() {
        let sample = |u: Vec2, uc: f32| (uc >= 0.3).then(|| square_to_cosine_hemisphere(u));
        let result = harness(4).run(sample, |w| 0.7 * cosine_hemisphere_pdf(w));
        assert!(result.passed, "{result}");
        assert!((result.rejected_expected - 300_000.0).abs() < 1.0, "{result}");

        let result = harness(4).run(sample, cosine_hemisphere_pdf);
        assert!(!result.passed, "missing mass not detected:\n{result}");
    }

    /// Proof that the harness can fail: cosine-distributed samples against the uniform
    /// hemisphere pdf.
    #[test]
    fn fails_wrong_pdf() {
        let result = harness(5).run(|u, _| Some(square_to_cosine_hemisphere(u)), uniform_hemisphere_pdf);
        assert!(!result.passed, "{result}");
        assert!(result.p_value < result.threshold, "{result}");
        assert_eq!(result.zero_pdf_samples, 0);
        assert!(result.problems.is_empty(), "{:?}", result.problems);
    }

    /// A subtler error: uniform hemisphere samples against a pdf 5% too high near the pole and
    /// correspondingly lower elsewhere (`(1 + 0.1 (z − ½)) / (2π)` still integrates to one).
    #[test]
    fn fails_slightly_wrong_pdf() {
        let result = harness(6).run(
            |u, _| Some(square_to_uniform_hemisphere(u)),
            |w| uniform_hemisphere_pdf(w) * (1.0 + 0.1 * (w.z - 0.5)),
        );
        assert!((result.pdf_integral - 1.0).abs() < 1e-6, "{result}");
        assert!(!result.passed, "{result}");
    }

    /// Samples landing where the pdf is zero fail by themselves: uniform sphere samples
    /// against the hemisphere pdf, and a single stray sample among correct ones.
    #[test]
    fn flags_samples_where_pdf_is_zero() {
        let result = harness(7).run(|u, _| Some(square_to_uniform_sphere(u)), uniform_hemisphere_pdf);
        assert!(!result.passed);
        assert!(result.zero_pdf_samples > 400_000, "{result}");

        let mut calls = 0;
        let result = harness(8).run(
            |u, _| {
                calls += 1;
                Some(if calls == 1000 { -Vec3::Z } else { square_to_cosine_hemisphere(u) })
            },
            cosine_hemisphere_pdf,
        );
        assert!(!result.passed, "{result}");
        assert_eq!(result.zero_pdf_samples, 1, "{result}");
        assert!(result.problems.iter().any(|p| p.contains("pdf = 0")), "{result}");
    }

    /// Samples in a cell whose integrated pdf is zero fail: the pdf is positive only exactly
    /// at the pole, where no quadrature node lies.
    #[test]
    fn flags_samples_in_cells_expecting_none() {
        let test = ChiSquareTest { sample_count: 10_000, ..ChiSquareTest::default() };
        let result = test.run(|_, _| Some(Vec3::Z), |w| if w.z >= 1.0 { 1.0 } else { 0.0 });
        assert!(!result.passed);
        assert_eq!(result.zero_pdf_samples, 0, "{result}");
        assert_eq!(result.zero_expected_cells, 1, "{result}");
    }

    /// A pdf 0.2% too large everywhere is nearly invisible to the statistic but fails the
    /// integral check.
    #[test]
    fn flags_pdf_integrating_to_more_than_one() {
        let result = harness(9)
            .run(|u, _| Some(square_to_uniform_hemisphere(u)), |w| 1.002 * uniform_hemisphere_pdf(w));
        assert!(!result.passed);
        assert!((result.pdf_integral - 1.002).abs() < 1e-6, "{result}");
        assert!(result.p_value >= result.threshold, "{result}");
        assert!(result.problems.iter().any(|p| p.contains("integrates")), "{result}");
    }

    /// Non-unit or non-finite samples and a negative pdf are failures.
    #[test]
    fn flags_invalid_samples_and_pdfs() {
        let small = ChiSquareTest { sample_count: 10_000, ..ChiSquareTest::default() };
        let result = small.run(|u, _| Some(2.0 * square_to_cosine_hemisphere(u)), cosine_hemisphere_pdf);
        assert!(!result.passed);
        assert_eq!(result.invalid_samples, 10_000);

        let result = small.run(|_, _| Some(Vec3::NAN), cosine_hemisphere_pdf);
        assert!(!result.passed);
        assert_eq!(result.invalid_samples, 10_000);

        let result =
            small.run(|u, _| Some(square_to_cosine_hemisphere(u)), |w| cosine_hemisphere_pdf(w) - 0.001);
        assert!(!result.passed);
        assert!(result.bad_pdf_values > 0);
    }

    /// A von Mises–Fisher lobe `κ/(2π(1 − e^{−2κ}))·exp(−κ(1 − μ·ω))` of concentration
    /// `κ` about the unit `mu`, and its exact sampler: in the frame of `mu`,
    /// `1 − cos θ = −ln(1 − ξ₀(1 − e^{−2κ}))/κ`, `φ = 2π ξ₁`. Evaluated in f64 from `‖ω − μ‖²/2
    /// = 1 − μ·ω` (no cancellation), so that its own rounding stays far below the tolerances.
    struct VonMisesFisher {
        kappa: f64,
        mu: [f64; 3],
    }

    impl VonMisesFisher {
        fn new(kappa: f64, z: f64, phi: f64) -> Self {
            let r = (1.0 - z * z).sqrt();
            Self { kappa, mu: [r * phi.cos(), r * phi.sin(), z] }
        }

        fn pdf(&self, w: Vec3) -> f32 {
            let w = [f64::from(w.x), f64::from(w.y), f64::from(w.z)];
            let len = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
            let d2: f64 = (0..3).map(|i| (w[i] / len - self.mu[i]).powi(2)).sum();
            let k = self.kappa;
            (k / (TAU * -(-2.0 * k).exp_m1()) * (-k * 0.5 * d2).exp()) as f32
        }

        fn sample(&self, u: Vec2) -> Vec3 {
            let k = self.kappa;
            let one_minus_cos = -(-f64::from(u.x) * -(-2.0 * k).exp_m1()).ln_1p() / k;
            let cos = 1.0 - one_minus_cos;
            let sin = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0).sqrt();
            let phi = TAU * f64::from(u.y);
            // An orthonormal frame (t, b, μ).
            let [x, y, z] = self.mu;
            let (t, b) = {
                let t = if z.abs() < 0.9 { [y, -x, 0.0] } else { [0.0, z, -y] };
                let n = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
                let t = [t[0] / n, t[1] / n, t[2] / n];
                (t, [y * t[2] - z * t[1], z * t[0] - x * t[2], x * t[1] - y * t[0]])
            };
            let (sp, cp) = phi.sin_cos();
            let w: Vec<f64> = (0..3).map(|i| sin * cp * t[i] + sin * sp * b[i] + cos * self.mu[i]).collect();
            Vec3::new(w[0] as f32, w[1] as f32, w[2] as f32)
        }
    }

    /// A lobe far narrower than a cell (κ = 2·10⁴: about 0.4° wide, in a cell of 1.8° × 2.8°),
    /// centred off the grid lines: the adaptive quadrature integrates it to 1 and the test
    /// passes; the fixed rule (quadrature_tolerance = 0) gets the expected counts wrong and
    /// the same samples fail.
    #[test]
    fn adaptive_quadrature_resolves_a_sharp_lobe() {
        let lobe = VonMisesFisher::new(2e4, 0.3, 1.0);
        let result = harness(10).run(|u, _| Some(lobe.sample(u)), |w| lobe.pdf(w));
        assert!(result.passed, "{result}");
        assert_eq!(result.unconverged_cells, 0, "{result}");
        assert!((result.pdf_integral - 1.0).abs() < 1e-5, "{result}");

        let fixed = ChiSquareTest { quadrature_tolerance: 0.0, ..harness(10) };
        let result = fixed.run(|u, _| Some(lobe.sample(u)), |w| lobe.pdf(w));
        assert!(!result.passed, "{result}");
        assert!((result.pdf_integral - 1.0).abs() > 1e-3, "{result}");
    }

    /// `integrate_pdf` by itself: exact for the uniform sphere, and a pdf that is pure noise
    /// (so that no tolerance is met) exhausts the evaluation budget and is reported as
    /// unconverged, cheaply.
    #[test]
    fn integrate_pdf_reports_convergence() {
        let test = ChiSquareTest::default();
        let uniform = test.integrate_pdf(uniform_sphere_pdf);
        assert!((uniform.total - 1.0).abs() < 1e-6, "{}", uniform.total);
        assert_eq!(uniform.unconverged_cells, 0);
        assert_eq!(uniform.cells.len(), 64 * 128);

        let small = ChiSquareTest { cos_theta_res: 2, phi_res: 2, max_cell_evaluations: 20_000, ..test };
        let noise = |w: Vec3| {
            (furnace_sampling::hash::pcg_hash(w.x.to_bits() ^ w.y.to_bits().rotate_left(16) ^ w.z.to_bits())
                >> 8) as f32
                / (1 << 24) as f32
        };
        let noisy = small.integrate_pdf(noise);
        assert_eq!(noisy.unconverged_cells, 4, "{noisy:?}");
        assert!(noisy.evaluations < 4 * 21_000, "{}", noisy.evaluations);
        assert!((noisy.total / (4.0 * PI) - 0.5).abs() < 0.05, "{}", noisy.total);
    }

    /// The failure output: report and files contain the tables.
    #[test]
    fn writes_tables() {
        let test =
            ChiSquareTest { cos_theta_res: 8, phi_res: 16, sample_count: 20_000, ..ChiSquareTest::default() };
        let result = test.run(|u, _| Some(square_to_cosine_hemisphere(u)), uniform_hemisphere_pdf);
        let report = result.report();
        assert!(report.contains("FAILED") && report.contains("expected counts"));
        assert!(report.contains("observed counts") && report.contains("residual"));

        let dir = std::env::temp_dir().join(format!("furnace-chi2-test-{}", std::process::id()));
        let paths = result.write_tables(&dir, "cosine_vs_uniform").expect("write tables");
        assert_eq!(paths.len(), 3);
        let text = std::fs::read_to_string(&paths[0]).unwrap();
        assert!(text.contains("Full-resolution"));
        let csv = std::fs::read_to_string(&paths[1]).unwrap();
        assert_eq!(csv.lines().count(), 1 + 8 * 16 + 1);
        let ppm = std::fs::read(&paths[2]).unwrap();
        assert!(ppm.starts_with(b"P6\n"));
        let header = b"P6\n1544 256\n255\n";
        // 16 φ cells × 32 px per panel, three panels and two 4 px gaps; 8 rows × 32 px.
        assert_eq!(&ppm[..header.len()], header);
        assert_eq!(ppm.len(), header.len() + 1544 * 256 * 3);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn pooling() {
        // Nothing to pool: χ² = Σ (o − e)²/e, one term per cell.
        let p = pooled_chi_square(&[(10.0, 12.0), (14.0, 12.0), (0.0, 0.0)], 5.0);
        assert_eq!(p.terms, 2);
        assert_eq!(p.pooled_cells, 0);
        assert!((p.chi2 - (4.0 / 12.0 + 4.0 / 12.0)).abs() < 1e-12);

        // Three small cells (1 + 2 + 1 = 4 < 5 expected) pull in the next-smallest (6) too.
        let table = [(2.0, 1.0), (0.0, 2.0), (3.0, 1.0), (7.0, 6.0), (50.0, 40.0)];
        let p = pooled_chi_square(&table, 5.0);
        assert_eq!(p.pooled_cells, 4);
        assert_eq!(p.terms, 2);
        let expected = (12.0_f64 - 10.0).powi(2) / 10.0 + (10.0_f64).powi(2) / 40.0;
        assert!((p.chi2 - expected).abs() < 1e-12, "{p:?}");

        // Samples where nothing is expected are pooled with the next cells until the pool
        // expects enough...
        let p = pooled_chi_square(&[(1.0, 0.0), (10.0, 10.0)], 5.0);
        assert_eq!((p.terms, p.pooled_cells), (1, 2));
        assert!((p.chi2 - 0.1).abs() < 1e-12, "{p:?}");
        // ...and if nothing expects anything, the pool's χ² is infinite.
        let p = pooled_chi_square(&[(1.0, 0.0), (3.0, 0.0)], 5.0);
        assert_eq!(p.chi2, f64::INFINITY);
    }

    #[test]
    fn sidak() {
        assert!((sidak_threshold(0.01, 1) - 0.01).abs() < 1e-15);
        // 1 − 0.99^(1/3)
        assert!((sidak_threshold(0.01, 3) - 0.003_344_506_587_403_636).abs() < 1e-15);
    }

    #[test]
    fn ln_gamma_known_values() {
        // Reference values from mpmath (30 digits).
        let cases = [
            (1.0, 0.0),
            (2.0, 0.0),
            (0.5, 0.572_364_942_924_700_1), // ln √π
            (3.5, 1.200_973_602_347_074_2),
            (1e-3, 6.907_178_885_383_853),
            (100.0, 359.134_205_369_575_4),
            (1000.0, 5_905.220_423_209_181),
            (4000.0, 29_172.970_494_954_6),
        ];
        for (x, want) in cases {
            let got = ln_gamma(x);
            assert!((got - want).abs() <= 1e-13 * want.abs().max(1.0), "ln Γ({x}) = {got}, want {want}");
        }
        // Γ(n) = (n − 1)!
        let mut factorial = 1.0_f64;
        for n in 1..30 {
            let got = ln_gamma(n as f64);
            assert!((got - factorial.ln()).abs() < 1e-12, "ln Γ({n})");
            factorial *= n as f64;
        }
    }

    /// The p-value against chi-square tables (the 5% critical values) and mpmath.
    #[test]
    fn p_values() {
        let cases = [
            // Critical values at 5%, as printed in tables (3 decimals) and exactly.
            (1, 3.841, 0.050_013_683_763_956_7),
            (10, 18.307, 0.050_000_589_091_398_12),
            (100, 124.342, 0.050_000_715_769_971_77),
            (1, 3.841_458_820_694_124, 0.05),
            (10, 18.307_038_053_275_146, 0.05),
            (100, 124.342_113_404_004_07, 0.05),
            // Both branches and the tails.
            (3, 0.5, 0.918_891_411_654_675_9),
            (7, 2.0, 0.959_840_368_730_101_6),
            (1, 1e-6, 0.999_202_115_572_177_9),
            (2, 40.0, 2.061_153_622_438_558e-9),
            (50, 150.0, 6.315_223_256_933_987e-12),
            (1, 100.0, 1.523_970_604_832_105e-23),
            // Thousands of degrees of freedom (histograms of thousands of cells).
            (8000, 8000.0, 0.497_897_386_646_320_6),
            (8000, 8300.0, 0.009_438_573_702_676_664),
            (4000, 3700.0, 0.999_702_983_804_675_6),
        ];
        for (dof, x, want) in cases {
            let got = chi_square_p_value(x, dof);
            assert!((got - want).abs() <= 1e-10 * want, "Q({dof}/2, {x}/2) = {got}, want {want}");
        }
        assert_eq!(chi_square_p_value(0.0, 5), 1.0);
        assert_eq!(chi_square_p_value(f64::INFINITY, 5), 0.0);
        assert!(chi_square_p_value(1.0, 0).is_nan());
    }

    /// Even degrees of freedom have the closed form `Q(k, y) = e^{−y} Σ_{i<k} yⁱ/i!` (the
    /// Poisson tail), evaluated here in logarithms independently of [`ln_gamma`].
    #[test]
    fn p_values_match_poisson_sums() {
        for k in [1_usize, 2, 5, 20, 100, 500] {
            for y in [0.1, 1.0, 0.5 * k as f64, k as f64, 1.5 * k as f64 + 10.0] {
                let mut ln_factorial = 0.0;
                let mut sum = 0.0;
                for i in 0..k {
                    if i > 0 {
                        ln_factorial += (i as f64).ln();
                    }
                    sum += (-y + i as f64 * f64::ln(y) - ln_factorial).exp();
                }
                let got = chi_square_p_value(2.0 * y, 2 * k);
                assert!(
                    (got - sum).abs() <= 1e-11 * sum.max(1e-300),
                    "Q({k}, {y}) = {got}, Poisson sum {sum}"
                );
            }
        }
    }

    /// The Gauss–Legendre rule integrates `xᵐ` exactly for `m ≤ 2n − 1`.
    #[test]
    fn gauss_legendre_is_exact_for_polynomials() {
        for n in 1..=12 {
            let rule = gauss_legendre(n);
            for m in 0..2 * n {
                let got: f64 = rule.iter().map(|&(x, w)| w * x.powi(m as i32)).sum();
                let want = if m % 2 == 0 { 2.0 / (m as f64 + 1.0) } else { 0.0 };
                assert!((got - want).abs() < 1e-13, "n = {n}, x^{m}: {got} vs {want}");
            }
        }
    }
}
