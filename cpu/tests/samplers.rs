//! Every sampler kind renders, and the fixed-N kinds refuse what they cannot do.

use furnace_cpu::CpuRenderer;
use furnace_render::RenderSettings;
use furnace_sampling::SamplerKind;
use furnace_scene::builtin;
use glam::Vec3;

#[test]
fn fixed_n_samplers_need_n_and_stop_at_n() {
    let scene = builtin::furnace_sphere(builtin::lambert(Vec3::ONE), 8);
    for sampler in [SamplerKind::Hammersley, SamplerKind::Cmj] {
        let settings = RenderSettings { width: 4, height: 4, sampler, ..Default::default() };
        assert!(CpuRenderer::with_default_camera(scene.clone(), settings).is_err(), "{sampler} without N");
        let settings = RenderSettings { sample_count: Some(16), ..settings };
        let renderer = CpuRenderer::with_default_camera(scene.clone(), settings).expect("N given");
        let mut film = renderer.new_film();
        renderer.render_into(&mut film, 0, 16).expect("within N");
        assert!(renderer.render_into(&mut film, 16, 1).is_err(), "{sampler}: sample 16 of N = 16");
        assert_eq!(film.sample_count(0, 0), 16, "{sampler}: the refused pass added nothing");
    }
}

#[test]
fn every_sampler_renders_the_white_furnace() {
    let scene = builtin::furnace_sphere(builtin::lambert(Vec3::ONE), 32);
    for sampler in SamplerKind::ALL {
        let settings =
            RenderSettings { width: 8, height: 8, sampler, sample_count: Some(16), ..Default::default() };
        let renderer = CpuRenderer::with_default_camera(scene.clone(), settings).expect("a sampler");
        let mut film = renderer.new_film();
        renderer.render_into(&mut film, 0, 16).expect("render");
        for (i, v) in film.to_rgb_f32().into_iter().enumerate() {
            // Tolerance 1e-2: each pixel is exact up to paths lost at the flat triangles' edges
            // (at most one of 16 here would be 6%, none is expected at this tessellation).
            assert!((v - 1.0).abs() < 1e-2, "{sampler}: value {i} = {v}");
        }
    }
}
