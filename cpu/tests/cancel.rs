//! A raised cancel flag stops a pass within a sample's time, and the film keeps whole samples
//! only: every pixel holds the same sample indices, in order, as a render that never started
//! the stopped part.

use furnace_cpu::CpuRenderer;
use furnace_render::{AdaptiveSampling, CancelFlag, Integrator, RenderError, RenderSettings};
use std::time::{Duration, Instant};

fn renderer(settings: RenderSettings) -> CpuRenderer {
    let scene = furnace_scene::builtin::cornell_box().expect("the built-in Cornell box");
    CpuRenderer::with_default_camera(scene, settings).expect("a progressive sampler")
}

/// A flag raised before the pass: nothing is added, the film equals the one before it bit for
/// bit, and the next pass continues as if the stopped one never ran.
#[test]
fn a_flag_raised_before_the_pass_adds_nothing() {
    let settings = RenderSettings { width: 24, height: 16, bounces: 4, seed: 3, ..Default::default() };
    let mut stopped = renderer(settings);
    let mut plain = renderer(settings);
    let flag = CancelFlag::new();
    stopped.set_cancel_flag(flag.clone());
    stopped.render_pass(0, 2).unwrap();
    plain.render_pass(0, 2).unwrap();
    flag.raise();
    match stopped.render_pass(2, 2) {
        Err(RenderError::Interrupted { samples: 0 }) => {}
        other => panic!("expected an interruption with no samples, got {other:?}"),
    }
    assert_eq!(stopped.film().unwrap(), plain.film().unwrap(), "the stopped pass left a trace");
    flag.clear();
    stopped.render_pass(2, 2).unwrap();
    plain.render_pass(2, 2).unwrap();
    assert_eq!(stopped.film().unwrap(), plain.film().unwrap());
}

/// Under adaptive sampling a stopped pass leaves the sums, counts and convergence marks as
/// they were after the last test point.
#[test]
fn a_stopped_adaptive_pass_keeps_sums_and_marks() {
    let adaptive = Some(AdaptiveSampling { threshold: 0.05, min_samples: 8 });
    let settings =
        RenderSettings { width: 16, height: 16, bounces: 3, seed: 5, adaptive, ..Default::default() };
    let mut whole = renderer(settings);
    whole.render_pass(0, 8).unwrap();
    let mut cut = renderer(settings);
    let flag = CancelFlag::new();
    cut.set_cancel_flag(flag.clone());
    cut.render_pass(0, 8).unwrap();
    flag.raise();
    assert!(matches!(cut.render_pass(8, 4), Err(RenderError::Interrupted { samples: 0 })));
    assert_eq!(cut.film().unwrap(), whole.film().unwrap());
}

/// A pass of 2048² paths of up to 16 bounces without Russian roulette (seconds on two cores)
/// stopped 50 ms in returns within 2 s — a sample takes microseconds, the rest is the margin of
/// a loaded CI machine — with an empty film.
#[test]
fn a_long_pass_stops_promptly_and_keeps_nothing_of_itself() {
    let settings = RenderSettings {
        width: 2048,
        height: 2048,
        bounces: 16,
        russian_roulette: false,
        seed: 1,
        ..Default::default()
    };
    let mut r = renderer(settings);
    let flag = CancelFlag::new();
    r.set_cancel_flag(flag.clone());
    let raiser = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(50));
        let raised = Instant::now();
        flag.raise();
        raised
    });
    let result = r.render_pass(0, 1);
    let returned = Instant::now();
    let raised = raiser.join().unwrap();
    assert!(matches!(result, Err(RenderError::Interrupted { samples: 0 })), "{result:?}");
    let delay = returned.duration_since(raised);
    assert!(delay < Duration::from_secs(2), "the pass went on for {delay:?} after the flag");
    let film = r.film().unwrap();
    assert!(film.counts().iter().all(|&c| c == 0), "a stopped pass added samples");
    assert_eq!(film.rejected(), 0);
}
