//! Adaptive sampling (`RenderSettings::adaptive`): pixels stop once their noise is below a
//! threshold, tested every `ADAPTIVE_STEP` samples.
//!
//! 1. The rule depends only on each pixel's sums at fixed sample indices: the film is the same,
//!    bit for bit, however the render is cut into passes (CPU, and GPU with an f64 film), and a
//!    resumed film continues exactly.
//! 2. A converged pixel takes no more samples: its sums never change again.
//! 3. The GPU's marks (tested on the GPU for an f64 film, on the host for an f32 one) are the
//!    CPU's, sample for sample.
//! 4. The bias of stopping early, measured: converged pixels against an independent 16× longer
//!    render, as z-scores of their own standard errors.

use furnace_cpu::CpuRenderer;
use furnace_gpu::GpuRenderer;
use furnace_render::{AdaptiveSampling, Film, Integrator, RenderSettings, relative_noise};
use furnace_sampling::SamplerKind;
use furnace_scene::builtin;
use furnace_tests::gpu::test_context;

const SIZE: u32 = 16;
/// 8 %: at 16×16 and up to 48 spp some of the Cornell box's pixels converge (the smooth walls)
/// and some do not (the sunlit floor's soft shadow edges, the sphere's reflections), so both
/// branches of every test below are exercised (asserted).
const RULE: AdaptiveSampling = AdaptiveSampling { threshold: 0.08, min_samples: 16 };

fn settings(seed: u32) -> RenderSettings {
    RenderSettings {
        width: SIZE,
        height: SIZE,
        sampler: SamplerKind::Sobol,
        seed,
        adaptive: Some(RULE),
        ..RenderSettings::default()
    }
}

fn cpu_film(passes: &[u32], s: RenderSettings) -> Film {
    let cpu = CpuRenderer::with_default_camera(builtin::cornell_box().unwrap(), s).unwrap();
    let mut film = cpu.new_film();
    let mut first = 0;
    for &n in passes {
        cpu.render_into(&mut film, first, n).unwrap();
        first += n;
    }
    film
}

#[test]
fn cpu_adaptive_films_do_not_depend_on_pass_cuts() {
    let whole = cpu_film(&[48], settings(1));
    let converged = whole.converged_count().unwrap();
    let pixels = u64::from(SIZE * SIZE);
    eprintln!("{converged}/{pixels} pixels converged at 48 spp");
    assert!(converged > pixels / 10 && converged < pixels * 9 / 10, "{converged}/{pixels}");
    for cuts in [&[4; 12][..], &[13, 20, 15], &[1, 7, 8, 31, 1]] {
        assert!(cpu_film(cuts, settings(1)) == whole, "passes {cuts:?} give another film");
    }
}

#[test]
fn converged_pixels_take_no_more_samples() {
    let cpu = CpuRenderer::with_default_camera(builtin::cornell_box().unwrap(), settings(2)).unwrap();
    let mut film = cpu.new_film();
    cpu.render_into(&mut film, 0, 32).unwrap();
    let before = film.clone();
    cpu.render_into(&mut film, 32, 32).unwrap();
    let marks = before.converged().unwrap();
    let mut still = 0;
    for (i, &marked) in marks.iter().enumerate() {
        if marked {
            assert_eq!(film.sums()[i], before.sums()[i], "converged pixel {i} changed");
            assert_eq!(film.counts()[i], before.counts()[i]);
        } else {
            // Still sampling at 32: at least up to the next test, at 40 (it may converge there).
            still += 1;
            assert!(film.counts()[i] >= 40, "pixel {i} stopped early: {} samples", film.counts()[i]);
        }
    }
    // A pixel marks itself only when its noise was below the threshold at a test.
    for (i, &marked) in marks.iter().enumerate() {
        if marked {
            let noise =
                relative_noise(before.sums()[i], before.lum_sq_sums().unwrap()[i], before.counts()[i]);
            assert!(noise < f64::from(RULE.threshold), "pixel {i}: noise {noise}");
            assert!(before.counts()[i] >= u64::from(RULE.min_samples));
        }
    }
    assert!(still > 0 && still < marks.len(), "{still} pixels still sampling");
}

#[test]
fn gpu_adaptive_sampling_matches_the_cpu_and_resumes_exactly() {
    let scene = builtin::cornell_box().unwrap();
    let camera = scene.default_camera();
    let cpu = cpu_film(&[48], settings(3));
    let n = cpu.counts().len();
    for f64_film in [true, false] {
        let Some(mut ctx) = test_context() else { return };
        ctx.shader_f64 &= f64_film;
        let mut gpu = GpuRenderer::new(ctx, &scene, &camera, settings(3)).unwrap();
        gpu.render_pass(0, 20).unwrap();
        gpu.render_pass(20, 28).unwrap();
        let g = Integrator::film(&mut gpu).unwrap();
        let (gm, cm) = (g.converged().unwrap(), cpu.converged().unwrap());
        let same = gm.iter().zip(cm).filter(|(a, b)| a == b).count();
        eprintln!(
            "{:?} film: {same}/{n} marks as the CPU's; converged GPU {} CPU {}; the integrator says {:?}",
            gpu.film_precision(),
            g.converged_count().unwrap(),
            cpu.converged_count().unwrap(),
            gpu.converged_pixels()
        );
        assert_eq!(gpu.converged_pixels(), g.converged_count());
        // The same samples give the same decisions, except where a path parts at an ulp (see
        // integrator.rs) and moves a pixel's noise across the threshold: at most 2 %.
        assert!(same * 100 >= n * 98, "only {same}/{n} marks agree");
        // Converged pixels stopped at the test that marked them: a multiple of 8 samples from
        // 16 on (the box has no rejected samples).
        for (i, &marked) in gm.iter().enumerate() {
            let c = g.counts()[i];
            if marked {
                assert!(
                    c.is_multiple_of(8) && (16..=48).contains(&c),
                    "pixel {i}: converged with {c} samples"
                );
            } else {
                assert_eq!(c, 48, "pixel {i}");
            }
        }
        if f64_film {
            // Other pass cuts, and a film resumed in a new renderer: the same film, bit for bit.
            let Some(ctx) = test_context() else { return };
            let mut other = GpuRenderer::new(ctx, &scene, &camera, settings(3)).unwrap();
            for (first, count) in [(0, 7), (7, 17)] {
                other.render_pass(first, count).unwrap();
            }
            let saved = other.film().unwrap();
            let Some(ctx) = test_context() else { return };
            let mut resumed = GpuRenderer::new(ctx, &scene, &camera, settings(3)).unwrap();
            resumed.load_film(&saved).unwrap();
            resumed.render_pass(24, 24).unwrap();
            assert!(resumed.film().unwrap() == g, "cut and resumed GPU film differs");
        }
    }
}

/// Stopping on a pixel's own samples favours pixels whose samples happened to agree. Measured:
/// each converged pixel's mean against an independent render of 16× as many samples, in units
/// of the converged pixel's own (iid) standard error. Unbiased stopping gives z of mean 0; the
/// bound |z̄| < 0.25 over ~100 values (the mean of 100 unit-spread z has a spread of 0.1, so
/// 2.5σ) flags a bias of a quarter of a standard error, the size the minimum of 16 samples is
/// there to keep away (measured: z̄ = −0.009; the spread is 0.65, not 1, because Sobol points
/// err less than the iid estimate says).
#[test]
fn stopping_early_costs_little_bias() {
    const SPP: u32 = 64;
    let s = RenderSettings { width: 32, height: 32, ..settings(4) };
    let adaptive = {
        let cpu = CpuRenderer::with_default_camera(builtin::cornell_box().unwrap(), s).unwrap();
        let mut film = cpu.new_film();
        cpu.render_into(&mut film, 0, SPP).unwrap();
        film
    };
    let reference = {
        let r = RenderSettings { adaptive: None, sampler: SamplerKind::Random, seed: 99, ..s };
        let cpu = CpuRenderer::with_default_camera(builtin::cornell_box().unwrap(), r).unwrap();
        let mut film = cpu.new_film();
        cpu.render_into(&mut film, 0, 16 * SPP).unwrap();
        film
    };
    let (marks, sq) = (adaptive.converged().unwrap(), adaptive.lum_sq_sums().unwrap());
    let w = glam::DVec3::from(furnace_render::LUMINANCE.map(f64::from));
    let mut zs = Vec::new();
    for i in 0..marks.len() {
        let n = adaptive.counts()[i] as f64;
        let mean = adaptive.sums()[i].dot(w) / n;
        let var = ((sq[i] - n * mean * mean) / (n - 1.0)).max(0.0) / n;
        if marks[i] && var > 0.0 {
            let r = reference.mean(i).dot(w);
            zs.push((mean - r) / var.sqrt());
        }
    }
    let k = zs.len() as f64;
    let zmean = zs.iter().sum::<f64>() / k;
    let zstd = (zs.iter().map(|z| (z - zmean).powi(2)).sum::<f64>() / k).sqrt();
    let total = |f: &Film| (0..marks.len()).map(|i| f.mean(i).dot(w)).sum::<f64>();
    let ratio = total(&adaptive) / total(&reference);
    let taken = adaptive.counts().iter().sum::<u64>() as f64 / (marks.len() as f64 * f64::from(SPP));
    eprintln!(
        "{} of {} pixels converged; their z against a 16× render: mean {zmean:.3}, std {zstd:.3}; image mean ratio {ratio:.4}; {:.1} % of the samples taken",
        zs.len(),
        marks.len(),
        100.0 * taken
    );
    assert!(zs.len() > 100, "too few converged pixels to measure: {}", zs.len());
    assert!(zmean.abs() < 0.25, "converged pixels are biased: mean z {zmean}");
    // The whole image: within 1 % (the reference's own noise is ~0.2 %).
    assert!((ratio - 1.0).abs() < 0.01, "image mean ratio {ratio}");
}
