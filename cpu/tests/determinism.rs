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

/// A structure built before the renderer (`CpuRenderer::accel_for`, as the CLI's default-light
/// probe does) renders the same film as the renderer's own, for a flat and an instanced scene;
/// one built for another scene is refused, not traced.
#[test]
fn a_structure_built_before_renders_the_same_and_a_foreign_one_is_refused() {
    let settings = RenderSettings { width: 24, height: 16, bounces: 3, seed: 3, ..Default::default() };
    let flat = furnace_scene::builtin::cornell_box().expect("the built-in Cornell box");
    let forest = furnace_scene::builtin::forest(3, 1);
    for scene in [&flat, &forest] {
        let camera = scene.default_camera();
        let own = CpuRenderer::new(scene.clone(), &camera, settings).expect("renderer");
        let given = CpuRenderer::with_accel(scene.clone(), &camera, settings, CpuRenderer::accel_for(scene))
            .expect("the scene's own structure");
        let render = |r: &CpuRenderer| {
            let mut film = r.new_film();
            r.render_into(&mut film, 0, 2).expect("render");
            film
        };
        assert_eq!(render(&own), render(&given), "{}", scene.name);
    }
    for (scene, other) in [(&flat, &forest), (&forest, &flat)] {
        let foreign = CpuRenderer::accel_for(other);
        let r = CpuRenderer::with_accel(scene.clone(), &scene.default_camera(), settings, foreign);
        assert!(r.is_err(), "{} took {}'s structure", scene.name, other.name);
    }
}
