//! Convergence: RMSE of a smooth and a discontinuous 2-D integral against the sample count,
//! over 256 independent pixels, and the fitted log-log slope per sampler.
//!
//! N = 4, 8, …, 4096 (powers of two, where the progressive samplers are best balanced); the
//! fixed-N samplers (Hammersley, CMJ) are built for each N. Seeds are fixed, so the slopes are
//! deterministic; the bounds are those of the issue:
//!
//! * random: −0.5 ± 0.05 on both integrands (the Monte Carlo rate; with 256 pixels the RMSE at
//!   each N has ~4.4% relative noise, which moves the fitted slope by ~±0.01);
//! * CMJ, PMJ02, Owen-Sobol: ≤ −0.70 on the disk (theory: −0.75 for a smooth-edged
//!   discontinuity under 2-D stratification);
//! * Owen-Sobol (and PMJ02, the same distribution): ≤ −1.2 on the smooth function (theory:
//!   −1.5 for scrambled nets).
//!
//! The full table is written to `target/test-output/sampling/convergence.md` on every run.

use crate::common;
use common::*;
use furnace_sampling::{AnySampler, SamplerKind};

const PIXELS: u32 = 256;
const SEED: u32 = 2024;

struct Curve {
    kind: SamplerKind,
    dim: u32,
    smooth: Vec<f64>,
    disk: Vec<f64>,
}

fn measure(kind: SamplerKind, dim: u32, counts: &[u32]) -> Curve {
    let mut c = Curve { kind, dim, smooth: vec![], disk: vec![] };
    for &n in counts {
        let s = AnySampler::new(kind, SEED, Some(n)).unwrap();
        c.smooth.push(rmse(&estimates(&s, smooth, PIXELS, 0, n, dim), SMOOTH_INTEGRAL));
        c.disk.push(rmse(&estimates(&s, disk, PIXELS, 0, n, dim), DISK_INTEGRAL));
    }
    c
}

#[test]
fn convergence_slopes() {
    let counts: Vec<u32> = (2..=12).map(|k| 1u32 << k).collect();
    let xs: Vec<f64> = counts.iter().map(|&n| n as f64).collect();
    // Dimensions (0,1) and (4,5): the first pair, and one that exercises each sampler's
    // decorrelation of higher dimensions (Owen-Sobol's second group, PMJ02's third pair).
    let curves: Vec<Curve> =
        SamplerKind::ALL.iter().flat_map(|&k| [0, 4].map(|dim| measure(k, dim, &counts))).collect();

    let mut header = vec!["sampler", "dims", "integrand"];
    let labels: Vec<String> = counts.iter().map(|n| format!("N={n}")).collect();
    header.extend(labels.iter().map(String::as_str));
    header.push("slope");
    let mut rows = vec![];
    let mut failures = vec![];
    for c in &curves {
        for (name, errs) in [("smooth", &c.smooth), ("disk", &c.disk)] {
            let slope = loglog_slope(&xs, errs);
            let mut row = vec![c.kind.to_string(), format!("{},{}", c.dim, c.dim + 1), name.into()];
            row.extend(errs.iter().map(|e| format!("{e:.2e}")));
            row.push(format!("{slope:.3}"));
            rows.push(row);
            let bound_ok = match (c.kind, name) {
                (SamplerKind::Random, _) => (slope + 0.5).abs() <= 0.05,
                (SamplerKind::Cmj | SamplerKind::Pmj02 | SamplerKind::Sobol, "disk") => slope <= -0.70,
                (SamplerKind::Pmj02 | SamplerKind::Sobol, "smooth") => slope <= -1.2,
                _ => true, // Hammersley and CMJ-smooth: measured and reported, no bound set.
            };
            if !bound_ok {
                failures.push(format!("{} dims {},{} {name}: slope {slope:.3}", c.kind, c.dim, c.dim + 1));
            }
        }
    }
    let text = table(&header, &rows);
    let path = write_output("convergence.md", &text);
    println!("{text}\n(written to {})", path.display());
    assert!(failures.is_empty(), "slopes out of bounds: {failures:?}\n{text}\n(table in {})", path.display());
}

/// Dimensions taken from *different* pairs or groups must be decorrelated, or a path tracer's
/// bounces become correlated (biased per pixel, error that stops falling). Integrates the
/// smooth function of two coordinates from different pairs — (0,2), (1,3), (0,4), (3,6) — and
/// requires at least the Monte Carlo rate: slope ≤ −0.45 (−0.5 with the ±0.05 allowance used
/// for random sampling above). With correlated padding (e.g. PMJ02 without its per-pair index
/// shuffle) the slope is ≈ 0.
#[test]
fn dimensions_across_pairs_are_decorrelated() {
    let counts: Vec<u32> = (2..=12).map(|k| 1u32 << k).collect();
    let xs: Vec<f64> = counts.iter().map(|&n| n as f64).collect();
    let mut rows = vec![];
    let mut failures = vec![];
    for kind in SamplerKind::ALL {
        for (a, b) in [(0u32, 2u32), (1, 3), (0, 4), (3, 6)] {
            let errs: Vec<f64> = counts
                .iter()
                .map(|&n| {
                    let s = AnySampler::new(kind, SEED, Some(n)).unwrap();
                    let est: Vec<f64> = (0..PIXELS)
                        .map(|p| {
                            let sum: f64 = (0..n)
                                .map(|i| smooth(s.value(p, i, a) as f64, s.value(p, i, b) as f64))
                                .sum();
                            sum / n as f64
                        })
                        .collect();
                    rmse(&est, SMOOTH_INTEGRAL)
                })
                .collect();
            let slope = loglog_slope(&xs, &errs);
            let mut row = vec![kind.to_string(), format!("{a},{b}")];
            row.extend(errs.iter().map(|e| format!("{e:.2e}")));
            row.push(format!("{slope:.3}"));
            rows.push(row);
            if slope > -0.45 {
                failures.push(format!("{kind} dims ({a},{b}): slope {slope:.3}"));
            }
        }
    }
    let mut header = vec!["sampler", "dims"];
    let labels: Vec<String> = counts.iter().map(|n| format!("N={n}")).collect();
    header.extend(labels.iter().map(String::as_str));
    header.push("slope");
    let text = table(&header, &rows);
    let path = write_output("cross_pairs.md", &text);
    println!("{text}\n(written to {})", path.display());
    assert!(failures.is_empty(), "correlated dimensions: {failures:?}\n{text}");
}

use furnace_sampling::Sampler as _;
