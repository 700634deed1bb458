//! The GPU integrator at the scale edges of `furnace-cpu`'s `tests/stability.rs` (issue 7,
//! "Stability suite"): the Cornell box scaled by 1e10 renders on the GPU what it renders at
//! scale 1. Before the geometric normal was formed robustly (`scene_geometric_normal` in
//! `src/wgsl/scene.wgsl`, twin of furnace-cpu's `geometric_normal`), |cross|² overflowed f32,
//! the normal came out zero and every large triangle ended its path: the image lost half its
//! light (measured on the CPU twin: mean ratio 0.50–0.65). And scaled by 1e-8: before the ray
//! offsets scaled with the scene (`offset_ray_origin_scaled`, twin of furnace-accel's), their
//! absolute 2⁻¹⁶ step near the origin was larger than the whole box and light leaked (CPU twin
//! at 1e-6: mean ratio 1.65).
//!
//! 32×32 pixels, 4 Sobol samples, same seed at both scales; the image means must agree within
//! 1e-3 relative (the same-sample GPU/CPU parity bar of `tests/integrator.rs`: most paths are
//! the same paths, rounding moves a few).

use furnace_gpu::{GpuRenderer, test_context};
use furnace_render::RenderSettings;
use furnace_sampling::SamplerKind;
use furnace_scene::Scene;

fn scaled_cbox(s: f32) -> Scene {
    let mut scene = furnace_scene::builtin::cornell_box().expect("the built-in Cornell box");
    scene.scale_lengths(s);
    scene
}

#[test]
fn scaled_cornell_box_renders_the_same_image_on_the_gpu() {
    let settings = RenderSettings {
        width: 32,
        height: 32,
        sampler: SamplerKind::Sobol,
        seed: 5,
        ..RenderSettings::default()
    };
    let mut means = vec![];
    for s in [1.0f32, 1e10, 1e-8] {
        // A renderer owns its context: one per scale.
        let Some(ctx) = test_context() else { return };
        let scene = scaled_cbox(s);
        let camera = scene.default_camera();
        let mut gpu = GpuRenderer::new(ctx, &scene, &camera, settings).expect("a renderer");
        gpu.render_pass(0, 4).expect("a pass");
        let film = gpu.film().expect("the film");
        assert_eq!(film.rejected(), 0, "s = {s:e}: non-finite samples");
        let n = film.counts().len();
        let mut m = [0.0f64; 3];
        for i in 0..n {
            let p = film.mean(i);
            for c in 0..3 {
                m[c] += p[c] / n as f64;
            }
        }
        eprintln!("s = {s:e}: image mean {m:?}");
        means.push(m);
    }
    for (k, s) in [(1, "1e10"), (2, "1e-8")] {
        for c in 0..3 {
            let ratio = means[k][c] / means[0][c];
            assert!((ratio - 1.0).abs() < 1e-3, "channel {c}: mean at {s} / mean at 1 = {ratio} ({means:?})");
        }
    }
}

/// A fixed-N sampler used past its design on the GPU, as on the CPU
/// (`furnace-cpu`'s `tests/samplers.rs`): Hammersley and CMJ built for N = 4 render samples
/// 0…3, refuse a pass that reaches sample 4 with the sampler's error (naming N), and the refused
/// pass adds nothing to the film.
#[test]
fn fixed_n_sampler_refuses_to_run_past_n_on_the_gpu() {
    for sampler in [SamplerKind::Hammersley, SamplerKind::Cmj] {
        let Some(ctx) = test_context() else { return };
        let settings = RenderSettings {
            width: 8,
            height: 8,
            sampler,
            sample_count: Some(4),
            ..RenderSettings::default()
        };
        let scene =
            furnace_scene::builtin::furnace_sphere(furnace_scene::builtin::lambert(glam::Vec3::ONE), 8);
        let camera = scene.default_camera();
        let mut gpu = GpuRenderer::new(ctx, &scene, &camera, settings).expect("N given");
        gpu.render_pass(0, 4).expect("samples 0…3 are within N");
        let err = gpu.render_pass(4, 1).expect_err("sample 4 of N = 4").to_string();
        assert!(err.contains("N = 4") && err.contains("sample 4"), "{sampler}: {err}");
        let film = gpu.film().expect("the film");
        assert!(film.counts().iter().all(|&c| c == 4), "{sampler}: the refused pass added samples");
    }
}
