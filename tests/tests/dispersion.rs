//! KHR_materials_dispersion through the whole integrator (the GPU's same-samples parity is in
//! `integrator.rs`): a dispersive solid that does not separate the wavelengths stays white, and
//! one that does separates them in the order of their indices.

use furnace_cpu::CpuRenderer;
use furnace_render::{Film, RenderSettings};
use furnace_sampling::SamplerKind;
use furnace_scene::{Light, Scene, Sky};
use glam::{DVec3, Vec3};

fn render(scene: &Scene, settings: RenderSettings, spp: u32) -> Film {
    let cpu = CpuRenderer::with_default_camera(scene.clone(), settings).unwrap();
    let mut film = cpu.new_film();
    cpu.render_into(&mut film, 0, spp).unwrap();
    film
}

/// The per-channel mean over the image and its standard error (pixels independent).
fn mean_and_error(film: &Film, width: u32, height: u32) -> (DVec3, DVec3) {
    let n = f64::from(width * height);
    let (mut sum, mut sq) = (DVec3::ZERO, DVec3::ZERO);
    for y in 0..height {
        for x in 0..width {
            let p = film.pixel(x, y);
            sum += p;
            sq += p * p;
        }
    }
    let mean = sum / n;
    let var = (sq / n - mean * mean) * (n / (n - 1.0));
    (mean, (var / n).map(f64::sqrt))
}

/// A white furnace of glass: the reference spheres made clear smooth solids (indices 1.0–2.5)
/// under a white sky of radiance 1, nothing else. Every path through lossless smooth
/// dielectrics under that sky carries radiance 1, so every pixel's expectation is white 1
/// whatever the wavelength does; with dispersion 2 (V_d = 10) each path is one wavelength
/// weighted by its colour, and only the mean is white. Spheres trap no light by total internal
/// reflection, so 64 events lose nothing measurable (the run without dispersion shows it).
/// Abbe numbers down to 2·10⁻²⁹ (dispersion 10³⁰: blue indices clamped at the dielectric's 100,
/// red ones at 1, where the interface vanishes) hold the same: no rejected sample, no gain.
#[test]
fn a_clear_dispersive_solid_stays_white_in_a_white_sky() {
    let mut scene = Scene::load(furnace_tests::data::reference("pbr/pbr_ior.gltf")).unwrap();
    scene.lights = vec![Light::Sky(Sky { radiance: Vec3::ONE })];
    let settings = RenderSettings {
        width: 64,
        height: 32,
        bounces: 64,
        sampler: SamplerKind::Sobol,
        seed: 7,
        ..RenderSettings::default()
    };
    let (w, h) = (settings.width, settings.height);
    let mut plain = DVec3::ZERO;
    for dispersion in [0.0, 2.0, 1e3, 1e30] {
        for m in &mut scene.materials {
            m.transmission_factor = 1.0;
            m.volume = true;
            m.double_sided = true;
            m.roughness_factor = 0.0;
            m.base_color_factor = glam::Vec4::ONE;
            m.dispersion = if m.ior != 1.0 { dispersion } else { 0.0 };
        }
        let film = render(&scene, settings, 64);
        assert_eq!(film.rejected(), 0, "dispersion {dispersion}: NaN or infinite samples");
        let (mean, error) = mean_and_error(&film, w, h);
        eprintln!("dispersion {dispersion}: mean {mean:.5} ± {error:.5}");
        if dispersion == 0.0 {
            // Without dispersion every path is white itself: the channels agree per pixel. The
            // mean is 1 but for the paths the faceted spheres end (a refracted direction that
            // the interpolated normal allows and the facet does not): 5e-5 of them.
            for y in 0..h {
                for x in 0..w {
                    let p = film.pixel(x, y);
                    assert!((p.x - p.y).abs() < 1e-9 && (p.y - p.z).abs() < 1e-9, "({x}, {y}): {p}");
                }
            }
            assert!((mean - DVec3::ONE).abs().max_element() < 2e-4, "{mean}");
            plain = mean;
            continue;
        }
        for c in 0..3 {
            // 4σ of the dispersive run (the plain run's error is 30× smaller): a false failure
            // once in ~16,000 runs per channel; the seed is fixed, so it passes or fails always.
            let z = (mean[c] - plain[c]) / error[c];
            assert!(z.abs() < 4.0, "channel {c}: {} is {z:.1}σ from the undispersed {}", mean[c], plain[c]);
        }
    }
}

/// DispersionPrisms' prisms of index 1.5 at dispersion 0 and 2: a white backdrop with black
/// lines seen through a prism that bends light down. Without dispersion the view through it is
/// grey; with it the lines' edges are coloured, and the blue image of the lines lies above the
/// red one (blue is bent more, so a ray must leave the camera higher to reach the same line).
#[test]
fn a_prism_separates_blue_above_red() {
    let scene = Scene::load(furnace_tests::data::scene("DispersionPrisms/DispersionPrisms.gltf")).unwrap();
    let settings = RenderSettings {
        width: 400,
        height: 320,
        bounces: 8,
        sampler: SamplerKind::Sobol,
        seed: 3,
        ..RenderSettings::default()
    };
    let film = render(&scene, settings, 16);
    // The prisms of the second row (index 1.5): columns 0 (dispersion 0), 1 (dispersion 0.5) and
    // 3 (dispersion 2), the inner part of their faces in the image (the camera at 11 m, yfov
    // 0.46, frames 6.44 × 5.15 m of the prisms' plane in 400 × 320 pixels).
    let px = |x_m: f32, y_m: f32| ((200.0 + x_m * 400.0 / 6.44) as u32, (160.0 - y_m * 320.0 / 5.15) as u32);
    let profile = |x_m: f32| -> Vec<DVec3> {
        let (x0, y_top) = px(x_m - 0.25, 0.575 + 0.28);
        let (x1, y_bottom) = px(x_m + 0.25, 0.575 - 0.28);
        (y_top..y_bottom)
            .map(|y| (x0..x1).map(|x| film.pixel(x, y)).sum::<DVec3>() / f64::from(x1 - x0))
            .collect()
    };
    let plain = profile(-2.2);
    let chroma =
        |p: &[DVec3]| p.iter().map(|c| c.max_element() - c.min_element()).sum::<f64>() / p.len() as f64;
    eprintln!("chroma: dispersion 0 {:.4}, dispersion 2 {:.4}", chroma(&plain), chroma(&profile(1.1)));
    let spectral = profile(1.1);
    // Without dispersion the view through the prism is grey but for the light the backdrop
    // gets through its dispersive neighbours (1.2 % chroma against 42 %).
    assert!(chroma(&spectral) > 0.2, "dispersion colours the lines' edges");
    assert!(chroma(&plain) < 0.1 * chroma(&spectral), "without dispersion the prism is grey");
    // The shift of the blue profile against the red one that correlates best (rows, + = up),
    // at dispersion 0.5: red and blue ~3 rows apart, the lines' period through the prism ~16
    // rows, so a search over ±6 rows finds the shift without reaching the next line.
    let spectral = profile(-1.1);
    let n = spectral.len() as i32;
    let correlation = |k: i32| -> f64 {
        let (mut s, mut m) = (0.0, 0);
        for i in 0..n {
            let j = i + k;
            if (0..n).contains(&j) {
                s += (spectral[i as usize].z - 0.5) * (spectral[j as usize].x - 0.5);
                m += 1;
            }
        }
        s / f64::from(m)
    };
    let best = (-6..=6).max_by(|&a, &b| correlation(a).total_cmp(&correlation(b))).unwrap();
    eprintln!(
        "blue lies {best} rows above red; correlations {:?}",
        (-6..=6).map(|k| (correlation(k) * 1e3).round()).collect::<Vec<_>>()
    );
    // Expected 2.5 rows: the red and blue channels' centroid wavelengths (≈605 and 455 nm)
    // differ in index by 0.0137 at V_d = 40; ∂δ/∂n = 2 sin(A/2)/cos((A + δ)/2) = 0.74 at the
    // prism's minimum deviation; the backdrop 6 m behind the prisms, 17 m from the camera, turns
    // 0.0101 rad of deviation into 0.0036 rad at the camera: 2.5 rows at 696 rows per radian.
    assert!((2..=4).contains(&best), "blue must lie 2–4 rows above red: the best shift is {best}");
}
