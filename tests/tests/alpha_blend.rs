//! glTF `alphaMode: BLEND` as stochastic transparency, on both backends: a path ray stops at a
//! blended surface with probability α (its coverage) and else passes straight on; a shadow ray
//! carries 1 − α of its light through it; a blended emitter's light samples are weighted by α.
//!
//! The scenes (written in memory, `furnace_tests::gltf`): a 2 m × 2 m quad at height 1 m of
//! `baseColorFactor` alpha 0.3, over a 6 m × 6 m floor at height 0, seen by orthographic
//! cameras looking straight down. Every expected value is exact: what each sample of a pixel
//! can be is known, so the tests check the values themselves, their mean against α, and their
//! spread against the binomial's (which a seed shared by the samples of a pixel would break).

use furnace_render::{Integrator, LightSampling, RenderSettings};
use furnace_sampling::SamplerKind;
use furnace_scene::{AlphaMode, Scene};
use furnace_tests::backends::Backend;
use furnace_tests::gltf::{MaterialDesc, Quad, SceneDesc, TopCamera};
use glam::{DVec3, Vec3};
use std::f32::consts::PI;

// The scene of `alpha_mask.rs`, its quad blended instead of masked: 60 pixels over 2.4 m, 0.04 m
// each, so the quad's edges (±1 m) fall on pixel edges.
use super::alpha_mask::{
    ALBEDO, FLOOR_EMISSION, HALF_VIEW, QUAD_EMISSION, QUAD_HEIGHT, SIZE, SUN_IRRADIANCE, sun_direction,
};

const ALPHA: f32 = 0.3;
const SPP: u32 = 16;

fn floor(emission: Vec3) -> Quad {
    Quad {
        x: [-3.0, 3.0],
        z: [-3.0, 3.0],
        y: 0.0,
        tangent: None,
        material: MaterialDesc { albedo: Vec3::splat(ALBEDO), emissive: emission, ..MaterialDesc::default() },
    }
}

fn blended_quad(emission: Vec3, blend_alpha: Option<f32>) -> Quad {
    Quad {
        x: [-1.0, 1.0],
        z: [-1.0, 1.0],
        y: QUAD_HEIGHT,
        tangent: None,
        material: MaterialDesc {
            albedo: Vec3::splat(ALBEDO),
            emissive: emission,
            blend_alpha,
            double_sided: false,
            ..MaterialDesc::default()
        },
    }
}

/// The blended quad (emitting red upwards) over the floor (emitting dim blue), lit by the sun;
/// cameras above the quad and between the quad and the floor.
fn scene(camera: usize) -> Scene {
    let desc = SceneDesc {
        quads: vec![blended_quad(QUAD_EMISSION, Some(ALPHA)), floor(FLOOR_EMISSION)],
        cameras: vec![
            TopCamera { position: Vec3::new(0.0, 3.0, 0.0), half_size: HALF_VIEW },
            TopCamera { position: Vec3::new(0.0, 0.5, 0.0), half_size: HALF_VIEW },
        ],
        sun: Some((sun_direction(), SUN_IRRADIANCE)),
        sky: Vec3::ZERO,
    };
    let mut scene = desc.load("alpha_blend.gltf");
    assert_eq!(scene.materials[0].alpha_mode, AlphaMode::Blend, "the loader reads BLEND");
    assert!(scene.warnings.is_empty(), "BLEND loads without a warning: {:?}", scene.warnings);
    scene.cameras.swap(0, camera);
    scene
}

fn settings(bounces: u32, light_sampling: LightSampling) -> RenderSettings {
    RenderSettings {
        width: SIZE,
        height: SIZE,
        bounces,
        sampler: SamplerKind::Random,
        seed: 11,
        light_sampling,
        ..Default::default()
    }
}

/// The pixel means of `spp` samples of `scene` on `backend` (`None`: GPU tests skipped).
fn render(backend: Backend, scene: &Scene, settings: RenderSettings, spp: u32) -> Option<Vec<DVec3>> {
    let mut integrator: Box<dyn Integrator> = backend.open_default(scene, settings)?;
    integrator.render_pass(0, spp).expect("a pass");
    let film = integrator.film().expect("the film");
    assert_eq!(film.rejected(), 0, "{backend}: non-finite samples");
    Some((0..SIZE * SIZE).map(|i| film.pixel(i % SIZE, i / SIZE)).collect())
}

/// Whether pixel `(x, y)` of a camera centred over the quad lies wholly within `half` metres of
/// the centre (a margin of a pixel for rounding at the edges).
fn inside(x: u32, y: u32, half: f32) -> bool {
    let pixel = 2.0 * HALF_VIEW / SIZE as f32;
    let c = |i: u32| (i as f32 + 0.5) * pixel - HALF_VIEW;
    c(x).abs() < half - pixel && c(y).abs() < half - pixel
}

/// Camera rays, no bounce: each sample of a pixel over the quad sees the quad's red (with
/// probability α) or the floor's blue, so `red + 4·blue = 1` exactly in every such pixel; the
/// red fraction has mean α and, over the pixels, the binomial variance α(1 − α)/spp.
#[test]
fn camera_rays_stop_at_a_blended_surface_with_probability_alpha() {
    let scene = scene(0);
    for backend in Backend::ALL {
        let Some(image) = render(backend, &scene, settings(0, LightSampling::Mis), SPP) else { return };
        let mut fractions = Vec::new();
        for y in 0..SIZE {
            for x in 0..SIZE {
                let v = image[(y * SIZE + x) as usize];
                if inside(x, y, 1.0) {
                    // Tolerance: f32 rounding of the film's sum of 16 samples.
                    let sum = v.x / f64::from(QUAD_EMISSION.x) + v.z / f64::from(FLOOR_EMISSION.z);
                    assert!((sum - 1.0).abs() < 1e-5, "{backend}: pixel ({x}, {y}) = {v} is no mixture");
                    fractions.push(v.x);
                } else if !inside(x, y, 1.0 + 0.08) {
                    let floor = FLOOR_EMISSION.as_dvec3();
                    assert!((v - floor).abs().max_element() < 1e-6, "{backend}: pixel ({x}, {y}) = {v}");
                }
            }
        }
        let n = fractions.len() as f64;
        let mean = fractions.iter().sum::<f64>() / n;
        let variance = fractions.iter().map(|f| (f - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let p = f64::from(ALPHA);
        let expected_variance = p * (1.0 - p) / f64::from(SPP);
        // The mean of n·spp Bernoulli(α) draws: standard error √(α(1 − α)/(n·spp)) (≈ 2.3e-3 for
        // n ≈ 2300); 5 standard errors (p ≈ 6e-7 of a false failure).
        let se_mean = (p * (1.0 - p) / (n * f64::from(SPP))).sqrt();
        // The sample variance of n binomial fractions has a relative standard error of about
        // √(2/n) ≈ 3 %; 5 of them. Samples of a pixel that decided together would give 16×.
        let ratio = variance / expected_variance;
        eprintln!(
            "{backend}: {n} pixels over the quad, red fraction {mean:.4} (α = {p}, σ {se_mean:.4}), variance ratio {ratio:.3}"
        );
        assert!(n > 2000.0, "the quad covers the pixels the test expects: {n}");
        assert!((mean - p).abs() < 5.0 * se_mean, "{backend}: red fraction {mean} for α = {p}");
        assert!((ratio - 1.0).abs() < 5.0 * (2.0 / n).sqrt(), "{backend}: variance ratio {ratio}");
    }
}

/// The floor seen from between the quad and the floor, one bounce: where the sun's shadow ray
/// crosses the quad, the floor receives 1 − α of the sun; elsewhere all of it. No sample is
/// random there (the quad is single-sided, so paths that stop under it end dark), so every
/// such pixel is compared with its value.
#[test]
fn shadow_rays_carry_one_minus_alpha_through_a_blended_surface() {
    let scene = scene(1);
    let l = -sun_direction();
    let sun = f64::from(ALBEDO / PI * l.y) * SUN_IRRADIANCE.as_dvec3();
    let dark = FLOOR_EMISSION.as_dvec3();
    for backend in Backend::ALL {
        let Some(image) = render(backend, &scene, settings(1, LightSampling::Mis), 4) else { return };
        let (mut shaded, mut lit) = (0, 0);
        for y in 0..SIZE {
            for x in 0..SIZE {
                // Where the shadow ray from the pixel's centre crosses the quad's plane.
                let pixel = 2.0 * HALF_VIEW / SIZE as f32;
                let f = Vec3::new(
                    (x as f32 + 0.5) * pixel - HALF_VIEW,
                    0.0,
                    (y as f32 + 0.5) * pixel - HALF_VIEW,
                );
                let q = f + l * (QUAD_HEIGHT / l.y);
                let margin = 0.6 * pixel / l.y;
                let expected = if q.x.abs() < 1.0 - margin && q.z.abs() < 1.0 - margin {
                    shaded += 1;
                    dark + f64::from(1.0 - ALPHA) * sun
                } else if q.x.abs() > 1.0 + margin || q.z.abs() > 1.0 + margin {
                    lit += 1;
                    dark + sun
                } else {
                    continue;
                };
                let v = image[(y * SIZE + x) as usize];
                // Tolerance: f32 rounding of the BRDF, the transmittance and the film's mean
                // (1e-5 relative on the CPU; the GPU's fused multiply-adds and division round
                // differently, 1e-4).
                let tolerance = if backend == Backend::Cpu { 1e-5 } else { 1e-4 };
                assert!(
                    (v - expected).abs().max_element() < tolerance * expected.max_element(),
                    "{backend}: pixel ({x}, {y}) = {v}, expected {expected}"
                );
            }
        }
        eprintln!("{backend}: {shaded} pixels under the quad, {lit} in the open, all exact");
        assert!(shaded > 1000 && lit > 500, "the test covers both kinds of pixel: {shaded}, {lit}");
    }
}

/// A blended emitter facing the floor lights it like an opaque one of α times its emission:
/// with light samples only, pixel for pixel; with MIS, in the image mean within its standard
/// error (BSDF samples see the blended emitter with probability α at full emission).
#[test]
fn a_blended_emitter_lights_like_an_opaque_one_of_alpha_times_its_emission() {
    // The emitter faces down: its triangles wound the other way, the normals left to geometry.
    let facing_down = |quad: Quad| {
        let desc = SceneDesc {
            quads: vec![quad, floor(Vec3::ZERO)],
            cameras: vec![TopCamera { position: Vec3::new(0.0, 0.5, 0.0), half_size: HALF_VIEW }],
            sun: None,
            sky: Vec3::ZERO,
        };
        let mut scene = desc.load("blended_emitter.gltf");
        scene.geometry.normals.clear();
        for t in 0..scene.geometry.triangle_count() {
            if scene.triangle_material(t) == 0 {
                scene.geometry.triangles[t].swap(1, 2);
            }
        }
        scene
    };
    let blended = facing_down(blended_quad(Vec3::ONE, Some(ALPHA)));
    let opaque = facing_down(blended_quad(Vec3::splat(ALPHA), None));
    let mean = |image: &[DVec3]| image.iter().sum::<DVec3>() / image.len() as f64;
    for backend in Backend::ALL {
        let Some(b) = render(backend, &blended, settings(1, LightSampling::Nee), 16) else { return };
        let o = render(backend, &opaque, settings(1, LightSampling::Nee), 16).expect("the same backend");
        for (i, (b, o)) in b.iter().zip(&o).enumerate() {
            // Tolerance: the emission is scaled after evaluation instead of before (one f32
            // rounding), then summed over 16 samples.
            assert!(
                (*b - *o).abs().max_element() <= 1e-5 * o.max_element(),
                "{backend}: pixel {i}: {b} vs {o}"
            );
        }
        let spp = 64;
        let b = render(backend, &blended, settings(1, LightSampling::Mis), spp).expect("the same backend");
        let o = render(backend, &opaque, settings(1, LightSampling::Mis), spp).expect("the same backend");
        let (mb, mo) = (mean(&b).x, mean(&o).x);
        // The standard error of the difference of the two means, from the spread of the
        // pixels' differences (both images have the same expectation pixel for pixel, so the
        // floor's own gradient cancels; pixels are independent).
        let d: Vec<f64> = b.iter().zip(&o).map(|(b, o)| b.x - o.x).collect();
        let dm = d.iter().sum::<f64>() / d.len() as f64;
        let var = d.iter().map(|x| (x - dm).powi(2)).sum::<f64>() / (d.len() as f64 - 1.0);
        let se = (var / d.len() as f64).sqrt();
        eprintln!("{backend}: MIS image mean {mb:.5} blended vs {mo:.5} opaque (σ {se:.5})");
        assert!(mo > 0.01, "the floor is lit");
        // 5 standard errors: p ≈ 6e-7 of a false failure; a blended emitter that emitted fully
        // under BSDF sampling, or not at all, moves the mean by far more.
        assert!((mb - mo).abs() < 5.0 * se, "{backend}: {mb} vs {mo} (σ {se})");
    }
}
