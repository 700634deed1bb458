//! Point and spot lights (`KHR_lights_punctual`) against the closed form, on both backends.
//!
//! A Lambert floor (albedo 0.5) at y = 0 seen from straight above by an orthographic camera
//! (4 × 4 m, 32² pixels), black sky, one bounce, one light at height `h`: a floor point at
//! distance `d` from the light receives `I·k·cos θ / d² = I·k·h / d³` and sends `albedo/π` of
//! it to the camera, `k` being the spot cone's attenuation × the range window (the formulas the
//! `KHR_lights_punctual` specification recommends, written out here again). Each pixel's
//! expectation is that radiance averaged over the pixel's footprint, integrated here by a
//! 16×16 midpoint rule (relative error < 1e-5 for these smooth integrands: the pixel is 1/8 of
//! the light's height or less). The renders use 256 Owen-scrambled Sobol samples per pixel, whose
//! integration error on a smooth pixel is ~1e-4 of its value; pixels where `k` has a kink (the
//! spot's inner cone edge, the range's edge) converge more slowly. Bar: every pixel within
//! 1e-3 of its expectation relative to the image's largest value, and the image mean within
//! 1e-4 relative. Measured on the CPU and on lavapipe (the same to the printed digits): worst
//! pixel 2.1e-5 (point), 1.8e-4 (spot, at the inner cone's edge), 4.1e-5 (range); image means
//! within 3e-6. A wrong exponent of d, cos θ left out, or the cone's t not squared each move
//! pixels by far more than 1e-3 of the peak.
//!
//! Also the edge where the inverse square fails: a light on the floor (d → 0 at the pixel below
//! it) must give no ∞ or NaN — that pixel only loses what it cannot represent.

use furnace_render::{PointLightSampling, RenderSettings};
use furnace_sampling::SamplerKind;
use furnace_scene::{Light, PointLight, Scene, SpotCone};
use furnace_tests::backends::Backend;
use furnace_tests::gltf::{MaterialDesc, Quad, SceneDesc, TopCamera};
use glam::{Vec2, Vec3};

const SIZE: u32 = 32;
const HALF_VIEW: f32 = 2.0;
const ALBEDO: f32 = 0.5;
const SPP: u32 = 256;

fn floor_scene(light: PointLight) -> Scene {
    floor_scene_lit(&[light])
}

fn floor_scene_lit(lights: &[PointLight]) -> Scene {
    let floor = Quad {
        x: [-3.0, 3.0],
        z: [-3.0, 3.0],
        y: 0.0,
        tangent: None,
        material: MaterialDesc { albedo: Vec3::splat(ALBEDO), ..MaterialDesc::default() },
    };
    let desc = SceneDesc {
        quads: vec![floor],
        cameras: vec![TopCamera { position: Vec3::new(0.0, 5.0, 0.0), half_size: HALF_VIEW }],
        sun: None,
        sky: Vec3::ZERO,
    };
    let mut scene = desc.load("point_light_floor.gltf");
    scene.lights.extend(lights.iter().map(|&l| Light::Point(l)));
    scene
}

/// The spec's recommended attenuation, independently of `PointLight::intensity_towards`.
fn attenuation(light: &PointLight, p: Vec3) -> f64 {
    let v = (p - light.position).as_dvec3();
    let d = v.length();
    let mut k = 1.0;
    if let Some(cone) = &light.spot {
        let cos = v.dot(cone.direction.as_dvec3()) / d;
        let (ci, co) = (f64::from(cone.cos_inner), f64::from(cone.cos_outer));
        let t = ((cos - co) / (ci - co)).clamp(0.0, 1.0);
        k *= t * t;
    }
    if let Some(range) = light.range {
        k *= (1.0 - (d / f64::from(range)).powi(4)).clamp(0.0, 1.0);
    }
    k
}

/// Each pixel's expected radiance (RGB), by a 16×16 midpoint rule over its footprint.
fn expected(scene: &Scene, light: &PointLight) -> Vec<[f64; 3]> {
    let camera = scene.default_camera();
    let n = 16;
    (0..SIZE * SIZE)
        .map(|i| {
            let (x, y) = (i % SIZE, i / SIZE);
            let mut sum = 0.0;
            for a in 0..n {
                for b in 0..n {
                    let film = Vec2::new(
                        x as f32 + (a as f32 + 0.5) / n as f32,
                        y as f32 + (b as f32 + 0.5) / n as f32,
                    );
                    let ray = camera.generate_ray(film, SIZE, SIZE);
                    let p = ray.origin + ray.direction * (ray.origin.y / -ray.direction.y);
                    let v = (light.position - p).as_dvec3();
                    let d = v.length();
                    let cos = v.y / d;
                    if cos > 0.0 {
                        sum += attenuation(light, p) * cos / (d * d);
                    }
                }
            }
            let e = sum / f64::from(n * n) * f64::from(ALBEDO) / std::f64::consts::PI;
            light.intensity.as_dvec3().to_array().map(|c| c * e)
        })
        .collect()
}

/// Renders `light` over the floor on `backend`; `None` when GPU tests are skipped.
fn render(backend: Backend, scene: &Scene) -> Option<Vec<[f64; 3]>> {
    render_with(backend, scene, PointLightSampling::All)
}

fn render_with(backend: Backend, scene: &Scene, point_lights: PointLightSampling) -> Option<Vec<[f64; 3]>> {
    let settings = RenderSettings {
        point_lights,
        width: SIZE,
        height: SIZE,
        bounces: 1,
        sampler: SamplerKind::Sobol,
        seed: 9,
        ..Default::default()
    };
    let mut integrator = backend.open_default(scene, settings)?;
    integrator.render_pass(0, SPP).expect("a pass");
    let film = integrator.film().expect("the film");
    assert_eq!(film.rejected(), 0, "{backend}: non-finite samples");
    Some((0..film.counts().len()).map(|i| film.mean(i).to_array()).collect())
}

fn check(name: &str, light: PointLight) {
    check_lights(name, &[light], PointLightSampling::All, [1e-3, 1e-3, 1e-4]);
}

/// The floor lit by `lights`, gathered by `point_lights`, against the sum of their closed
/// forms: every pixel within `pixel_bar` of the image's peak, every 8 × 8 block's mean within
/// `block_bar` of it, the image mean within `mean_bar`.
fn check_lights(
    name: &str,
    lights: &[PointLight],
    point_lights: PointLightSampling,
    [pixel_bar, block_bar, mean_bar]: [f64; 3],
) {
    let scene = floor_scene_lit(lights);
    let mut want = vec![[0.0f64; 3]; (SIZE * SIZE) as usize];
    for light in lights {
        for (w, e) in want.iter_mut().zip(expected(&scene, light)) {
            for c in 0..3 {
                w[c] += e[c];
            }
        }
    }
    let peak = want.iter().flatten().fold(0.0f64, |a, &b| a.max(b));
    let mean = |img: &[[f64; 3]]| img.iter().flatten().sum::<f64>() / (img.len() * 3) as f64;
    assert!(peak > 0.0, "{name}: the light reaches the floor");
    for backend in Backend::ALL {
        let Some(got) = render_with(backend, &scene, point_lights) else { return };
        let (mut worst, mut at) = (0.0f64, 0);
        for (i, (g, w)) in got.iter().zip(&want).enumerate() {
            for c in 0..3 {
                let e = (g[c] - w[c]).abs() / peak;
                if e > worst {
                    (worst, at) = (e, i);
                }
            }
        }
        let ratio = mean(&got) / mean(&want);
        // Means of 8 × 8-pixel blocks: each block's error relative to the peak (a weight wrong
        // in one part of the image shows there even where pixel noise hides it).
        let block = |img: &[[f64; 3]], bx: u32, by: u32, c: usize| {
            let px = (0..64).map(|k| ((by * 8 + k / 8) * SIZE + bx * 8 + k % 8) as usize);
            px.map(|i| img[i][c]).sum::<f64>() / 64.0
        };
        let mut worst_block = 0.0f64;
        for (bx, by, c) in
            (0..SIZE / 8).flat_map(|bx| (0..SIZE / 8).flat_map(move |by| (0..3).map(move |c| (bx, by, c))))
        {
            worst_block = worst_block.max((block(&got, bx, by, c) - block(&want, bx, by, c)).abs() / peak);
        }
        println!(
            "{name}, {backend}: worst pixel error {worst:.2e} of the peak at pixel ({}, {}), worst 8x8 block {worst_block:.2e}, \
             image mean ratio {ratio:.6}",
            at as u32 % SIZE,
            at as u32 / SIZE
        );
        assert!(
            worst_block < block_bar,
            "{name}, {backend}: an 8x8 block off by {worst_block:e} of the peak"
        );
        assert!(
            worst < pixel_bar,
            "{name}, {backend}: pixel ({}, {}) off by {worst:e} of the peak: {:?} vs {:?}",
            at as u32 % SIZE,
            at as u32 / SIZE,
            got[at],
            want[at]
        );
        assert!((ratio - 1.0).abs() < mean_bar, "{name}, {backend}: image mean ratio {ratio}");
    }
}

#[test]
fn point_light_lights_the_floor_by_the_inverse_square_law() {
    check("point", point());
}

/// The point light of the tests: (2, 1, 0.5) W/sr one metre above the floor.
fn point() -> PointLight {
    PointLight {
        position: Vec3::new(0.3, 1.0, -0.2),
        intensity: Vec3::new(2.0, 1.0, 0.5),
        range: None,
        spot: None,
    }
}

/// The spot light of the tests: (1, 2, 3) W/sr, cone 20° to 35°, tilted.
fn spot() -> PointLight {
    let (inner, outer) = (20f32.to_radians(), 35f32.to_radians());
    PointLight {
        position: Vec3::new(-0.2, 1.5, 0.1),
        intensity: Vec3::new(1.0, 2.0, 3.0),
        range: None,
        spot: Some(SpotCone {
            direction: Vec3::new(0.2, -1.0, 0.1).normalize(),
            cos_inner: inner.cos(),
            cos_outer: outer.cos(),
        }),
    }
}

#[test]
fn spot_light_cone_falls_off_between_its_angles() {
    check("spot", spot());
}

#[test]
fn range_window_ends_the_light() {
    check(
        "range",
        PointLight {
            position: Vec3::new(0.0, 1.0, 0.0),
            intensity: Vec3::splat(1.5),
            range: Some(1.5),
            spot: None,
        },
    );
}

/// A light on the floor (and just above it): the inverse square diverges at the pixel below;
/// no sample may come out non-finite, and the rest of the image is what it is for a light at
/// that height.
#[test]
fn a_light_on_the_surface_gives_no_infinity_or_nan() {
    for h in [0.0f32, 1e-30, 1e-6] {
        let light =
            PointLight { position: Vec3::new(0.01, h, 0.02), intensity: Vec3::ONE, range: None, spot: None };
        let scene = floor_scene(light);
        for backend in Backend::ALL {
            let Some(got) = render(backend, &scene) else { return };
            let finite = got.iter().flatten().all(|v| v.is_finite());
            let max = got.iter().flatten().fold(0.0f64, |a, &b| a.max(b));
            println!("light at height {h:e}, {backend}: largest pixel value {max:.3e}");
            assert!(finite, "{backend}, h = {h:e}: a non-finite pixel");
        }
    }
}

/// `--point-lights one`: a point light, a spot light and a dim blue point light (powers 14.8,
/// 1.2 and 2.4 in luminance: probabilities 0.80, 0.06, 0.13, far from uniform), one chosen per
/// event by power and weighted by 1/pmf, against the sum of the three closed forms. Each
/// estimate is unbiased but noisier than gathering all three (the spot's share is seen by
/// one sample in sixteen, ×16), so the bars are for noise: every pixel within 0.1 of the
/// peak, every 8 × 8 block within 1e-2, the image mean within 2e-3 (measured, fixed seed, the
/// CPU and lavapipe alike: 5.1e-2, 1.3e-3, 6e-4). The weight left out (1 instead of 1/pmf) puts
/// the mean at 0.57 of the truth, a uniform choice weighted by these pmfs at 1.64: both far
/// past the bars.
#[test]
fn one_light_per_event_converges_to_the_sum_of_the_lights() {
    let lights = [
        point(),
        spot(),
        PointLight {
            position: Vec3::new(-1.0, 0.8, 1.0),
            intensity: Vec3::new(0.1, 0.2, 0.4),
            range: None,
            spot: None,
        },
    ];
    check_lights("three lights, one per event", &lights, PointLightSampling::One, [1e-1, 1e-2, 2e-3]);
}

/// With one light, choosing one light per event is gathering all: the same image, bit for bit.
#[test]
fn one_light_of_one_is_all_of_them() {
    let scene = floor_scene(point());
    for backend in Backend::ALL {
        let Some(all) = render_with(backend, &scene, PointLightSampling::All) else { return };
        let one = render_with(backend, &scene, PointLightSampling::One).unwrap();
        assert!(all == one, "{backend}: --point-lights one with one light changed the image");
    }
}
