//! The film must not depend on the number of threads: bit-identical with 1 and 2 rayon threads.

use furnace_cpu::CpuRenderer;
use furnace_render::RenderSettings;
use furnace_sampling::SamplerKind;

#[test]
fn one_and_two_threads_give_identical_films() {
    let scene = furnace_scene::builtin::cornell_box().expect("the built-in Cornell box");
    for sampler in [SamplerKind::Sobol, SamplerKind::Random] {
        let settings =
            RenderSettings { width: 32, height: 24, bounces: 4, sampler, seed: 7, ..Default::default() };
        let renderer =
            CpuRenderer::with_default_camera(scene.clone(), settings).expect("a progressive sampler");
        let render = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a pool");
            let mut film = renderer.new_film();
            // Two passes, as a progressive render would add them.
            pool.install(|| {
                renderer.render_into(&mut film, 0, 3).expect("render");
                renderer.render_into(&mut film, 3, 5).expect("render");
            });
            film
        };
        let (one, two) = (render(1), render(2));
        // Bit-identical: compare the bit patterns, so that NaN or -0.0 could not hide a change.
        let bits = |f: &furnace_render::Film| f.to_rgb_f32().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&one), bits(&two), "{sampler}");
        assert_eq!(one, two, "{sampler}: f64 sums and counts");
        assert!(one.to_rgb_f32().iter().any(|&v| v > 0.0), "{sampler}: the image is not black");
    }
}
