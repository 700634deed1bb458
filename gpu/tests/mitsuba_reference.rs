//! The GPU integrator against Mitsuba 3 (furnace-cpu's `tests/data/cbox/`, an independent
//! renderer) on the Cornell box, to the bar of the CPU test (`cpu/tests/reference.rs`):
//!
//! * per-channel image-mean ratio ours/Mitsuba within ±0.5%;
//! * per-pixel z-scores `z = (ours − ref)/√(se_ours² + se_ref²)` (every pixel and channel whose
//!   denominator is not 0) with standard deviation in [0.9, 1.15]; z mean and the fraction
//!   with |z| > 3 are reported.
//!
//! As there: Mitsuba's material model (`SpecularOptions::mitsuba()`), the random sampler, one
//! sample per pixel per pass so that each pixel's standard error comes from its own `N`
//! samples (`N − 1` degrees of freedom), direct light (1 bounce, against `cbox_ref_direct`) and
//! 4 bounces (against `cbox_ref_bounces4`).
//!
//! ## Fewer pixels: the references box-downsampled
//!
//! On lavapipe the GPU integrator is 30–100× slower than the CPU one (0.02–0.05 Msamples/s at
//! 4 bounces on the 2-core VM), so the CPU test's 256² × (128 + 512) samples are out of reach.
//! We render 32×32 and compare with the references averaged over 8×8 blocks. That is exact,
//! not an approximation, for this code: `Camera::generate_ray` (and its WGSL twin
//! `camera_ray`) maps the film point `p` (pixels) of a `w × h` image linearly to
//! `x = 2p.x/w − 1`, `y = 1 − 2p.y/h` on the film plane, with the aspect ratio `w/h` (1 for
//! both sizes), and the integrator jitters `p` uniformly inside the pixel (`DIM_PIXEL`,
//! independent of the other dimensions for the random sampler): a box filter one pixel wide,
//! which is also how the references were rendered (`README-references.md`). Pixel `(i, j)` of
//! the 32² image therefore covers exactly the film region of reference pixels
//! `8i..8i+8 × 8j..8j+8`, uniformly, so its expectation is the mean of those 64 pixels'
//! expectations, and the standard error of that mean is `√(Σ se_k²)/64` (the reference's
//! pixels are independent). `downsampling_keeps_the_image_mean_and_pools_the_errors` checks
//! the arithmetic.
//!
//! ## How many samples
//!
//! The excess of z's standard deviation over 1 at small N comes from heavy tails: rare bright
//! paths (the sky through the ceiling hole found by a BSDF sample, the metal sphere's GGX tail)
//! leave pixels whose estimated error is small and whose z is large and negative; in direct
//! light a pixel whose rare path never came has no variance at all and a |z| of 100–500, and
//! one such pixel among the 3072 z values of a 32² image lifts z std from 1.0 to 2.0. Only more
//! samples per pixel cure it. A large pixel mixes the sample distributions of the small pixels
//! it covers, so its rarest path is less rare: direct light needs fewer samples at 32² than at
//! 64²; but with fewer z values the statistic varies more from seed to seed. Measured with
//! `cargo run --profile test -p furnace-gpu --example mitsuba_budget -- --backend cpu --size 32
//! --bounces 4 --seeds 40 --first-seed 200 --max-spp 512` (and `--bounces 1 --max-spp 1024`,
//! and `--size 64`): the CPU twin traces the same paths from the same sample values as the GPU,
//! much faster (`--backend gpu` printed the same tables to every digit for seeds 11, 100 and
//! 107). z std over 40 seeds each (min – max; median, standard deviation over seeds):
//!
//! | bounces | size | N = 64 | N = 128 | N = 256 | N = 512 | N = 1024 |
//! |---|---|---|---|---|---|---|
//! | 4 | 32² | 1.046 – 1.237 | 0.999 – 1.129 | **0.983 – 1.107; 1.039, 0.025** | 0.951 – 1.076 | — |
//! | 4 | 64² | 1.062 – 1.285 | 1.035 – 1.116 | 1.005 – 1.066; 1.042, 0.015 | 0.993 – 1.046 | — |
//! | 1 | 32² | 6.1 – 25 | 1.04 – 13.6 | 0.99 – 6.0 | 0.961 – 1.107; 1.022, 0.038 | **0.946 – 1.070; 1.003, 0.028** |
//! | 1 | 64² | 7.5 – 11.8 | 2.2 – 6.4 | 1.02 – 2.94 | 0.985 – 1.82 | 0.967 – 1.034; 1.004, 0.013 |
//!
//! At the chosen N (below) the image-mean ratios of the 40 seeds stayed within ±0.26% at 4
//! bounces and ±0.14% direct (standard error of the ratio 0.14% and 0.07%). z mean is slightly negative
//! (−0.13 to +0.05: the skew above), |z| > 3 at most 1.4% of the values.
//!
//! At 64² the bar needs the same N as at 32² (256 at 4 bounces, 1024 direct), four times the
//! samples: ≈ 140 s of lavapipe CPU time, over the budget. Hence **32², 4
//! bounces: 256 passes of 1 spp** (worst of 40 seeds 1.107, mean + 3 sd = 1.11), **direct:
//! 1024 passes of 1 spp** (at 512 the worst seed came to 1.107 and mean + 3 sd to 1.14, too
//! close to 1.15); fixed seed 11 (the CPU test's), which gives 1.030 and 1.006. Cost: 0.26 M
//! paths at 4 bounces, 1.05 M direct, one film read-back per pass.
//! `cargo test --profile test -p furnace-gpu --test mitsuba_reference -- --nocapture` (the four
//! tests, two at a time) took 48.6 s of CPU (user) on lavapipe, and 47 s wall at load 4–5
//! (75 s at load 6–7) on the shared 2-core VM: about 25–30 s on two idle cores. Most of the
//! direct test's time is the per-pass round trips (render, then the film read back): ≈ 10 ms a
//! pass here, 1024 passes.
//!
//! ## It can fail
//!
//! `gltf_default_model_fails_the_bar` renders the 4-bounce configuration with the glTF default
//! material model (height-correlated masking, Turquin compensation) instead of Mitsuba's: only
//! the metal sphere changes, and the test must fail, on the ratio alone. Measured (seed 11,
//! lavapipe): 4 bounces, 256 spp: ratios 1.0280, 1.0210, 1.0145 (± 0.0015), z mean +0.38,
//! z std 1.34; direct, 1024 spp: ratios 1.0158, 1.0128, 1.0095 (± 0.0007), z std 1.95.
//!
//! On failure the candidate, its standard error, the downsampled reference (and its error) and
//! the z image are written to `target/test-output/furnace-gpu/`, with the table.

#[path = "../../cpu/tests/support/cbox.rs"]
mod cbox;

use cbox::{BatchEstimator, Comparison, Estimate, Image, Reference};
use furnace_brdf::SpecularOptions;
use furnace_gpu::{GpuRenderer, test_context};
use furnace_render::Film;
use furnace_render::RenderSettings;
use furnace_sampling::SamplerKind;
use glam::DVec3;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The bar of issue 5 (the CPU test's).
const MAX_RATIO_ERROR: f64 = 5e-3;
const Z_STD_RANGE: (f64, f64) = (0.9, 1.15);
/// Rendered size; the 256² references are averaged over `256/SIZE` square blocks.
const SIZE: u32 = 32;
/// Fixed seed of the random sampler (see the module docs for the spread over seeds).
const SEED: u32 = 11;

/// The references live with the CPU crate's tests.
fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../cpu/tests/data/cbox")
}

fn output_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/test-output/furnace-gpu");
    std::fs::create_dir_all(&dir).expect("an output folder");
    dir
}

/// The reference averaged over `factor × factor` blocks: each block's mean, and the standard
/// error of that mean `√(Σ se²)/factor²` (independent pixels).
fn downsample(r: &Reference, factor: usize) -> Reference {
    let (w, h) = (r.mean.width / factor, r.mean.height / factor);
    assert_eq!((w * factor, h * factor), (r.mean.width, r.mean.height), "{}: size", r.name);
    let mut mean = vec![DVec3::ZERO; w * h];
    let mut var = vec![DVec3::ZERO; w * h];
    for y in 0..r.mean.height {
        for x in 0..r.mean.width {
            let (i, k) = ((y / factor) * w + x / factor, y * r.mean.width + x);
            mean[i] += r.mean.pixels[k];
            var[i] += r.stderr.pixels[k] * r.stderr.pixels[k];
        }
    }
    let n = (factor * factor) as f64;
    Reference {
        name: format!("{}_{w}x{h}", r.name),
        mean: Image { width: w, height: h, pixels: mean.iter().map(|m| *m / n).collect() },
        stderr: Image { width: w, height: h, pixels: var.iter().map(|v| v.map(f64::sqrt) / n).collect() },
    }
}

/// `{stem}.exr` and `{stem}_stderr.exr`, downsampled to `SIZE`².
fn reference(stem: &str) -> Reference {
    let full = Reference {
        name: stem.to_owned(),
        mean: Image::read_exr(&data_dir().join(format!("{stem}.exr"))),
        stderr: Image::read_exr(&data_dir().join(format!("{stem}_stderr.exr"))),
    };
    downsample(&full, full.mean.width / SIZE as usize)
}

/// `passes` GPU passes of one sample per pixel (sample indices `0..passes`); each pixel's mean
/// and standard error from its own samples (Welford, `cbox::BatchEstimator`).
fn render(bounces: u32, specular: SpecularOptions, passes: u32) -> Option<Estimate> {
    let ctx = test_context()?;
    let scene = furnace_scene::builtin::cornell_box().expect("the built-in Cornell box");
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        bounces,
        sampler: SamplerKind::Random,
        seed: SEED,
        specular,
        ..Default::default()
    };
    let mut gpu = GpuRenderer::new(ctx, &scene, &scene.default_camera(), settings).expect("a GPU renderer");
    let n = (SIZE * SIZE) as usize;
    let mut estimators = vec![BatchEstimator::new(1); n];
    let mut before = Film::new(SIZE, SIZE);
    for pass in 0..passes {
        gpu.render_pass(pass, 1).expect("a GPU pass");
        let after = gpu.film().expect("reading the film");
        assert_eq!(after.rejected(), 0, "pass {pass}: non-finite samples");
        for (i, e) in estimators.iter_mut().enumerate() {
            assert_eq!(after.counts()[i], u64::from(pass) + 1, "pixel {i}: sample count");
            // This pass's one sample: the sums' difference (exact: the sums are f64 sums of
            // f32 samples, far from f64's precision).
            e.push(DVec3::from_array(std::array::from_fn(|c| after.sums()[i][c] - before.sums()[i][c])));
        }
        before = after;
    }
    let per_pixel: Vec<(DVec3, DVec3)> = estimators.iter().map(BatchEstimator::estimate).collect();
    let image = |f: fn(&(DVec3, DVec3)) -> DVec3| Image {
        width: SIZE as usize,
        height: SIZE as usize,
        pixels: per_pixel.iter().map(f).collect(),
    };
    Some(Estimate { mean: image(|p| p.0), stderr: image(|p| p.1) })
}

fn passes_bar(c: &Comparison) -> bool {
    (c.ratio() - 1.0).abs().max_element() < MAX_RATIO_ERROR
        && (Z_STD_RANGE.0..=Z_STD_RANGE.1).contains(&c.z_std)
}

fn table(stem: &str, model: &str, passes: u32, c: &Comparison, seconds: f64) -> String {
    let block = 256 / SIZE;
    format!(
        "| reference | model | size | passes × spp | ratio R, G, B (± se) | z mean | z std | \\|z\\| > 3 | max \\|z\\| | z values | time |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n\
         | {stem} | {model} | {SIZE}² ({block}×{block} blocks) | {passes} × 1 | {} | {seconds:.1} s |",
        c.cells()
    )
}

/// A GPU render compared with a downsampled reference, and the table that describes it.
struct Outcome {
    reference: Reference,
    candidate: Estimate,
    comparison: Comparison,
    table: String,
}

impl Outcome {
    /// Writes the candidate, its standard error, the reference, its error, the z image and the
    /// table to `target/test-output/furnace-gpu/`; returns the folder.
    fn write(&self, stem: &str) -> PathBuf {
        let dir = output_dir();
        for (name, image) in [
            ("candidate", &self.candidate.mean),
            ("candidate_stderr", &self.candidate.stderr),
            ("reference", &self.reference.mean),
            ("reference_stderr", &self.reference.stderr),
            ("z", &self.comparison.z_image),
        ] {
            image.write_exr(&dir.join(format!("{stem}_{SIZE}_{name}.exr")));
        }
        std::fs::write(dir.join(format!("{stem}_{SIZE}.md")), format!("{}\n", self.table))
            .expect("writing the table");
        dir
    }
}

/// Renders `passes` one-sample passes with `specular` and compares them with `stem`; `None`
/// when GPU tests are skipped.
fn evaluate(
    stem: &str,
    bounces: u32,
    specular: SpecularOptions,
    model: &str,
    passes: u32,
) -> Option<Outcome> {
    let reference = reference(stem);
    let start = Instant::now();
    let candidate = render(bounces, specular, passes)?;
    let seconds = start.elapsed().as_secs_f64();
    let comparison = cbox::compare(&candidate, &reference);
    let table = table(stem, model, passes, &comparison, seconds);
    println!("{table}");
    Some(Outcome { reference, candidate, comparison, table })
}

fn compare(stem: &str, bounces: u32, passes: u32) {
    let Some(o) = evaluate(stem, bounces, SpecularOptions::mitsuba(), "Mitsuba", passes) else { return };
    let c = &o.comparison;
    if !passes_bar(c) {
        let dir = o.write(stem);
        panic!(
            "{stem}: ratio {:.5} (bar ±{MAX_RATIO_ERROR}), z std {:.3} (bar {Z_STD_RANGE:?}); candidate, its \
             standard error, the downsampled reference, z images and the table in {}",
            c.ratio(),
            c.z_std,
            dir.display()
        );
    }
}

#[test]
fn downsampling_keeps_the_image_mean_and_pools_the_errors() {
    // A 4×4 image with distinct values and errors, averaged over 2×2 blocks.
    let pixels = |f: fn(usize) -> f64| (0..16).map(|k| DVec3::new(f(k), 2.0 * f(k), 0.0)).collect();
    let r = Reference {
        name: "synthetic".into(),
        mean: Image { width: 4, height: 4, pixels: pixels(|k| k as f64) },
        stderr: Image { width: 4, height: 4, pixels: pixels(|k| 1.0 + (k % 3) as f64) },
    };
    let d = downsample(&r, 2);
    assert_eq!((d.mean.width, d.mean.height), (2, 2));
    // Block (1, 0) holds pixels 2, 3, 6, 7: mean 4.5; errors 3, 1, 1, 2: √(9+1+1+4)/4.
    assert_eq!(d.mean.pixels[1], DVec3::new(4.5, 9.0, 0.0));
    assert!((d.stderr.pixels[1].x - 15f64.sqrt() / 4.0).abs() < 1e-15, "{:?}", d.stderr.pixels[1]);
    // The image mean is unchanged (exactly: sums of small integers), and so is the standard
    // error of the image mean, √(Σ se²)/n, that the ratio's error comes from.
    assert_eq!(d.mean.mean(), r.mean.mean());
    let var_of_mean =
        |i: &Image| i.pixels.iter().map(|s| s.x * s.x).sum::<f64>() / (i.pixels.len() as f64).powi(2);
    assert!((var_of_mean(&d.stderr) - var_of_mean(&r.stderr)).abs() < 1e-15);
}

#[test]
fn cornell_box_direct_matches_mitsuba() {
    compare("cbox_ref_direct", 1, 1024);
}

#[test]
fn cornell_box_four_bounces_matches_mitsuba() {
    compare("cbox_ref_bounces4", 4, 256);
}

/// The bar is sharp enough to see a wrong material model: the glTF default (height-correlated
/// masking, Turquin compensation) instead of Mitsuba's, on the metal sphere only, at the
/// 4-bounce test's settings. It must fail the ratio part of the bar (by itself: measured 1.028
/// for red, ±0.0015), not just the noisier z part.
#[test]
fn gltf_default_model_fails_the_bar() {
    let stem = "cbox_ref_bounces4";
    let Some(o) = evaluate(stem, 4, SpecularOptions::default(), "glTF default", 256) else { return };
    let c = &o.comparison;
    let worst = (c.ratio() - 1.0).abs().max_element();
    if worst < MAX_RATIO_ERROR {
        let dir = o.write(&format!("{stem}_gltf_default"));
        panic!(
            "the glTF default model came within the bar on the ratio: {:.5} (bar ±{MAX_RATIO_ERROR}), z std \
             {:.3}: the test cannot tell the models apart; images and table in {}",
            c.ratio(),
            c.z_std,
            dir.display()
        );
    }
}
