//! White-furnace and closed-form tests of the path tracer.
//!
//! * A Lambert sphere of albedo 1 under a sky of radiance 1 is invisible (radiance 1).
//! * A GGX metal sphere (α = 1, F = 1, separable masking, no compensation) reflects the
//!   directional albedo `E(μ)` of each pixel's view angle: the expected image mean is
//!   `E(μ)` averaged over the pixel centres, as the oracle (the oracle script `render_ref.py` of the references,
//!   `furnace_stats`) computes it (Mitsuba 3, at its camera: 0.37282).
//! * With Turquin compensation the metal sphere is invisible again.
//! * Looking from inside a sphere with albedo ½ and emission ½, a path with `B` bounces sees
//!   exactly `Σ_{k=0..B} ½·½ᵏ = 1 − 2^−(B+1)` (pbrt-v4's "Kd 0.5, Le 0.5" test): checks the
//!   bounce convention exactly, and Russian roulette for bias.
//! * A Lambert floor under the sun receives `albedo/π · E · cos θ`.
//!
//! Statistical tests use the random sampler (independent passes) with a fixed seed, estimate
//! their Monte Carlo standard error from 8 independent passes, and require it to be below a
//! fifth of the tolerance, so that a failure means bias, not noise.

use furnace_brdf::{Masking, SpecularOptions};
use furnace_cpu::CpuRenderer;
use furnace_render::{Film, RenderSettings};
use furnace_sampling::SamplerKind;
use furnace_scene::{Camera, Geometry, Light, Material, Scene, Sun, builtin, oct_encode};
use glam::{Vec2, Vec3};

/// Sphere tessellation: `4·n·(n−1)` triangles. The flat triangles lie within
/// `1 − cos(π/n)` ≈ 5e-4 of the unit sphere, inside the masks' margins (0.995, 1.01).
const SPHERE_N: u32 = 96;
const SIZE: u32 = 64;
const PASSES: u32 = 8;

/// A pixel `(x, y)`.
type Pixel = (u32, u32);

/// Pixels whose four corners all hit a sphere of radius 0.995 (`sphere`) and pixels whose four
/// corners all miss one of radius 1.01 (`background`), as the oracle's `furnace_stats` does.
fn masks(camera: &Camera) -> (Vec<Pixel>, Vec<Pixel>) {
    let hits = |x: u32, y: u32, r: f32| {
        let ray = camera.generate_ray(Vec2::new(x as f32, y as f32), SIZE, SIZE);
        let b = ray.direction.dot(ray.origin);
        b * b - (ray.origin.length_squared() - r * r) > 0.0
    };
    let corners =
        |x: u32, y: u32, r: f32| [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)].map(|(i, j)| hits(i, j, r));
    let mut sphere = Vec::new();
    let mut background = Vec::new();
    for y in 0..SIZE {
        for x in 0..SIZE {
            if corners(x, y, 0.995).iter().all(|&h| h) {
                sphere.push((x, y));
            }
            if corners(x, y, 1.01).iter().all(|&h| !h) {
                background.push((x, y));
            }
        }
    }
    (sphere, background)
}

/// `(mean, standard error)` of the mean channel over `pixels`, from `PASSES` independent passes
/// of `spp` samples each (random sampler), and the accumulated film.
fn render_stats(renderer: &CpuRenderer, pixels: &[(u32, u32)], spp: u32) -> (f64, f64, Film) {
    let mut total = renderer.new_film();
    let mut means = Vec::new();
    for pass in 0..PASSES {
        let mut film = renderer.new_film();
        renderer.render_into(&mut film, pass * spp, spp).expect("render");
        renderer.render_into(&mut total, pass * spp, spp).expect("render");
        means.push(
            pixels.iter().map(|&(x, y)| film.pixel(x, y).element_sum() / 3.0).sum::<f64>()
                / pixels.len() as f64,
        );
        assert_eq!(film.rejected(), 0);
    }
    let n = f64::from(PASSES);
    let mean = means.iter().sum::<f64>() / n;
    let var = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt(), total)
}

fn furnace(material: Material, specular: SpecularOptions, bounces: u32) -> CpuRenderer {
    let scene = builtin::furnace_sphere(material, SPHERE_N);
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        bounces,
        sampler: SamplerKind::Random,
        seed: 1,
        specular,
        ..Default::default()
    };
    CpuRenderer::with_default_camera(scene, settings).expect("a progressive sampler")
}

#[test]
fn lambert_white_furnace_is_invisible() {
    let renderer = furnace(builtin::lambert(Vec3::ONE), SpecularOptions::default(), 4);
    let (sphere, background) = masks(&renderer.scene().default_camera());
    assert!(sphere.len() > 1000, "{} sphere pixels", sphere.len());
    // Every Lambert path of albedo 1 carries exactly 1 when it escapes, so the noise is only
    // the rare path lost to the flat triangles; 4 spp per pass suffices.
    let (mean, stderr, film) = render_stats(&renderer, &sphere, 4);
    println!("Lambert furnace: sphere mean {mean:.6} ± {stderr:.1e} over {} pixels", sphere.len());
    // Tolerance 0.2% (the brief's): the rendering is exact up to paths lost where a sampled
    // direction is above the shading normal's horizon but below the flat triangle.
    assert!((mean - 1.0).abs() < 2e-3, "sphere mean {mean}");
    assert!(stderr < 4e-4, "Monte Carlo error {stderr} not well below the tolerance");
    let bg = background.iter().map(|&(x, y)| film.pixel(x, y).element_sum() / 3.0).sum::<f64>()
        / background.len() as f64;
    assert_eq!(bg, 1.0, "background = sky");
}

/// `μ = −n·d` where the ray through film point `p` meets the exact unit sphere.
fn view_cosine(camera: &Camera, p: Vec2) -> f64 {
    let ray = camera.generate_ray(p, SIZE, SIZE);
    let (o, d) = (ray.origin.as_dvec3(), ray.direction.as_dvec3());
    let b = d.dot(o);
    let t = -b - (b * b - (o.length_squared() - 1.0)).sqrt().max(0.0);
    -(o + t * d).dot(d)
}

/// The expected metal-sphere image mean: `E(μ)` (Gauss–Legendre quadrature of order 96,
/// `furnace_brdf::turquin::directional_albedo`) averaged over the masked pixels, with `μ` from
/// the exact unit sphere. Returns `(at pixel centres, over pixel areas)`: the first is what
/// the oracle's `furnace_stats` computes; the second averages `E(μ)` over 8×8 points in each
/// pixel, which is what a box-filtered render converges to (at 64×64 the two differ by ~0.1%,
/// because `E(μ)` is curved and `μ` varies fast near the silhouette). `E` is tabulated on
/// 1025 values of `μ` and interpolated linearly (error < 1e-6).
fn expected_ggx_mean(camera: &Camera, sphere: &[(u32, u32)], alpha: f32) -> (f64, f64) {
    const GRID: usize = 1024;
    let table: Vec<f64> = (0..=GRID)
        .map(|i| {
            furnace_brdf::turquin::directional_albedo(
                (i as f32 / GRID as f32).max(1e-4),
                alpha,
                Masking::Separable,
                96,
            )
        })
        .collect();
    let e = |mu: f64| {
        let x = mu.clamp(0.0, 1.0) * GRID as f64;
        let i = (x as usize).min(GRID - 1);
        table[i] + (x - i as f64) * (table[i + 1] - table[i])
    };
    let n = sphere.len() as f64;
    let centres = sphere
        .iter()
        .map(|&(x, y)| e(view_cosine(camera, Vec2::new(x as f32 + 0.5, y as f32 + 0.5))))
        .sum::<f64>();
    let areas = sphere
        .iter()
        .map(|&(x, y)| {
            let sub = (0..64).map(|k| {
                let p = Vec2::new(
                    x as f32 + ((k % 8) as f32 + 0.5) / 8.0,
                    y as f32 + ((k / 8) as f32 + 0.5) / 8.0,
                );
                e(view_cosine(camera, p))
            });
            sub.sum::<f64>() / 64.0
        })
        .sum::<f64>();
    (centres / n, areas / n)
}

#[test]
fn ggx_alpha_one_furnace_matches_directional_albedo() {
    let renderer = furnace(builtin::metal(1.0), SpecularOptions::mitsuba(), 4);
    let camera = renderer.scene().default_camera();
    let (sphere, _) = masks(&camera);
    let (at_centres, expected) = expected_ggx_mean(&camera, &sphere, 1.0);
    let (mean, stderr, _) = render_stats(&renderer, &sphere, 256);
    println!(
        "GGX α=1 furnace: sphere mean {mean:.5} ± {stderr:.1e}, expected {expected:.5} over pixel areas \
         (ratio {:.5}), {at_centres:.5} at pixel centres (ratio {:.5})",
        mean / expected,
        mean / at_centres
    );
    // Tolerance 0.5% (the brief's; Mitsuba matched the quadrature to 1.5e-4).
    assert!((mean / expected - 1.0).abs() < 5e-3, "sphere mean {mean} vs {expected}");
    assert!(stderr < 1e-3 * expected, "Monte Carlo error {stderr} not well below the tolerance");
}

#[test]
fn ggx_alpha_one_with_compensation_is_invisible() {
    for masking in [Masking::Separable, Masking::HeightCorrelated] {
        let options = SpecularOptions { masking, compensation: true, ..SpecularOptions::default() };
        let renderer = furnace(builtin::metal(1.0), options, 4);
        let (sphere, _) = masks(&renderer.scene().default_camera());
        let (mean, stderr, _) = render_stats(&renderer, &sphere, 256);
        println!("GGX α=1 compensated ({masking:?}): sphere mean {mean:.5} ± {stderr:.1e}");
        // Tolerance: ≥ 0.995 (the brief's); Turquin with F0 = 1 restores the albedo to 1 up to
        // the table's interpolation error. The upper bound catches energy gain.
        assert!((0.995..1.005).contains(&mean), "{masking:?}: sphere mean {mean}");
        assert!(stderr < 1e-3, "{masking:?}: Monte Carlo error {stderr}");
    }
}

/// The camera inside a sphere of albedo ½ and emission ½. Its light samples choose triangles
/// by power: inside a sphere a triangle's solid angle per unit area is `cos θ / d²` with
/// `cos θ = d / 2R`, so the power choice's light pdf is `cos θ / π`, the cosine BSDF's, and
/// every path's MIS estimate is exact (the light BVH's choice, unbiased too, would add noise).
fn glowing_interior(bounces: u32, russian_roulette: bool) -> CpuRenderer {
    let mut material = builtin::lambert(Vec3::splat(0.5));
    material.emissive = Vec3::splat(0.5);
    let mut scene = builtin::furnace_sphere(material, 64);
    // Emission is one-sided: turn the sphere inside out (winding and normals) so that its
    // emitting side faces the camera inside it.
    for t in &mut scene.geometry.triangles {
        t.swap(1, 2);
    }
    for n in &mut scene.geometry.normals {
        *n = furnace_scene::oct_encode(-furnace_scene::oct_decode(*n));
    }
    scene.cameras = vec![Camera::look_at(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, furnace_scene::DEFAULT_YFOV)];
    let settings = RenderSettings {
        width: 16,
        height: 16,
        bounces,
        sampler: SamplerKind::Random,
        seed: 3,
        russian_roulette,
        light_selection: furnace_render::LightSelection::Power,
        ..Default::default()
    };
    CpuRenderer::with_default_camera(scene, settings).expect("a progressive sampler")
}

#[test]
fn bounces_count_scattering_events() {
    let pixels: Vec<_> = (0..16).flat_map(|y| (0..16).map(move |x| (x, y))).collect();
    for bounces in [0, 1, 2, 4, 8] {
        let renderer = glowing_interior(bounces, false);
        let (mean, _, _) = render_stats(&renderer, &pixels, 2);
        let expected = 1.0 - 0.5f64.powi(bounces as i32 + 1);
        println!("glowing interior, {bounces} bounces: {mean:.6} (expected {expected:.6})");
        // Tolerance 1e-3: every path's value is exact (Lambert weight = albedo) except the rare
        // path lost between the shading and the geometric horizon of the flat triangles.
        assert!((mean - expected).abs() < 1e-3, "{bounces} bounces: {mean} vs {expected}");
    }
}

#[test]
fn russian_roulette_is_unbiased() {
    let pixels: Vec<_> = (0..16).flat_map(|y| (0..16).map(move |x| (x, y))).collect();
    let renderer = glowing_interior(12, true);
    let (mean, stderr, _) = render_stats(&renderer, &pixels, 64);
    let expected = 1.0 - 0.5f64.powi(13);
    println!(
        "glowing interior, 12 bounces, Russian roulette: {mean:.5} ± {stderr:.1e} (expected {expected:.5})"
    );
    // Tolerance: 5 standard errors plus the 1e-3 of the flat triangles (see above).
    assert!((mean - expected).abs() < 5.0 * stderr + 1e-3, "{mean} ± {stderr} vs {expected}");
    assert!(stderr > 0.0 && stderr < 2e-3, "roulette adds some noise, not much: {stderr}");
}

#[test]
fn sunlit_lambert_floor() {
    // A 20 m square floor at y = 0, seen from 1 m above, looking straight down; sun at 60° from
    // the zenith; sky black; bounces = 1 (direct light only).
    let mut g = Geometry::default();
    let s = 10.0;
    g.positions =
        vec![Vec3::new(-s, 0.0, -s), Vec3::new(-s, 0.0, s), Vec3::new(s, 0.0, s), Vec3::new(s, 0.0, -s)];
    g.normals = vec![oct_encode(Vec3::Y); 4];
    g.triangles = vec![[0, 1, 2], [0, 2, 3]];
    g.triangle_materials = vec![0, 0];
    let albedo = Vec3::new(0.8, 0.5, 0.2);
    let theta = 60f32.to_radians();
    let irradiance = Vec3::new(3.0, 2.0, 1.0);
    let scene = Scene {
        name: "floor".into(),
        geometry: g,
        instancing: Default::default(),
        materials: vec![builtin::lambert(albedo), Material::default()],
        textures: Vec::new(),
        images: Vec::new(),
        cameras: vec![Camera::look_at(Vec3::Y, Vec3::ZERO, Vec3::Z, 0.5)],
        lights: vec![Light::Sun(Sun::delta(-Vec3::new(theta.sin(), theta.cos(), 0.0), irradiance))],
        warnings: Vec::new(),
        dropped_triangles: 0,
        extensions: Vec::new(),
        variants: Vec::new(),
        animations: Vec::new(),
        posed_by: None,
    };
    let settings = RenderSettings { width: 8, height: 8, bounces: 1, ..Default::default() };
    let renderer = CpuRenderer::with_default_camera(scene, settings).expect("a progressive sampler");
    let mut film = renderer.new_film();
    renderer.render_into(&mut film, 0, 4).expect("render");
    let expected = (albedo / std::f32::consts::PI * irradiance * theta.cos()).as_dvec3();
    for y in 0..8 {
        for x in 0..8 {
            // Tolerance: f32 rounding of the BRDF and frame (deterministic, no noise).
            let err = ((film.pixel(x, y) - expected) / expected).abs().max_element();
            assert!(err < 1e-5, "pixel ({x}, {y}): {} vs {expected}", film.pixel(x, y));
        }
    }
}
