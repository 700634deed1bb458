//! A raised cancel flag stops a long GPU pass between its dispatches and gives the film back as
//! it was before the pass, bit for bit; the render then continues as if the stopped pass never
//! ran.

use furnace_gpu::GpuRenderer;
use furnace_render::{AdaptiveSampling, CancelFlag, Integrator, RenderError, RenderSettings};
use furnace_scene::builtin;
use furnace_tests::gpu::test_context;

/// 256 × 128 pixels of paths of up to 20 bounces: the first pass of paths longer than 16 bounces
/// is submitted dispatch by dispatch when a cancel flag is set, its dispatches halved for them
/// (2¹⁵ samples on a software adapter: one per sample of a pass; more on hardware).
fn renderer(settings: RenderSettings) -> Option<GpuRenderer> {
    let scene = builtin::cornell_box().expect("the built-in Cornell box");
    Some(GpuRenderer::new(test_context()?, &scene, &scene.default_camera(), settings).expect("a renderer"))
}

fn check(settings: RenderSettings) {
    let (Some(mut stopped), Some(mut plain)) = (renderer(settings), renderer(settings)) else { return };
    if furnace_gpu::context::is_hardware(&stopped.context().info) {
        // A hardware adapter renders this image in one dispatch, which nothing interrupts; the
        // 4K render of 1024-bounce paths on such an adapter is where a pass gets split and stopped.
        eprintln!("skipped: one dispatch per pass on a hardware adapter");
        return;
    }
    let flag = CancelFlag::new();
    stopped.set_cancel_flag(flag.clone());
    flag.raise();
    match Integrator::render_pass(&mut stopped, 0, 2) {
        Err(RenderError::Interrupted { samples: 0 }) => {}
        other => panic!("expected an interruption with no samples, got {other:?}"),
    }
    let empty = Integrator::film(&mut stopped).unwrap();
    assert!(empty.counts().iter().all(|&c| c == 0), "the stopped pass left samples");
    assert_eq!(empty.rejected(), 0);
    assert_eq!(empty.converged_count().unwrap_or(0), 0, "the stopped pass left convergence marks");
    flag.clear();
    for (first, n) in [(0, 8), (8, 8)] {
        Integrator::render_pass(&mut stopped, first, n).unwrap();
        Integrator::render_pass(&mut plain, first, n).unwrap();
    }
    let (a, b) = (Integrator::film(&mut stopped).unwrap(), Integrator::film(&mut plain).unwrap());
    assert_eq!(a, b, "the render after the stopped pass differs from one that never ran it");
    assert_eq!(stopped.converged_pixels(), plain.converged_pixels());
}

#[test]
fn a_stopped_pass_gives_the_film_back() {
    check(RenderSettings { width: 256, height: 128, bounces: 20, seed: 4, ..Default::default() });
}

/// With adaptive sampling the marks and the device's count of converged pixels are given back
/// too (the test at sample 8 marks pixels; a threshold of 0.3 converges some of them).
#[test]
fn a_stopped_adaptive_pass_gives_the_marks_back() {
    let adaptive = Some(AdaptiveSampling { threshold: 0.3, min_samples: 8 });
    check(RenderSettings { width: 256, height: 128, bounces: 20, seed: 4, adaptive, ..Default::default() });
}
