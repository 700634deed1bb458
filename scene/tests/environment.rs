//! Environment maps: importance sampling against its pdf (chi-square), the pdf's normalisation,
//! and the loader's handling of maps named by a scene.

use furnace_scene::{Environment, EnvironmentMap, Scene};
use furnace_tests::Rng;
use furnace_tests::chi2::ChiSquareTest;
use glam::Vec3;
use std::sync::Arc;

/// Maps tested: a 1 × 1 constant, a random 7 × 5 (odd, not 2:1), a random 16 × 8 rotated 37° at
/// intensity 3, and a 16 × 8 map black but for one bright texel (a tiny sun), each with the plain
/// and the compensated distribution: eight tests, one family.
const TESTS: usize = 8;

fn maps() -> Vec<(String, Environment)> {
    let mut rng = Rng(0xe_2b);
    let mut random = |w: u32, h: u32| {
        let texels = (0..w * h).map(|_| Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0).collect();
        Arc::new(EnvironmentMap::new(w, h, texels, format!("random {w}x{h}")).unwrap().0)
    };
    let mut sun = vec![Vec3::ZERO; 16 * 8];
    sun[3 * 16 + 5] = Vec3::splat(1e6);
    let sun = Arc::new(EnvironmentMap::new(16, 8, sun, "one texel").unwrap().0);
    vec![
        ("constant".into(), Environment::new(Arc::new(EnvironmentMap::constant(Vec3::ONE)))),
        ("random 7x5".into(), Environment::new(random(7, 5))),
        (
            "random 16x8 rotated".into(),
            Environment { intensity: 3.0, rotation: 37f32.to_radians(), ..Environment::new(random(16, 8)) },
        ),
        ("one texel".into(), Environment::new(sun)),
    ]
}

/// Sampling follows the pdf (Pearson's chi-square over 64 × 128 cells of the sphere, 10⁶
/// samples, significance 0.01 for the family of eight, Šidák-corrected; the harness integrates
/// the pdf adaptively over each cell and fails if it does not integrate to 1). On failure the
/// observed and expected tables are written to `target/test-output/chi2/`.
#[test]
fn sampling_follows_the_pdf() {
    let dir = furnace_tests::data::output_dir("chi2");
    for (name, env) in maps() {
        for compensated in [false, true] {
            let sampler = env.sampler(compensated).expect("not black");
            let test = ChiSquareTest { test_count: TESTS, seed: 3, ..ChiSquareTest::default() };
            // The harness bins cos θ about +Z and φ from +X; the map's frame has its poles on ±Y
            // and u from −Z. Handing the harness `(−m.z, m.x, m.y)` of the map-frame direction m
            // puts the map's rows and columns on its cell grid's axes (cos θ = m.y, φ = 2πu):
            // the pdf's discontinuities lie along the axes its adaptive quadrature bisects.
            let to_harness = |d: Vec3| {
                let m = env.to_map(d);
                Vec3::new(-m.z, m.x, m.y)
            };
            let from_harness = |w: Vec3| env.to_world(Vec3::new(w.y, w.z, -w.x));
            // A sample on a cell's edge whose direction rounds into a neighbour of probability 0
            // (compensation makes such cells) is counted and left out: the harness would see a
            // sample where the pdf is 0. At most 10⁻⁵ of them.
            let mut on_edge = 0;
            let result = test.run(
                |u, _| {
                    let s = sampler.sample(&env, u)?;
                    if sampler.pdf(s.direction) == 0.0 {
                        on_edge += 1;
                        return None;
                    }
                    Some(to_harness(s.direction))
                },
                |w| sampler.pdf(from_harness(w)),
            );
            assert!(on_edge <= 10, "{name}: {on_edge} samples where the pdf is 0");
            let label = format!("environment {name}{}", if compensated { " compensated" } else { "" });
            eprintln!("{label}: {}", result.report().lines().next().unwrap_or(""));
            result.assert_passed(&label.replace(' ', "_"), &dir);
        }
    }
}

/// A sample's pdf is the pdf of its direction, and its radiance the radiance seen along it.
#[test]
fn samples_agree_with_pdf_and_lookup() {
    let mut rng = Rng(7);
    for (name, env) in maps() {
        let sampler = env.sampler(false).unwrap();
        for _ in 0..10_000 {
            let u = glam::Vec2::new(rng.f32(), rng.f32());
            let Some(s) = sampler.sample(&env, u) else { continue };
            let p = sampler.pdf(s.direction);
            // The direction's round trip through (u, v) may land on the neighbouring cell only
            // within rounding of an edge: 1 in 10⁴ here would be far more than that.
            assert!((p - s.pdf).abs() <= 1e-3 * s.pdf, "{name}: sampled pdf {} vs pdf {p}", s.pdf);
            let l = env.radiance(s.direction);
            assert!(
                (l - s.radiance).abs().max_element() <= 1e-3 * s.radiance.max_element().max(1e-3),
                "{name}"
            );
        }
    }
}

/// `extras.environment` of the reference scene loads its EXR (512 × 256, texel-centred as the
/// references' README rules); a scene naming a missing map fails naming both files.
#[test]
fn a_scene_names_its_environment() {
    let path = furnace_tests::data::reference("envmap/envmap_spheres.gltf");
    let scene = Scene::load(&path).unwrap();
    let env = scene.environment().expect("extras.environment");
    assert_eq!((env.map.width(), env.map.height()), (512, 256));
    assert!(env.visible && env.rotation == 0.0);
    assert!(scene.has_own_light());

    let dir = furnace_tests::data::output_dir("environment");
    let gltf = std::fs::read_to_string(&path).unwrap().replace("envmap_spheres_env.exr", "missing.exr");
    let moved = dir.join("missing_env.gltf");
    std::fs::write(&moved, gltf).unwrap();
    std::fs::copy(path.with_file_name("envmap_spheres.bin"), dir.join("envmap_spheres.bin")).unwrap();
    let e = Scene::load(&moved).unwrap_err().to_string();
    assert!(
        e.contains("missing_env.gltf")
            && e.contains("scenes[0].extras.environment.uri")
            && e.contains("missing.exr"),
        "{e}"
    );
}

/// Bad maps: a missing file, garbage bytes, a truncated EXR, an infinite texel — one error each,
/// naming the file (and the texel); negative texels and a map that is not 2:1 load with a
/// warning naming them.
#[test]
fn bad_maps_are_one_clear_error_or_a_warning() {
    let dir = furnace_tests::data::output_dir("environment");
    let missing = dir.join("no-such-map.hdr");
    let e = EnvironmentMap::load(&missing).unwrap_err().to_string();
    assert!(e.contains("no-such-map.hdr") && e.contains("cannot read"), "{e}");

    let garbage = dir.join("garbage.hdr");
    std::fs::write(&garbage, b"#?RADIANCE\nthis is not a header\n\x00\x01\x02").unwrap();
    let e = EnvironmentMap::load(&garbage).unwrap_err().to_string();
    assert!(e.contains("garbage.hdr") && e.contains("cannot decode"), "{e}");

    let exr = furnace_tests::data::reference("envmap/envmap_spheres_env.exr");
    let bytes = std::fs::read(&exr).unwrap();
    let truncated = dir.join("truncated.exr");
    std::fs::write(&truncated, &bytes[..bytes.len() / 3]).unwrap();
    let e = EnvironmentMap::load(&truncated).unwrap_err().to_string();
    assert!(e.contains("truncated.exr") && e.contains("cannot decode"), "{e}");

    let e = EnvironmentMap::new(
        3,
        2,
        vec![Vec3::ONE, Vec3::ONE, Vec3::ONE, Vec3::ONE, Vec3::new(0.0, 0.0, f32::INFINITY), Vec3::ONE],
        "inf.exr",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("inf.exr") && e.contains("(1, 1)") && e.contains("B = inf"), "{e}");

    let (_, w) = EnvironmentMap::new(7, 5, vec![Vec3::ONE; 35], "odd.hdr").unwrap();
    let w = w.expect("a warning");
    assert!(w.contains("odd.hdr") && w.contains("not 2:1"), "{w}");
    let (_, w) = EnvironmentMap::new(4, 2, vec![Vec3::ONE; 8], "fine.hdr").unwrap();
    assert!(w.is_none(), "{w:?}");
}
