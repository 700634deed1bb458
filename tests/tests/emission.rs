//! Emission is one-sided (the references' convention): a double-sided emissive quad seen from
//! its front shows its emitted radiance, seen from its back shows nothing — on both backends.
//!
//! The quad (2 × 2 m at y = 1, facing +Y, `emissiveFactor` (0.25, 0.5, 1), albedo 0.5, double-sided)
//! is the only thing in a black world, so nothing else can light either side: the front's pixels
//! are exactly the emission and the back's exactly 0 (the quad cannot see itself).

use furnace_render::RenderSettings;
use furnace_sampling::SamplerKind;
use furnace_scene::{Camera, Scene};
use furnace_tests::backends::Backend;
use furnace_tests::gltf::{MaterialDesc, Quad, SceneDesc, TopCamera};
use glam::Vec3;

const EMISSION: Vec3 = Vec3::new(0.25, 0.5, 1.0);

fn scene() -> Scene {
    let quad = Quad {
        x: [-1.0, 1.0],
        z: [-1.0, 1.0],
        y: 1.0,
        tangent: None,
        material: MaterialDesc {
            albedo: Vec3::splat(0.5),
            emissive: EMISSION,
            double_sided: true,
            ..MaterialDesc::default()
        },
    };
    let desc = SceneDesc {
        quads: vec![quad],
        cameras: vec![TopCamera { position: Vec3::new(0.0, 3.0, 0.0), half_size: 0.5 }],
        sun: None,
        sky: Vec3::ZERO,
    };
    desc.load("emissive_quad.gltf")
}

/// Every pixel's mean from `camera` (8×8 pixels, 16 samples, 2 bounces).
fn render(backend: Backend, scene: &Scene, camera: &Camera) -> Option<Vec<[f64; 3]>> {
    let settings =
        RenderSettings { width: 8, height: 8, bounces: 2, sampler: SamplerKind::Sobol, ..Default::default() };
    let mut integrator = backend.open(scene, camera, settings).expect("an integrator")?;
    integrator.render_pass(0, 16).expect("a pass");
    let film = integrator.film().expect("the film");
    Some((0..film.counts().len()).map(|i| film.mean(i).to_array()).collect())
}

#[test]
fn emission_is_one_sided() {
    let scene = scene();
    let front = scene.default_camera();
    // Below the quad looking up at its back, its view inside the quad.
    let back = Camera::look_at(Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Z, 0.3);
    for backend in Backend::ALL {
        let Some(seen_front) = render(backend, &scene, &front) else { return };
        for p in &seen_front {
            // Exact up to f32 rounding of the emission.
            for c in 0..3 {
                assert!((p[c] - f64::from(EMISSION[c])).abs() < 1e-6, "{backend}: front pixel {p:?}");
            }
        }
        let seen_back = render(backend, &scene, &back).expect("the same backend");
        assert!(seen_back.iter().flatten().all(|&v| v == 0.0), "{backend}: the back emits: {seen_back:?}");
    }
}
