//! What the viewer draws and how it restarts, without a window:
//!
//! 1. `FilmPresenter` draws a rendered film into a texture (both 8-bit formats, both film
//!    precisions) with the codes `furnace_post::to_srgb8` gives the film read back: equal, or
//!    one code apart where the exact value lies on a rounding boundary (the WGSL twin's floats
//!    are within 4e-6 of post's, `display_parity.rs`), at most 1 % of channels; the film
//!    centred in a larger target, the background around it.
//! 2. `NoiseEstimator` against an independent measure of the same noise: for two renders of
//!    independent seeds, E[(l_a − l_b)²] = 2 se² per pixel, so √(mean (l_a − l_b)² / 2) is the
//!    RMS standard error; they agree within 10 % (4096 pixels: the measure's own spread is
//!    about √(2/4096) ≈ 2 %, ×5 for margin), and the estimate halves (±10 %) from 16 to 64 spp.
//! 3. The viewer's restarts render what a new renderer renders: `set_camera` + `clear_film`,
//!    and `reconfigure` with other settings, give films bit-identical to a `GpuRenderer` made
//!    with that camera / those settings (the same samples, summed in the same order).

use furnace_gpu::GpuRenderer;
use furnace_gpu::film::{FilmPrecision, GpuFilm};
use furnace_gpu::present::{BACKGROUND, FilmPresenter, NoiseEstimator, Placement};
use furnace_post::{Tonemap, to_srgb8};
use furnace_render::{Film, RenderSettings};
use furnace_sampling::SamplerKind;
use furnace_scene::{Camera, builtin};
use furnace_tests::gpu::test_context;
use glam::Vec3;

fn settings(size: u32, seed: u32) -> RenderSettings {
    RenderSettings {
        width: size,
        height: size,
        sampler: SamplerKind::Random,
        seed,
        ..RenderSettings::default()
    }
}

/// Compares drawn codes with post's codes of the film; returns the channels one code apart.
fn compare_codes(drawn: &[[u8; 4]], film: &Film, ev: f32, tonemap: Tonemap, what: &str) -> usize {
    let radiance: Vec<Vec3> = film.to_rgb_f32().chunks_exact(3).map(Vec3::from_slice).collect();
    let expected = to_srgb8(&radiance, ev, tonemap);
    let mut off_by_one = 0;
    for (i, (d, e)) in drawn.iter().zip(&expected).enumerate() {
        for c in 0..3 {
            let diff = (i32::from(d[c]) - i32::from(e[c])).abs();
            assert!(
                diff <= 1,
                "{what}: pixel {i} channel {c}: drawn {} but post gives {} (film {:?})",
                d[c],
                e[c],
                radiance[i]
            );
            off_by_one += diff as usize;
        }
    }
    let channels = 3 * expected.len();
    assert!(
        off_by_one * 100 <= channels,
        "{what}: {off_by_one} of {channels} channels one code off (more than 1 %: not rounding)"
    );
    off_by_one
}

#[test]
fn the_presenter_draws_posts_codes_of_the_film() {
    let Some(ctx) = test_context() else { return };
    let scene = builtin::cornell_box().unwrap();
    let size = 48;
    let mut gpu = GpuRenderer::new(ctx, &scene, &scene.default_camera(), settings(size, 3)).unwrap();
    gpu.render_pass(0, 4).unwrap();
    gpu.enable_display().unwrap();
    let film = gpu.film().unwrap();
    let place = Placement::fit((size, size), (size, size));
    assert_eq!(place, Placement { origin: [0.0, 0.0], step: 1.0 });
    for format in [wgpu::TextureFormat::Bgra8Unorm, wgpu::TextureFormat::Rgba8Unorm] {
        let p = FilmPresenter::new(gpu.context(), gpu.film_precision(), format).unwrap();
        for (ev, tonemap) in [(0.0, Tonemap::Aces), (1.5, Tonemap::PbrNeutral), (-1.0, Tonemap::Clamp)] {
            let drawn =
                p.render_to_rgba8(gpu.context(), gpu.gpu_film(), &place, ev, tonemap, (size, size)).unwrap();
            let off = compare_codes(&drawn, &film, ev, tonemap, &format!("{format:?} {tonemap} {ev} EV"));
            eprintln!("{format:?} {tonemap} {ev:+} EV: {off} channels one code off of {}", 3 * size * size);
        }
    }

    // In a larger target: centred, the background around it.
    let p = FilmPresenter::new(gpu.context(), gpu.film_precision(), wgpu::TextureFormat::Rgba8Unorm).unwrap();
    let (tw, th) = (size + 20, size + 7);
    let place = Placement::fit((size, size), (tw, th));
    assert_eq!(place.origin, [10.0, 3.0]);
    let drawn =
        p.render_to_rgba8(gpu.context(), gpu.gpu_film(), &place, 0.0, Tonemap::Aces, (tw, th)).unwrap();
    let bg = BACKGROUND.map(|v| (v * 255.0).round() as u8);
    assert_eq!(drawn[0][..3], bg[..3], "the corner is background");
    let inner: Vec<[u8; 4]> = (0..size)
        .flat_map(|y| (0..size).map(move |x| ((y + 3) * tw + x + 10) as usize))
        .map(|i| drawn[i])
        .collect();
    compare_codes(&inner, &film, 0.0, Tonemap::Aces, "centred");

    // A film shown at half size samples every other pixel.
    let half = Placement::fit((size, size), (size / 2, size / 2));
    assert_eq!(half.step, 2.0);
    assert_eq!(half.film_pixel((size, size), 3, 5), Some((7, 11)));
}

#[test]
fn the_presenter_draws_f32_films_from_their_folded_means() {
    let Some(ctx) = test_context() else { return };
    let (w, h) = (13, 7);
    let mut film = Film::new(w, h);
    for y in 0..h {
        for x in 0..w {
            for k in 0..3 {
                film.add_sample(x, y, Vec3::new(0.01 * x as f32, 0.3 * k as f32, 0.05 * (x + y) as f32));
            }
        }
    }
    film.add_sample(0, 0, Vec3::splat(f32::NAN));
    let mut gpu_film = GpuFilm::new(&ctx, w, h, FilmPrecision::F32Pass).unwrap();
    assert!(gpu_film.display_source().is_none(), "no display buffer until asked for");
    gpu_film.write(&ctx, &film).unwrap();
    gpu_film.enable_display(&ctx).unwrap();
    assert!(!gpu_film.has_squares());
    let p = FilmPresenter::new(&ctx, FilmPrecision::F32Pass, wgpu::TextureFormat::Rgba8Unorm).unwrap();
    let drawn = p
        .render_to_rgba8(&ctx, &gpu_film, &Placement::fit((w, h), (w, h)), 0.5, Tonemap::Aces, (w, h))
        .unwrap();
    compare_codes(&drawn, &film, 0.5, Tonemap::Aces, "f32 film");
    // A presenter of the other precision refuses it.
    if ctx.shader_f64 {
        let p64 = FilmPresenter::new(&ctx, FilmPrecision::F64, wgpu::TextureFormat::Rgba8Unorm).unwrap();
        assert!(
            p64.render_to_rgba8(&ctx, &gpu_film, &Placement::fit((w, h), (w, h)), 0.0, Tonemap::Aces, (w, h))
                .is_err()
        );
    }
}

/// Luminance of each pixel's mean.
fn luminances(film: &Film) -> Vec<f64> {
    (0..film.sums().len()).map(|i| film.mean(i).dot(glam::DVec3::new(0.2126, 0.7152, 0.0722))).collect()
}

#[test]
fn the_noise_estimate_matches_the_spread_of_independent_renders() {
    let Some(ctx) = test_context() else { return };
    if !ctx.shader_f64 {
        eprintln!("no f64 shaders: the film keeps no squares, no noise estimate to test");
        return;
    }
    let scene = builtin::cornell_box().unwrap();
    let camera = scene.default_camera();
    let size = 64;
    let estimator = NoiseEstimator::new(&ctx).unwrap().expect("f64 device");
    let mut a = GpuRenderer::new(ctx, &scene, &camera, settings(size, 1)).unwrap();
    let ctx_b = test_context().unwrap();
    let mut b = GpuRenderer::new(ctx_b, &scene, &camera, settings(size, 2)).unwrap();
    let at = |spp: u32, a: &mut GpuRenderer, b: &mut GpuRenderer| {
        a.render_pass(0, spp).unwrap();
        b.render_pass(0, spp).unwrap();
        let est = estimator.estimate(a.context(), a.gpu_film()).unwrap().expect("pixels with samples");
        let (la, lb) = (luminances(&a.film().unwrap()), luminances(&b.film().unwrap()));
        let spread =
            (la.iter().zip(&lb).map(|(x, y)| (x - y) * (x - y)).sum::<f64>() / la.len() as f64 / 2.0).sqrt();
        eprintln!(
            "{spp} spp: estimated RMS standard error {:.5}, measured from two renders {spread:.5}; relative {:.4}",
            est.rms_standard_error,
            est.relative().unwrap()
        );
        assert_eq!(est.pixels, u64::from(size * size));
        assert!(
            (est.rms_standard_error / spread - 1.0).abs() < 0.1,
            "{spp} spp: estimate {} vs measured {spread}",
            est.rms_standard_error
        );
        a.clear_film().unwrap();
        b.clear_film().unwrap();
        est.rms_standard_error
    };
    let e16 = at(16, &mut a, &mut b);
    let e64 = at(64, &mut a, &mut b);
    assert!((e16 / e64 / 2.0 - 1.0).abs() < 0.1, "4× the samples halves the error: {e16} → {e64}");
    // A film loaded from a saved one has no squares: no estimate rather than a wrong one.
    let saved = a.film().unwrap();
    a.load_film(&saved).unwrap();
    assert!(a.gpu_film().has_squares(), "an empty film has all its squares (none)");
    a.render_pass(0, 2).unwrap();
    let saved = a.film().unwrap();
    a.load_film(&saved).unwrap();
    assert_eq!(estimator.estimate(a.context(), a.gpu_film()).unwrap(), None);
}

fn same_film(a: &Film, b: &Film, what: &str) {
    assert_eq!(a.counts(), b.counts(), "{what}: counts");
    let same = a
        .sums()
        .iter()
        .zip(b.sums())
        .all(|(x, y)| x.to_array().map(f64::to_bits) == y.to_array().map(f64::to_bits));
    assert!(same, "{what}: the sums differ");
}

#[test]
fn restarts_render_what_a_new_renderer_renders() {
    let Some(ctx) = test_context() else { return };
    let scene = builtin::cornell_box().unwrap();
    let start = scene.default_camera();
    let moved = Camera::look_at(Vec3::new(0.3, 1.1, 3.2), Vec3::new(0.0, 0.9, 0.0), Vec3::Y, 0.7);
    let s = settings(24, 5);
    let mut viewer = GpuRenderer::new(ctx, &scene, &start, s).unwrap();
    viewer.enable_display().unwrap();
    viewer.render_pass(0, 3).unwrap();
    // A camera move: set_camera + clear_film.
    viewer.set_camera(&moved);
    viewer.clear_film().unwrap();
    viewer.render_pass(0, 2).unwrap();
    viewer.render_pass(2, 3).unwrap();
    let mut fresh = GpuRenderer::new(test_context().unwrap(), &scene, &moved, s).unwrap();
    fresh.render_pass(0, 5).unwrap();
    same_film(&viewer.film().unwrap(), &fresh.film().unwrap(), "after a camera move");

    // A settings change (bounces, sampler, light sampling, size): reconfigure.
    let t = RenderSettings {
        width: 20,
        height: 16,
        bounces: 2,
        sampler: SamplerKind::Sobol,
        light_sampling: furnace_render::LightSampling::Bsdf,
        ..s
    };
    viewer.reconfigure(&scene, &moved, t).unwrap();
    assert_eq!((viewer.gpu_film().width(), viewer.gpu_film().height()), (20, 16));
    assert!(viewer.gpu_film().display_source().is_some(), "the display survives a new film");
    viewer.render_pass(0, 4).unwrap();
    let mut fresh = GpuRenderer::new(test_context().unwrap(), &scene, &moved, t).unwrap();
    fresh.render_pass(0, 4).unwrap();
    same_film(&viewer.film().unwrap(), &fresh.film().unwrap(), "after reconfigure");

    // A scene of other geometry is refused.
    let other = builtin::sunlit_interior(2000);
    assert!(viewer.reconfigure(&other, &moved, t).is_err());
}
