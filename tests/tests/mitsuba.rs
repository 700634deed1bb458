//! Both integrators against Mitsuba 3 (`tests/data/references/cbox/` and `lights/`, an
//! independent renderer) on the built-in Cornell box and the light boxes: one test, run on the CPU at the references' full resolution and
//! on the GPU (lavapipe in CI) at 32² against the references averaged over 8×8 blocks. The bar:
//!
//! * per-channel image-mean ratio ours/Mitsuba within ±0.5%;
//! * per-pixel z-scores `z = (ours − ref)/√(se_ours² + se_ref²)` (over every pixel and channel
//!   whose denominator is not 0) with standard deviation in [0.9, 1.15]; z mean and the fraction
//!   with |z| > 3 are reported.
//!
//! We render with Mitsuba's material model (`SpecularOptions::mitsuba()`: separable masking, no
//! compensation), the random sampler, direct light (1 bounce, against `cbox_ref_direct`) and 4
//! bounces (against `cbox_ref_bounces4`); `gltf_default_model_fails_the_bar_*` shows the bar
//! can fail.
//!
//! # The CPU: 256²
//!
//! ## How the candidate gets its own standard error
//!
//! `n` independent passes, each pixel's standard error from the spread of its `n` pass means
//! (`furnace_tests::cbox::render_passes`). With few passes the estimated error is itself noisy
//! and z follows Student's t with `n − 1` degrees of freedom, whose standard deviation is
//! `√((n−1)/(n−3))`: 1.18 for the old test's 8 passes, above the bar before any bias. So each
//! pass here is **one sample per pixel** of the random sampler (whose samples are independent):
//! the pass variance is the per-sample variance, with `N − 1` degrees of freedom for `N`
//! samples (inflation ≤ 1.004 at N = 128). What remains is the heavy tails: rare bright paths
//! (the sky through the ceiling hole found by a BSDF sample, the metal sphere's GGX tail) make
//! the per-pixel estimates skewed, and a pixel whose rare path never came has a small estimated
//! error and a large negative z. That excess depends on the total sample count N, not on how
//! it is split into passes (Edgeworth: skewness of the mean ∝ 1/√N), and only more samples cure
//! it. The reference's own error enters through `se_ref` (64 passes of Mitsuba's; ~0.4% per
//! pixel at 4 bounces, ~1% direct).
//!
//! Measured with `cargo run --release -p furnace-tests --example reference_budget` (one render
//! per seed evaluated at every prefix N and pass size b; seeds 100–102, and 103–105 for the
//! chosen N), z std:
//!
//! | bounces | N | b = 1 (N passes) | b = 4 | b = N/16 (16 passes) | b = N/8 (8 passes) |
//! |---|---|---|---|---|---|
//! | 4 | 64 | 1.112 – 1.126 | 1.166 – 1.174 | 1.166 – 1.174 | 1.272 – 1.285 |
//! | 4 | 128 | 1.044 – 1.059 | 1.078 – 1.082 | 1.116 – 1.123 | 1.222 |
//! | 4 | 256 | 1.022 – 1.030 | 1.034 – 1.041 | 1.090 | 1.191 |
//! | 4 | 2048 | 1.003 | 1.005 | 1.067 | 1.152 |
//! | 1 | 128 | 1.627 | 1.641 | 1.664 | 1.738 |
//! | 1 | 256 | 1.068 – 1.124 | 1.135 | 1.184 | — |
//! | 1 | 512 | 1.007 – 1.018 | 1.018 | 1.081 | — |
//! | 1 | 2048 | 1.007 | 1.008 | 1.013 | — |
//!
//! (ranges over seeds where more than one was run). Image-mean ratios were within ±0.06% in
//! every configuration. Hence the cheapest configurations that meet the bar with margin —
//! **4 bounces: 128 passes of 1 spp** (z std 1.044–1.059 over 6 seeds); **direct: 512 passes
//! of 1 spp** (1.007–1.018; at 256 spp the rarely sampled skylight pushes it to 1.07–1.12, too
//! close). Significance: over 6 seeds the z std of an unbiased render had a standard deviation
//! of ≈ 0.005 at these settings, against a margin of ≥ 0.09 to 1.15 and ≥ 0.1 to 0.9, so a
//! false failure would take a > 15σ fluctuation; a real bias fails loudly (rendering
//! with the glTF default model instead of Mitsuba's gives ratios 1.016–1.029 and z std 1.58).
//! Fixed seed 11; the test prints its table with `--nocapture`. Cost: 8.4 M paths at 4 bounces
//! and 33.6 M direct-light paths; the two CPU tests took 17.7 s
//! wall, 24 s CPU (test profile, the two tests in parallel) on the shared 2-core VM at load 7. On failure the candidate, its standard error, the reference and the z image
//! are written to `target/test-output/mitsuba/`, with the table.
//!
//! # The GPU: 32²
//!
//! ## Fewer pixels: the references box-downsampled
//!
//! On lavapipe the GPU integrator is 30–100× slower than the CPU one (0.02–0.05 Msamples/s at
//! 4 bounces on the 2-core VM), so the CPU's 256² × (128 + 512) samples are out of reach.
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
//! `cargo run --profile test -p furnace-tests --example mitsuba_budget -- --backend cpu --size 32
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
//! The GPU tests (four, two at a time) took 48.6 s of CPU (user) on lavapipe, and 47 s wall at load 4–5
//! (75 s at load 6–7) on the shared 2-core VM: about 25–30 s on two idle cores. Most of the
//! direct test's time is the per-pass round trips (render, then the film read back): ≈ 10 ms a
//! pass here, 1024 passes.
//!
//! # The point-light box
//!
//! `lights/cbox_point` (the box closed, two point lights, 4 bounces): delta lights reached only
//! by shadow rays, so light reflected once off the metal sphere onto a wall comes from rare
//! wall → sphere BSDF samples; the per-pixel estimates are skewed as in the Cornell box and z's
//! standard deviation falls with the samples per (downsampled) pixel. Measured with
//! `cargo run --release -p furnace-tests --example mitsuba_budget -- --backend cpu --lights point
//! --size S --seeds 2 --first-seed 200 --max-spp 1024`, z std (seeds 200, 201):
//!
//! | size | N = 128 | N = 256 | N = 512 | N = 1024 |
//! |---|---|---|---|---|
//! | 256² | 1.205, 1.200 | 1.108, 1.105 | 1.052, 1.055 | 1.030, 1.024 |
//! | 64² | 1.189, 1.182 | 1.113, 1.085 | 1.042, 1.021 | 1.029, 1.010 |
//! | 32² | 1.133, 1.161 | 1.050, 1.076 | 1.037, 1.046 | 1.023, 1.028 |
//!
//! with every image-mean ratio within ±0.3 % (±0.03 % at 256²). Hence the **CPU at 64² (4×4
//! blocks), 512 passes of 1 spp** (2.1 M paths, a quarter of the 256² Cornell box test's) and
//! the **GPU at 32², 512 passes of 2 spp** (each pixel's error from 512 batches of 2: the
//! same statistic as 1 spp per pass at half the round trips; at 256 spp the ratio's standard
//! error, 0.19 %, left the ±0.5 % bar only 2.6 σ away). With the fixed seed 11 both give
//! ratios 1.0024, 1.0022, 1.0023 (± 0.0010) and z std 0.990 at 32² — the CPU twin prints the
//! same digits from the same samples, so that is this seed's draw, not a GPU difference —
//! and 0.9997–0.9999 (± 0.0007), z std 1.040 at 64² on the CPU.
//!
//! # The emitter and sun-disc boxes
//!
//! `lights/cbox_area` (the closed box lit by one emissive quad), `lights/cbox_many_lights` (64
//! emissive squares over a 100× power range) and `lights/cbox_sun_disc` (the Cornell box with a
//! 5° sun disc), 4 bounces, light samples and BSDF samples combined by MIS (the default).
//!
//! Two things of these references needed care in the comparison itself
//! (`furnace_tests::cbox`):
//!
//! * **Pixels on an emitter** have a reference standard error of f32 rounding (10⁻⁹ of 0.2:
//!   every sample is the emitted radiance) and a candidate that differs by 10⁻⁷ relative — a z
//!   of 30–300 that is not bias. z's denominators get a floor of 10⁻⁶ of the reference value
//!   (`Z_ROUNDING_FLOOR`), far below any other pixel's noise; pixels with no error on either side
//!   still have no z.
//! * **The image-mean ratio leaves out the pixels that show an emitter**
//!   (`pixels_without_visible_emitters`: a camera-ray-only render is 0 there). Their noise is
//!   where the pixel's samples land on the emitter's edge — the same for every light-sampling
//!   method — and it dominated the ratio's error (± 0.57 % at 32², 1024 spp on the emissive
//!   quad box; ± 0.12 % without those pixels). z still covers every pixel.
//!
//! Measured with `cargo run --release -p furnace-tests --example mitsuba_budget -- --backend cpu
//! --lights area|many_lights|sun_disc --size S --seeds 2 --first-seed 200 --max-spp N` (seeds
//! 200, 201; z std, and the ratio's standard error):
//!
//! | box | size | N = 256 | N = 512 | N = 1024 | N = 4096 |
//! |---|---|---|---|---|---|
//! | emissive quad | 64² | 1.057, 1.108 (± 0.13 %) | 1.036, 1.054 (± 0.09 %) | 1.028, 1.012 | — |
//! | emissive quad | 32² | 1.091, 1.050 (± 0.23 %) | 1.050, 1.041 (± 0.16 %) | 1.029, 1.010 (± 0.12 %) | — |
//! | 64 emitters | 64² | 1.553, 1.645 | 1.194, 1.320 | 1.120, 1.238 (± 0.30 %) | 1.067, 1.067 (± 0.15 %) |
//! | 64 emitters | 32² | 1.197, 1.457 | 1.153, 1.157 | 1.107, 1.118 (± 0.61 %) | — |
//! | sun disc | 64² | 1.046, 1.027 (± 0.06 %) | 1.022, 1.010 (± 0.05 %) | 1.012, 1.002 | — |
//! | sun disc | 32² | 1.008, 1.051 (± 0.14 %) | 1.013, 0.993 (± 0.10 %) | 1.026, 1.023 | — |
//!
//! The budgets above were measured with light samples chosen by power (an alias table). The
//! 64-emitter box is the noisiest that way: power sends most light samples to the bright squares
//! across the room while a wall point is lit mostly by the dim ones near it. The light BVH, now
//! the default, weighs distance and orientation too: the same test's standard error fell from
//! 0.14 % to 0.09 % (variance ×0.4) and its z std from 1.067 to 1.026, so the budgets are
//! conservative. Hence the **CPU at 64²: the emissive quad 512 passes of 1 spp, the 64 emitters
//! 4096 (16.8 M paths, the heaviest CPU test: 40 s), the sun disc 512**; the **GPU at 32²: the
//! emissive quad 256 passes of 2 spp, the sun disc 128 of 2** (23 s and 8 s of lavapipe on the
//! idle 2-core VM, ≈ 2·10⁴ paths a second). The GPU has no 64-emitter test in CI: at 32² it
//! would need ≈ 4096 spp (4.2 M paths, 3–4 minutes of lavapipe, a sixth of CI's budget) for a
//! ratio error of 0.15 %; the GPU traces the same paths as the CPU from the same samples, by
//! power and by the light BVH (`tests/tests/integrator.rs`, 4095/4096 pixels within 10⁻⁴ on
//! this box) and matches the reference at full size on the H200 (BENCHMARKS.md). Fixed seed 11,
//! light BVH:
//!
//! | box | backend | ratio R, G, B (± se) | z std |
//! |---|---|---|---|
//! | emissive quad | CPU 64² | 0.9995, 0.9992, 0.9993 (± 0.0008) | 1.053 |
//! | 64 emitters | CPU 64² | 0.9995, 1.0000, 0.9999 (± 0.0009) | 1.026 |
//! | sun disc | CPU 64² | 0.9999, 1.0003, 1.0005 (± 0.0005) | 1.005 |
//! | emissive quad | GPU 32² | 1.0015, 1.0006, 1.0005 (± 0.0016) | 1.088 |
//! | sun disc | GPU 32² | 0.9991, 0.9997, 0.9988 (± 0.0014) | 1.045 |
//!
//! # The environment map
//!
//! `envmap/envmap_spheres` (a floor and three spheres, Lambert and GGX α 0.3 and 0.05, lit only
//! by a 512 × 256 HDR sky with a 1° sun of 2·10⁴), 4 bounces, environment importance sampling
//! and BSDF sampling by MIS. The sun reflected by the α 0.05 sphere makes a **caustic** on the
//! floor beside it, found only when a floor point's cosine-sampled ray happens to hit the small
//! part of the sphere that mirrors the sun (for every path tracer, Mitsuba's included): pixels
//! there have heavily skewed estimates, whose rare large samples most renders of a few thousand
//! spp per pixel have not yet drawn, so their mean and estimated error are both low and z is
//! large and negative (seed 11 at 80×60, 4096 spp: z mean −0.17, std 1.21, a cluster of
//! z ≈ −10 at the caustic, while the mean over that region agrees within 0.03 % — skew, not
//! bias). Only more samples per compared pixel cure it, so the comparison pools more: **20×15
//! (16×16 blocks) at 32 768 spp** (9.8 M paths, 16 s on 2 cores), measured z std 0.996, 1.094,
//! 1.011 for seeds 11, 12, 13, ratios within ±0.27 % (± 0.13 %); at 4096 spp z std was 1.22,
//! at 40×30 and 16 384 spp 1.15. On the GPU the same plan is 512 passes of 64 spp — minutes of
//! a software adapter, so that test is ignored in CI and run with `--ignored` on a hardware GPU;
//! in CI the GPU traces the CPU's paths from the same samples on this scene
//! (`tests/integrator.rs`, every environment-sampling mode, within 1.3·10⁻⁵ of the image mean).
//! With compensated environment sampling (the default; the figures above were measured with
//! plain importance sampling) seeds 11, 12, 13 give z std 1.021, 1.119, 1.026 and ratios within
//! +0.05 … +0.18 % (± 0.10 %; the whole image at 320×240 and 65 536 spp is within 5·10⁻⁵ of the
//! reference, BENCHMARKS.md, so that is the caustic's skew again). Seed 11 on the GPU (an H100):
//! ratios 1.0018, 1.0016, 1.0011 (± 0.0010), z std 1.020 — the CPU's figures to the digit.
//!
//! # The glass references
//!
//! `glass/glass_absorb` (an absorbing smooth sphere and a rough α 0.3 sphere) and
//! `glass/glass_box` (a smooth sphere, a rough α 0.1 slab in the sun, a thin-walled sheet),
//! 8 bounces, Mitsuba's `volpath`. The glass box's rough slab focuses the sun into a caustic
//! that floor and wall points see only through rare, bright paths (a refraction into the slab,
//! then a light sample at its upper face inside the narrow refracted lobe): on a wall pixel the
//! top 10⁻⁴ of 2²⁰ samples carry 1.3 % of the mean. Every pixel's estimate is skewed, z's mean
//! sits at −0.3 and its standard deviation at 1.2 from 512 to 8192 spp at any size (64², 32²,
//! 16²), and only the samples per compared pixel cure it. Measured with `cargo run --release -p
//! furnace-tests --example mitsuba_budget -- --backend cpu --glass box|absorb --bounces 8 --size
//! S --seeds N --first-seed F --max-spp M` (z std; ratios within their ± 0.1 %):
//!
//! | scene | size | N = 2048 | N = 8192 | N = 32 768 | N = 65 536 |
//! |---|---|---|---|---|---|
//! | glass box | 32² | 1.217, 1.194 | 1.215, 1.211 | — | — |
//! | glass box | 16² | 1.023, 1.227 | 1.181, 1.214, 1.262, 1.209, 1.243 | 1.119, 1.147, 1.172 | 1.082, 1.075, 1.070 |
//! | glass absorb | 64² | 1.005, 1.020 (N = 1024: 1.021, 1.011) | — | — | — |
//!
//! Hence the **CPU at 16², 4096 passes of 16 spp** for the glass box (16.8 M paths, 20 s alone,
//! so ignored in CI: `glass_box_matches_mitsuba_cpu`; seed
//! 11 gives ratios 1.0001, 1.0000, 0.9999 (± 0.0006), z mean −0.26, z std 1.131) and **64²,
//! 1024 passes of 1 spp** for the absorbing box (4.2 M paths, 6.5 s; 1.0000, 1.0003, 1.0004
//! (± 0.0003), z std 1.005). The GPU test is the full-size one (256², 512 passes of 128 spp,
//! ignored in CI: a software adapter runs glass paths ~7× slower than the box's), run with
//! `--ignored` on a hardware GPU: glass_absorb z std 1.020, glass_box 1.031, ratios within 10⁻⁴
//! (`docs/device/references.sh` scores full-size renders of every reference the same way).
//!
//! ## It can fail
//!
//! `gltf_default_model_fails_the_bar_gpu` renders the 4-bounce configuration with the glTF default
//! material model (height-correlated masking, Turquin compensation) instead of Mitsuba's: only
//! the metal sphere changes, and the test must fail, on the ratio alone. Measured (seed 11,
//! lavapipe): 4 bounces, 256 spp: ratios 1.0280, 1.0210, 1.0145 (± 0.0015), z mean +0.38,
//! z std 1.34; direct, 1024 spp: ratios 1.0158, 1.0128, 1.0095 (± 0.0007), z std 1.95.
//!
//! On failure the candidate, its standard error, the downsampled reference (and its error) and
//! the z image are written to `target/test-output/mitsuba/`, with the table.

use furnace_brdf::SpecularOptions;
use furnace_render::{PointLightSampling, RenderSettings};
use furnace_sampling::SamplerKind;
use furnace_tests::backends::Backend;
use furnace_tests::cbox::{self, Comparison, Estimate, Image, Reference};
use glam::DVec3;
use std::path::PathBuf;
use std::time::Instant;

/// The bar (see the module docs).
const MAX_RATIO_ERROR: f64 = 5e-3;
const Z_STD_RANGE: (f64, f64) = (0.9, 1.15);
/// Fixed seed of the random sampler (see the module docs for the spread over seeds).
const SEED: u32 = 11;

/// What a backend renders: its image size and one-sample passes per reference.
struct Plan {
    /// Width; the height keeps the reference's aspect ratio.
    size: u32,
    bounces: u32,
    passes: u32,
    spp_per_pass: u32,
}

/// The configurations the module docs derive (the point-light box: see there).
fn plan(backend: Backend, stem: &str) -> Plan {
    let (size, bounces, passes, spp_per_pass) = match (backend, stem) {
        (Backend::Cpu, "cbox_ref_direct") => (256, 1, 512, 1),
        (Backend::Cpu, "cbox_ref_bounces4") => (256, 4, 128, 1),
        (Backend::Cpu, "cbox_point_ref_bounces4") => (64, 4, 512, 1),
        (Backend::Cpu, "cbox_area_ref_bounces4") => (64, 4, 512, 1),
        (Backend::Cpu, "cbox_many_lights_ref_bounces4") => (64, 4, 4096, 1),
        (Backend::Cpu, "cbox_sun_disc_ref_bounces4") => (64, 4, 512, 1),
        // The caustic's skew needs many samples per compared pixel (module docs).
        (Backend::Cpu, "envmap_spheres_ref_bounces4") => (20, 4, 32768, 1),
        (Backend::Gpu, "cbox_ref_direct") => (32, 1, 1024, 1),
        (Backend::Gpu, "cbox_ref_bounces4") => (32, 4, 256, 1),
        (Backend::Gpu, "cbox_point_ref_bounces4") => (32, 4, 512, 2),
        (Backend::Gpu, "cbox_area_ref_bounces4") => (32, 4, 256, 2),
        (Backend::Gpu, "cbox_sun_disc_ref_bounces4") => (32, 4, 128, 2),
        (Backend::Gpu, "envmap_spheres_ref_bounces4") => (20, 4, 512, 64),
        // The glass box's caustics skew every pixel's estimate (module docs): 65 536 spp at 16².
        (Backend::Cpu, "glass_box_ref_bounces8") => (16, 8, 4096, 16),
        (Backend::Cpu, "glass_absorb_ref_bounces8") => (64, 8, 1024, 1),
        // Full size on a hardware GPU (ignored in CI), as many samples as the references.
        (Backend::Gpu, "glass_box_ref_bounces8" | "glass_absorb_ref_bounces8") => (256, 8, 512, 128),
        _ => panic!("no plan for {backend}, {stem}"),
    };
    Plan { size, bounces, passes, spp_per_pass }
}

/// The scenes of the references: `cbox_ref_*` is the built-in Cornell box; the others are the
/// glTF files beside their references.
fn case(stem: &str) -> (&'static str, furnace_scene::Scene) {
    match stem {
        "cbox_ref_direct" | "cbox_ref_bounces4" => {
            ("cbox", furnace_scene::builtin::cornell_box().expect("the built-in Cornell box"))
        }
        "cbox_point_ref_bounces4"
        | "cbox_area_ref_bounces4"
        | "cbox_many_lights_ref_bounces4"
        | "cbox_sun_disc_ref_bounces4" => {
            let file = stem.trim_end_matches("_ref_bounces4");
            let path = furnace_tests::data::reference(&format!("lights/{file}.gltf"));
            let scene = furnace_scene::Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
            ("lights", scene)
        }
        "glass_box_ref_bounces8" | "glass_absorb_ref_bounces8" => {
            let file = stem.trim_end_matches("_ref_bounces8");
            let path = furnace_tests::data::reference(&format!("glass/{file}.gltf"));
            let scene = furnace_scene::Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
            ("glass", scene)
        }
        "envmap_spheres_ref_bounces4" => {
            let path = furnace_tests::data::reference("envmap/envmap_spheres.gltf");
            let scene = furnace_scene::Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
            assert!(scene.environment().is_some(), "the scene names its environment map");
            ("envmap", scene)
        }
        _ => panic!("no scene for {stem}"),
    }
}

/// `{stem}.exr` and `{stem}_stderr.exr` of `folder`, downsampled to `size` pixels wide.
fn reference(folder: &str, stem: &str, size: u32) -> Reference {
    let full = Reference::load_in(folder, stem);
    if full.mean.width == size as usize {
        return full;
    }
    cbox::downsample(&full, full.mean.width / size as usize)
}

/// `passes` passes of one sample per pixel on `backend`; each pixel's mean and standard error
/// from its own samples. `None` when GPU tests are skipped.
fn render(
    backend: Backend,
    scene: &furnace_scene::Scene,
    (width, height): (u32, u32),
    bounces: u32,
    (specular, point_lights): (SpecularOptions, PointLightSampling),
    passes: u32,
    spp_per_pass: u32,
) -> Option<Estimate> {
    let settings = RenderSettings {
        width,
        height,
        bounces,
        sampler: SamplerKind::Random,
        seed: SEED,
        specular,
        point_lights,
        ..Default::default()
    };
    let mut integrator = backend.open_default(scene, settings)?;
    Some(cbox::render_passes(integrator.as_mut(), passes, spp_per_pass))
}

fn passes_bar(c: &Comparison) -> bool {
    (c.ratio() - 1.0).abs().max_element() < MAX_RATIO_ERROR
        && (Z_STD_RANGE.0..=Z_STD_RANGE.1).contains(&c.z_std)
}

fn table(
    backend: Backend,
    stem: &str,
    model: &str,
    (size, height, block): (u32, u32, u32),
    passes: (u32, u32),
    c: &Comparison,
    seconds: f64,
) -> String {
    format!(
        "| backend | reference | model | size | passes × spp | ratio R, G, B (± se) | z mean | z std | \\|z\\| > 3 | max \\|z\\| | z values | time |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n\
         | {backend} | {stem} | {model} | {size}×{height} ({block}×{block} blocks) | {} × {} | {} | {seconds:.1} s |",
        passes.0,
        passes.1,
        c.cells()
    )
}

/// A render compared with a (downsampled) reference, and the table that describes it.
struct Outcome {
    name: String,
    reference: Reference,
    candidate: Estimate,
    comparison: Comparison,
    table: String,
}

impl Outcome {
    /// Writes the candidate, its standard error, the reference, its error, the z image and the
    /// table to `target/test-output/mitsuba/`; returns the folder.
    fn write(&self) -> PathBuf {
        let dir = furnace_tests::data::output_dir("mitsuba");
        for (what, image) in [
            ("candidate", &self.candidate.mean),
            ("candidate_stderr", &self.candidate.stderr),
            ("reference", &self.reference.mean),
            ("reference_stderr", &self.reference.stderr),
            ("z", &self.comparison.z_image),
        ] {
            image.write_exr(&dir.join(format!("{}_{what}.exr", self.name)));
        }
        std::fs::write(dir.join(format!("{}.md", self.name)), format!("{}\n", self.table))
            .expect("writing the table");
        dir
    }
}

/// Renders `stem`'s configuration on `backend` with `specular` and compares it with the
/// reference; `None` when GPU tests are skipped.
fn evaluate(
    backend: Backend,
    stem: &str,
    model: (SpecularOptions, PointLightSampling),
    model_name: &str,
) -> Option<Outcome> {
    let plan = plan(backend, stem);
    let (bounces, passes) = (plan.bounces, plan.passes);
    let (folder, scene) = case(stem);
    let full_width = Reference::load_in(folder, stem).mean.width as u32;
    let reference = reference(folder, stem, plan.size);
    let height = reference.mean.height as u32;
    let start = Instant::now();
    let candidate = render(backend, &scene, (plan.size, height), bounces, model, passes, plan.spp_per_pass)?;
    let seconds = start.elapsed().as_secs_f64();
    let mask = cbox::pixels_without_visible_emitters(&scene, plan.size);
    let comparison = cbox::compare_masked(&candidate, &reference, mask.as_deref());
    let shape = (plan.size, height, full_width / plan.size);
    let table = table(backend, stem, model_name, shape, (passes, plan.spp_per_pass), &comparison, seconds);
    println!("{table}");
    let name = format!("{stem}_{backend}_{}_{model_name}", plan.size).replace(' ', "_");
    Some(Outcome { name, reference, candidate, comparison, table })
}

fn compare(backend: Backend, stem: &str) {
    compare_with(backend, stem, PointLightSampling::default());
}

/// [`compare`] with the point lights gathered by `point_lights`.
fn compare_with(backend: Backend, stem: &str, point_lights: PointLightSampling) {
    let model = match point_lights {
        PointLightSampling::One => "Mitsuba, one point light per event",
        _ => "Mitsuba",
    };
    let Some(o) = evaluate(backend, stem, (SpecularOptions::mitsuba(), point_lights), model) else { return };
    let c = &o.comparison;
    if !passes_bar(c) {
        let dir = o.write();
        panic!(
            "{backend}, {stem}: ratio {:.5} (bar ±{MAX_RATIO_ERROR}), z std {:.3} (bar {Z_STD_RANGE:?}); \
             candidate, its standard error, the reference, z images and the table in {}",
            c.ratio(),
            c.z_std,
            dir.display()
        );
    }
}

/// The bar is sharp enough to see a wrong material model: the glTF default (height-correlated
/// masking, Turquin compensation) instead of Mitsuba's, on the metal sphere only, at the
/// 4-bounce test's settings. It must fail the ratio part of the bar (by itself: measured 1.028
/// for red, ±0.0015, on the GPU), not just the noisier z part.
fn gltf_default_model_fails(backend: Backend) {
    let stem = "cbox_ref_bounces4";
    let Some(o) =
        evaluate(backend, stem, (SpecularOptions::default(), PointLightSampling::All), "glTF default")
    else {
        return;
    };
    let c = &o.comparison;
    let worst = (c.ratio() - 1.0).abs().max_element();
    if worst < MAX_RATIO_ERROR {
        let dir = o.write();
        panic!(
            "{backend}: the glTF default model came within the bar on the ratio: {:.5} (bar ±{MAX_RATIO_ERROR}), \
             z std {:.3}: the test cannot tell the models apart; images and table in {}",
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
    let d = cbox::downsample(&r, 2);
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
fn cornell_box_direct_matches_mitsuba_cpu() {
    compare(Backend::Cpu, "cbox_ref_direct");
}

#[test]
fn cornell_box_four_bounces_matches_mitsuba_cpu() {
    compare(Backend::Cpu, "cbox_ref_bounces4");
}

#[test]
fn cornell_box_direct_matches_mitsuba_gpu() {
    compare(Backend::Gpu, "cbox_ref_direct");
}

#[test]
fn cornell_box_four_bounces_matches_mitsuba_gpu() {
    compare(Backend::Gpu, "cbox_ref_bounces4");
}

#[test]
fn point_lights_match_mitsuba_cpu() {
    compare(Backend::Cpu, "cbox_point_ref_bounces4");
}

#[test]
fn point_lights_match_mitsuba_gpu() {
    compare(Backend::Gpu, "cbox_point_ref_bounces4");
}

/// One point light per event, chosen by power (`--point-lights one`), as Mitsuba chooses one
/// emitter per event (uniformly there): the same expectation, more noise per sample, which z
/// measures against the candidate's own standard error.
#[test]
fn point_lights_one_per_event_match_mitsuba_cpu() {
    compare_with(Backend::Cpu, "cbox_point_ref_bounces4", PointLightSampling::One);
}

#[test]
fn point_lights_one_per_event_match_mitsuba_gpu() {
    compare_with(Backend::Gpu, "cbox_point_ref_bounces4", PointLightSampling::One);
}

#[test]
fn emissive_quad_matches_mitsuba_cpu() {
    compare(Backend::Cpu, "cbox_area_ref_bounces4");
}

#[test]
fn emissive_quad_matches_mitsuba_gpu() {
    compare(Backend::Gpu, "cbox_area_ref_bounces4");
}

#[test]
fn many_emitters_match_mitsuba_cpu() {
    compare(Backend::Cpu, "cbox_many_lights_ref_bounces4");
}

#[test]
fn sun_disc_matches_mitsuba_cpu() {
    compare(Backend::Cpu, "cbox_sun_disc_ref_bounces4");
}

#[test]
fn sun_disc_matches_mitsuba_gpu() {
    compare(Backend::Gpu, "cbox_sun_disc_ref_bounces4");
}

#[test]
fn environment_map_matches_mitsuba_cpu() {
    compare(Backend::Cpu, "envmap_spheres_ref_bounces4");
}

#[test]
#[ignore = "32 768 spp: minutes on a software adapter; run with --ignored on a hardware GPU"]
fn environment_map_matches_mitsuba_gpu() {
    compare(Backend::Gpu, "envmap_spheres_ref_bounces4");
}

#[test]
fn glass_matches_mitsuba_cpu() {
    compare(Backend::Cpu, "glass_absorb_ref_bounces8");
}

#[test]
#[ignore = "65 536 spp per pixel (the caustic's skew, above): 20 s alone, about 50 s of CI's 2 busy cores; \
            CI traces the glass box on both backends from the same samples (tests/integrator.rs) and checks \
            its interfaces in closed form (glass_cases/closed_forms.rs); run with --ignored"]
fn glass_box_matches_mitsuba_cpu() {
    compare(Backend::Cpu, "glass_box_ref_bounces8");
}

#[test]
#[ignore = "full size, 65 536 spp: a hardware GPU's work (run with --ignored); in CI the GPU traces the CPU's paths (tests/integrator.rs)"]
fn glass_matches_mitsuba_gpu() {
    compare(Backend::Gpu, "glass_absorb_ref_bounces8");
    compare(Backend::Gpu, "glass_box_ref_bounces8");
}

#[test]
fn gltf_default_model_fails_the_bar_cpu() {
    gltf_default_model_fails(Backend::Cpu);
}

#[test]
fn gltf_default_model_fails_the_bar_gpu() {
    gltf_default_model_fails(Backend::Gpu);
}
