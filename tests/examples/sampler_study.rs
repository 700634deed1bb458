//! Which sampler should be the default? Error against the Mitsuba reference versus samples per
//! pixel on the Cornell box, for every `SamplerKind`.
//!
//! ```sh
//! cargo run --release -p furnace-tests --example sampler_study            # 128², 4 seeds
//! cargo run --release -p furnace-tests --example sampler_study -- --seeds 2 --max-spp 64
//! ```
//!
//! The built-in Cornell box at 128×128, 4 bounces, Mitsuba's material model, against
//! `tests/data/references/cbox/cbox_ref_bounces4.exr` averaged over 2×2 blocks (with a one-pixel box
//! filter that is exactly what a 128² render converges to). For spp = 1, 2, 4, …, `--max-spp`
//! (256): the progressive samplers (random, PMJ02, Owen-Sobol) render `--max-spp` samples once
//! per seed and are evaluated at every power-of-two prefix; the fixed-N samplers (Hammersley,
//! CMJ) render each N separately with `sample_count = N`. Seeds 0, 1, … (`--seeds`).
//!
//! Error: MSE over pixels and channels, averaged over seeds, **minus the reference's own noise
//! floor** `mean(se_ref²)` (the MSE a perfect renderer would score; 2×2 blocks of 65,536-spp
//! pixels), reported as RMSE = √(MSE − floor); relative MSE `mean((x − r)²/(r² + 10⁻⁴))` minus
//! its floor likewise. Also the wall time per render (2 threads, noisy on a shared machine).
//! Prints Markdown tables and writes every (sampler, spp, seed) row to
//! `target/sampler_study.csv`.

use furnace_brdf::SpecularOptions;
use furnace_cpu::CpuRenderer;
use furnace_render::RenderSettings;
use furnace_sampling::SamplerKind;
use furnace_tests::cbox::Reference;
use glam::DVec3;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::time::Instant;

const SIZE: usize = 128;
const BLOCK: usize = 2;

/// The reference averaged over `BLOCK²` blocks, and each block mean's variance.
fn downsampled(reference: &Reference) -> (Vec<DVec3>, Vec<DVec3>) {
    let w = reference.mean.width;
    assert_eq!(w, SIZE * BLOCK);
    let mut mean = vec![DVec3::ZERO; SIZE * SIZE];
    let mut var = vec![DVec3::ZERO; SIZE * SIZE];
    let n = (BLOCK * BLOCK) as f64;
    for (i, (m, s)) in reference.mean.pixels.iter().zip(&reference.stderr.pixels).enumerate() {
        let j = (i / w / BLOCK) * SIZE + (i % w) / BLOCK;
        mean[j] += *m / n;
        // Independent pixels: the block mean's variance is Σ se²/n².
        var[j] += *s * *s / (n * n);
    }
    (mean, var)
}

/// `(MSE, relative MSE)` of `image` against `reference` (`furnace_post::metrics`).
fn errors(image: &[DVec3], reference: &[DVec3]) -> (f64, f64) {
    let mut e = furnace_post::metrics::ErrorSum::default();
    for (x, r) in image.iter().zip(reference) {
        e.add_rgb(x.to_array(), r.to_array());
    }
    (e.mse(), e.rel_mse())
}

/// Renders samples `0..spp` of every pixel and returns the running means after each count in
/// `checkpoints` (ascending, the last = spp), pixel-major.
fn render(renderer: &CpuRenderer, checkpoints: &[u32]) -> Vec<Vec<DVec3>> {
    let spp = *checkpoints.last().expect("a checkpoint");
    let per_pixel: Vec<Vec<DVec3>> = (0..SIZE * SIZE)
        .into_par_iter()
        .map(|i| {
            let (x, y) = ((i % SIZE) as u32, (i / SIZE) as u32);
            let mut sum = DVec3::ZERO;
            let mut out = Vec::with_capacity(checkpoints.len());
            for index in 0..spp {
                let v = renderer.sample(x, y, index);
                // Non-finite samples would be rejected by the film; none are expected.
                assert!(v.is_finite(), "pixel ({x}, {y}) sample {index}: {v}");
                sum += v.as_dvec3();
                if checkpoints.contains(&(index + 1)) {
                    out.push(sum / f64::from(index + 1));
                }
            }
            out
        })
        .collect();
    (0..checkpoints.len()).map(|k| per_pixel.iter().map(|p| p[k]).collect()).collect()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let flag = |name: &str, default: u32| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .and_then(|s| s.parse().ok())
            .unwrap_or(default)
    };
    let (seeds, max_spp) = (flag("--seeds", 4), flag("--max-spp", 256));
    let reference = Reference::load("cbox_ref_bounces4");
    let (ref_mean, ref_var) = downsampled(&reference);
    let floor = ref_var.iter().map(|v| v.element_sum()).sum::<f64>() / (3 * ref_var.len()) as f64;
    let rel_floor = ref_var
        .iter()
        .zip(&ref_mean)
        .map(|(v, r)| (*v / (*r * *r + DVec3::splat(furnace_post::metrics::REL_MSE_EPSILON))).element_sum())
        .sum::<f64>()
        / (3 * ref_var.len()) as f64;
    let spps: Vec<u32> = (0..=16).map(|k| 1u32 << k).filter(|&n| n <= max_spp).collect();
    let scene = furnace_scene::builtin::cornell_box().expect("the built-in Cornell box");
    let settings = |sampler, seed, sample_count| RenderSettings {
        width: SIZE as u32,
        height: SIZE as u32,
        bounces: 4,
        sampler,
        seed,
        sample_count,
        specular: SpecularOptions::mitsuba(),
        ..Default::default()
    };
    // results[(sampler, spp index)] = (Σ MSE, Σ rel MSE, Σ seconds) over seeds.
    let mut results = vec![vec![(0.0f64, 0.0f64, 0.0f64); spps.len()]; SamplerKind::ALL.len()];
    let mut csv = String::from("sampler,spp,seed,mse,rel_mse,mse_minus_floor,rel_mse_minus_floor,seconds\n");
    for seed in 0..seeds {
        for (s, &kind) in SamplerKind::ALL.iter().enumerate() {
            let mut record = |k: usize, image: &[DVec3], seconds: f64| {
                let (mse, rel) = errors(image, &ref_mean);
                results[s][k].0 += mse;
                results[s][k].1 += rel;
                results[s][k].2 += seconds;
                writeln!(
                    csv,
                    "{kind},{},{seed},{mse:e},{rel:e},{:e},{:e},{seconds:.3}",
                    spps[k],
                    mse - floor,
                    rel - rel_floor
                )
                .expect("writing to a String");
            };
            if kind.is_progressive() {
                let renderer = CpuRenderer::with_default_camera(scene.clone(), settings(kind, seed, None))
                    .expect("a sampler");
                let start = Instant::now();
                let images = render(&renderer, &spps);
                let seconds = start.elapsed().as_secs_f64();
                for (k, image) in images.iter().enumerate() {
                    // Time of a prefix: the render's time pro rata.
                    record(k, image, seconds * f64::from(spps[k]) / f64::from(max_spp));
                }
            } else {
                for (k, &n) in spps.iter().enumerate() {
                    let renderer =
                        CpuRenderer::with_default_camera(scene.clone(), settings(kind, seed, Some(n)))
                            .expect("a sampler");
                    let start = Instant::now();
                    let image = render(&renderer, &[n]).pop().expect("one image");
                    record(k, &image, start.elapsed().as_secs_f64());
                }
            }
            eprintln!("seed {seed}: {kind} done");
        }
    }
    let s = f64::from(seeds);
    let names: Vec<String> = SamplerKind::ALL.iter().map(|k| k.to_string()).collect();
    println!(
        "Cornell box 128², 4 bounces, Mitsuba model; {seeds} seeds; reference noise floor: MSE {floor:.3e} \
         (RMSE {:.2e}), relative MSE {rel_floor:.3e}\n",
        floor.sqrt()
    );
    println!(
        "RMSE = √(MSE − floor), MSE averaged over seeds; in brackets: relative to the best at that spp\n"
    );
    println!("| spp | {} |", names.join(" | "));
    println!("|---|{}", "---|".repeat(names.len()));
    for (k, &n) in spps.iter().enumerate() {
        let mses: Vec<f64> = results.iter().map(|r| (r[k].0 / s - floor).max(0.0)).collect();
        let best = mses.iter().copied().fold(f64::INFINITY, f64::min);
        let cells: Vec<String> =
            mses.iter().map(|m| format!("{:.4e} ({:.2})", m.sqrt(), (m / best).sqrt())).collect();
        println!("| {n} | {} |", cells.join(" | "));
    }
    println!("\nRelative MSE − floor\n");
    println!("| spp | {} |", names.join(" | "));
    println!("|---|{}", "---|".repeat(names.len()));
    for (k, &n) in spps.iter().enumerate() {
        let cells: Vec<String> = results.iter().map(|r| format!("{:.3e}", r[k].1 / s - rel_floor)).collect();
        println!("| {n} | {} |", cells.join(" | "));
    }
    // Summary over the typical range 16–256 spp: geometric mean of MSE relative to random, the
    // log-log slope of RMSE, and throughput.
    let mut range: Vec<usize> = (0..spps.len()).filter(|&k| spps[k] >= 16).collect();
    if range.len() < 2 {
        range = (0..spps.len()).collect();
    }
    println!("\nOver {}–{} spp\n", spps[range[0]], max_spp);
    println!("| sampler | MSE / random (geometric mean) | RMSE slope vs spp | Msamples/s (2 threads) |");
    println!("|---|---|---|---|");
    for (si, kind) in SamplerKind::ALL.iter().enumerate() {
        let mse = |k: usize| (results[si][k].0 / s - floor).max(1e-30);
        let random = |k: usize| (results[0][k].0 / s - floor).max(1e-30);
        let gm = (range.iter().map(|&k| (mse(k) / random(k)).ln()).sum::<f64>() / range.len() as f64).exp();
        // Least-squares slope of ln RMSE on ln spp.
        let xs: Vec<f64> = range.iter().map(|&k| f64::from(spps[k]).ln()).collect();
        let ys: Vec<f64> = range.iter().map(|&k| 0.5 * mse(k).ln()).collect();
        let (mx, my) = (xs.iter().sum::<f64>() / xs.len() as f64, ys.iter().sum::<f64>() / ys.len() as f64);
        let slope = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum::<f64>()
            / xs.iter().map(|x| (x - mx).powi(2)).sum::<f64>();
        let samples: f64 = range.iter().map(|&k| f64::from(spps[k])).sum::<f64>() * (SIZE * SIZE) as f64 * s;
        let seconds: f64 = range.iter().map(|&k| results[si][k].2).sum();
        println!("| {kind} | {gm:.3} | {slope:.2} | {:.2} |", samples / seconds / 1e6);
    }
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/sampler_study.csv");
    std::fs::write(&path, csv).expect("writing the CSV");
    eprintln!("CSV: {}", path.display());
}
