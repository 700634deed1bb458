//! [`MultiGpuRenderer`] on two devices of one adapter (Mesa's software Vulkan exposes one adapter per
//! process; two devices opened on it are as separate as two GPUs: their own queues, memory and
//! loss). Every film is checked **bit for bit** against single-device renderers given the same
//! sample ranges in the same order and added on the host the same way: the share of each
//! device, the re-rendering of a retired device's samples, and the collection at each read are
//! all deterministic, so nothing here needs a tolerance.
//!
//! A device is lost with `wgpu::Device::destroy`, as in `errors.rs`.

use furnace_gpu::{GpuContext, GpuError, GpuRenderer, MultiGpuRenderer};
use furnace_render::{AdaptiveSampling, Film, Integrator, RenderSettings, SampleRange};
use furnace_scene::{Scene, builtin};
use furnace_tests::gpu::test_context;

fn settings() -> RenderSettings {
    RenderSettings { width: 12, height: 10, bounces: 3, ..RenderSettings::default() }
}

fn scene() -> Scene {
    builtin::cornell_box().unwrap()
}

/// Two devices on the test adapter, or `None` where GPU tests are skipped.
fn two_contexts() -> Option<Vec<GpuContext>> {
    Some(vec![test_context()?, test_context()?])
}

fn multi(contexts: Vec<GpuContext>, settings: RenderSettings) -> MultiGpuRenderer {
    let scene = scene();
    MultiGpuRenderer::new(contexts, &scene, &scene.default_camera(), settings).unwrap()
}

/// The film of one device rendering `ranges` in order (one pass each).
fn single(ranges: &[(u32, u32)], settings: RenderSettings) -> Film {
    let scene = scene();
    let mut r = GpuRenderer::new(test_context().unwrap(), &scene, &scene.default_camera(), settings).unwrap();
    for &(a, b) in ranges {
        r.render_pass(a, b - a).unwrap();
    }
    r.film().unwrap()
}

/// `films` added in order into an empty film, as the multi-device renderer collects them.
fn added(films: &[Film]) -> Film {
    let mut sum = Film::for_settings(&settings());
    for f in films {
        sum.add_film(f).unwrap();
    }
    sum
}

/// Asserts two films hold the same bits: sums, counts and rejections.
fn assert_same(what: &str, a: &Film, b: &Film) {
    assert_eq!(a.counts(), b.counts(), "{what}: counts");
    assert_eq!(a.rejected(), b.rejected(), "{what}: rejected");
    let bits = |f: &Film| f.sums().iter().flat_map(|s| s.to_array().map(f64::to_bits)).collect::<Vec<_>>();
    if let Some(i) = bits(a).iter().zip(bits(b)).position(|(x, y)| *x != y) {
        panic!(
            "{what}: sums differ first at pixel {}: {:?} vs {:?}",
            i / 3,
            a.sums()[i / 3],
            b.sums()[i / 3]
        );
    }
}

#[test]
fn two_devices_add_up_to_their_shares() {
    let Some(contexts) = two_contexts() else { return };
    let mut m = multi(contexts, settings());
    assert_eq!(m.device_count(), 2);
    assert!(m.describe().starts_with("gpus: 2 × "), "{}", m.describe());
    // Passes 0..3 and 3..7: the first device takes 0..2 (1.5 rounded) and 3..5, the second 2..3
    // and 5..7.
    m.render_pass(0, 3).unwrap();
    m.render_pass(3, 4).unwrap();
    let film = m.film().unwrap();
    assert!(film.counts().iter().all(|&c| c == 7), "every pixel has 7 samples");
    let expected = added(&[single(&[(0, 2), (3, 5)], settings()), single(&[(2, 3), (5, 7)], settings())]);
    assert_same("two devices", &film, &expected);
    // The load: each device's pixel samples are its shares (4 and 3 samples of 12 × 10),
    // each busy for part of the shares' time, and one collection counted.
    let load = m.load();
    let samples: Vec<f64> = load.devices.iter().map(|d| d.pixel_samples).collect();
    assert_eq!(samples, [4.0 * 120.0, 3.0 * 120.0]);
    for d in &load.devices {
        // A device's time is inside its share's, which starts before and ends after it.
        assert!(d.busy_seconds > 0.0 && d.busy_seconds <= load.shares_seconds, "{load:?}");
    }
    assert!((0.0..1.0).contains(&load.idle()) && load.collect_seconds > 0.0, "{load:?}");
    m.reset_load();
    let zero = m.load();
    assert!(zero.devices.iter().all(|d| d.pixel_samples == 0.0 && d.busy_seconds == 0.0));
    assert_eq!((zero.shares_seconds, zero.collect_seconds), (0.0, 0.0));
    // Reading the film collects it: a second read without passes is the same film.
    assert_same("read twice", &m.film().unwrap(), &film);
    assert!(m.take_retirements().is_empty());
}

#[test]
fn a_lost_device_leaves_its_samples_to_the_other() {
    let Some(contexts) = two_contexts() else { return };
    let mut m = multi(contexts, settings());
    m.render_pass(0, 4).unwrap();
    m.renderers().nth(1).unwrap().context().device.destroy();
    m.render_pass(4, 2).unwrap();
    assert_eq!(m.device_count(), 1);
    let retired = m.take_retirements();
    assert_eq!(retired.len(), 1);
    let r = &retired[0];
    assert_eq!(r.index, 1);
    assert!(matches!(r.error, GpuError::DeviceLost(_)), "{:?}", r.error);
    let lost = [SampleRange::new(2, 4).unwrap(), SampleRange::new(5, 6).unwrap()];
    assert_eq!(r.rerendered, lost);
    let message = r.to_string();
    assert!(message.contains("GPU 1") && message.contains("2..4, 5..6"), "{message}");
    let film = m.film().unwrap();
    assert!(film.counts().iter().all(|&c| c == 6), "the render finishes: every pixel has 6 samples");
    // The survivor rendered 0..2 and 4..5, then the lost device's 2..4 and 5..6.
    assert_same("after a loss", &film, &added(&[single(&[(0, 2), (4, 5), (2, 4), (5, 6)], settings())]));
}

#[test]
fn the_samples_collected_before_a_loss_are_kept() {
    let Some(contexts) = two_contexts() else { return };
    let mut m = multi(contexts, settings());
    m.render_pass(0, 2).unwrap();
    let first = m.film().unwrap();
    m.renderers().next().unwrap().context().device.destroy();
    m.render_pass(2, 2).unwrap();
    let film = m.film().unwrap();
    assert!(film.counts().iter().all(|&c| c == 4));
    // Device 0 held nothing since the collection but its share 2..3: only that is redone.
    assert_eq!(m.take_retirements()[0].rerendered, [SampleRange::new(2, 3).unwrap()]);
    let mut expected = first;
    expected.add_film(&single(&[(3, 4), (2, 3)], settings())).unwrap();
    assert_same("collected, then a loss", &film, &expected);
}

#[test]
fn every_device_lost_is_an_error_and_a_device_lost_at_opening_is_left_out() {
    let Some(contexts) = two_contexts() else { return };
    contexts[0].device.destroy();
    let mut m = multi(contexts, settings());
    assert_eq!((m.device_count(), m.opened_count()), (1, 2));
    let retired = m.take_retirements();
    assert_eq!(retired.len(), 1);
    assert_eq!((retired[0].index, retired[0].rerendered.len()), (0, 0));
    m.render_pass(0, 2).unwrap();
    assert_same("one of two opened", &m.film().unwrap(), &single(&[(0, 2)], settings()));
    m.renderers().next().unwrap().context().device.destroy();
    let e = m.render_pass(2, 1).unwrap_err().to_string();
    assert!(e.contains("every GPU of the render failed"), "{e}");
}

#[test]
fn a_resumed_film_continues_as_a_collected_one() {
    let Some(contexts) = two_contexts() else { return };
    // One run that reads its film after the first pass, and one that stops there and resumes
    // on new devices: the same collections in the same order, so the same bits.
    let mut whole = multi(contexts, settings());
    whole.render_pass(0, 2).unwrap();
    let saved = whole.film().unwrap();
    whole.render_pass(2, 3).unwrap();
    let mut resumed = multi(two_contexts().unwrap(), settings());
    resumed.set_film(&saved).unwrap();
    resumed.render_pass(2, 3).unwrap();
    assert_same("resumed", &resumed.film().unwrap(), &whole.film().unwrap());
    assert!(resumed.set_film(&Film::new(4, 4)).is_err(), "a film of another size");
}

#[test]
fn fixed_n_samplers_stop_at_n() {
    let Some(contexts) = two_contexts() else { return };
    let fixed = RenderSettings {
        sampler: furnace_sampling::SamplerKind::Hammersley,
        sample_count: Some(4),
        ..settings()
    };
    let mut m = multi(contexts, fixed);
    m.render_pass(0, 4).unwrap();
    let e = m.render_pass(4, 1).unwrap_err();
    assert!(matches!(e, furnace_render::RenderError::Sampler(_)), "{e:?}");
    assert_eq!(m.device_count(), 2, "a sampler error retires no device");
}

/// Adaptive sampling on two devices tests the sum of their films: the same pixels converge at
/// the same test points as on one device (the same samples; a decision could only differ for a
/// pixel within rounding of the threshold), so the counts match exactly and the sums to
/// `merge_bound`, whatever the pass cuts.
#[test]
fn adaptive_sampling_tests_the_sum_of_the_films() {
    let Some(contexts) = two_contexts() else { return };
    let adaptive =
        RenderSettings { adaptive: Some(AdaptiveSampling { threshold: 0.25, min_samples: 8 }), ..settings() };
    let mut m = multi(contexts, adaptive);
    // Cuts off the test points (8, 16, 24, 32): the renderer cuts blocks there itself.
    for (a, n) in [(0, 5), (5, 14), (19, 13)] {
        m.render_pass(a, n).unwrap();
    }
    let film = m.film().unwrap();
    let mut one =
        GpuRenderer::new(test_context().unwrap(), &scene(), &scene().default_camera(), adaptive).unwrap();
    one.render_pass(0, 32).unwrap();
    let expected = one.film().unwrap();
    assert_eq!(film.counts(), expected.counts(), "samples per pixel");
    assert_eq!(film.converged(), expected.converged(), "convergence marks");
    let converged = film.converged_count().unwrap();
    assert!(
        converged > 0 && converged < film.counts().len() as u64,
        "{converged} converged: a test that decides nothing"
    );
    assert_eq!(m.converged_pixels(), Some(converged));
    let bound = furnace_render::merge_bound(32);
    for (a, b) in film.sums().iter().zip(expected.sums()) {
        for (x, y) in a.to_array().into_iter().zip(b.to_array()) {
            assert!((x - y).abs() <= bound * y.abs(), "{x} vs {y}");
        }
    }
}
