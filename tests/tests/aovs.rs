//! First-hit AOVs (albedo, shading normal, depth): what they hold, checked against geometry
//! computed here independently, and the GPU integrator's against the CPU reference's.
//!
//! 1. Semantics on the white-furnace sphere (a unit sphere seen from z = 4, sky around it), CPU:
//!    pixels whose corners and centre all hit the sphere (by an analytic ray–sphere test here)
//!    must hold exactly the material's base colour, full coverage, a depth within the corners'
//!    analytic depths (widened by the tessellation's sagitta) and a normal near the radial one;
//!    pixels whose corners and centre all miss hold the miss values (albedo 1, normal 0, depth
//!    +∞, coverage 0).
//! 2. Same samples on both backends (Sobol, one seed): the AOV images agree per pixel (paths
//!    only part where a float differs at a triangle edge), for both GPU film precisions.
//! 3. AOVs do not change the image: the colour sums are bit-identical with AOVs on and off.

use furnace_cpu::CpuRenderer;
use furnace_gpu::GpuRenderer;
use furnace_render::{AovSample, Film, Integrator, RenderSettings};
use furnace_sampling::SamplerKind;
use furnace_scene::{Scene, builtin};
use furnace_tests::gpu::test_context;
use glam::{DVec3, Vec2, Vec3};

const ALBEDO: Vec3 = Vec3::new(0.2, 0.5, 0.8);
/// Rings of the UV sphere: its facets lie within 1 − cos(π/64) ≈ 1.2·10⁻³ of the unit sphere.
const RINGS: u32 = 64;

fn sphere() -> Scene {
    builtin::furnace_sphere(builtin::lambert(ALBEDO), RINGS)
}

fn settings(size: u32, aovs: bool) -> RenderSettings {
    RenderSettings {
        width: size,
        height: size,
        sampler: SamplerKind::Sobol,
        seed: 7,
        aovs,
        ..RenderSettings::default()
    }
}

fn render_cpu(scene: &Scene, s: RenderSettings, spp: u32) -> Film {
    let cpu = CpuRenderer::with_default_camera(scene.clone(), s).unwrap();
    let mut film = cpu.new_film();
    cpu.render_into(&mut film, 0, spp).unwrap();
    film
}

/// The analytic hit of a ray with the unit sphere at the origin: (t, outward normal).
fn unit_sphere_hit(origin: Vec3, dir: Vec3) -> Option<(f32, Vec3)> {
    let b = origin.dot(dir);
    let c = origin.length_squared() - 1.0;
    let disc = b * b - c;
    (disc > 0.0).then(|| {
        let t = -b - disc.sqrt();
        (t, (origin + t * dir).normalize())
    })
}

#[test]
fn aovs_hold_the_first_hit_of_the_camera_ray() {
    const SIZE: u32 = 48;
    let scene = sphere();
    let film = render_cpu(&scene, settings(SIZE, true), 16);
    let camera = scene.default_camera();
    // Tessellation: the facets lie up to the sagitta inside the sphere, so depths differ from
    // the analytic ones by at most that over the cosine of incidence, which is at least
    // √(1 − 0.95²) ≈ 0.31 for the pixels kept below (their rays pass at least 0.05 inside the
    // silhouette).
    let sagitta = 1.0 - (std::f32::consts::PI / RINGS as f32).cos();
    let (mut inside, mut outside) = (0, 0);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let points = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.5)];
            let hits: Vec<Option<(f32, Vec3)>> = points
                .iter()
                .map(|&(dx, dy)| {
                    let ray = camera.generate_ray(Vec2::new(x as f32 + dx, y as f32 + dy), SIZE, SIZE);
                    // Margin from the silhouette: the ray's closest approach to the centre.
                    let closest = (ray.origin - ray.origin.dot(ray.direction) * ray.direction).length();
                    if (closest - 1.0).abs() < 0.05 {
                        return Some((f32::NAN, Vec3::ZERO));
                    }
                    unit_sphere_hit(ray.origin, ray.direction)
                })
                .collect();
            let i = (y * SIZE + x) as usize;
            let m = film.aov(i).unwrap();
            if hits.iter().all(|h| h.is_some_and(|(t, _)| t.is_finite())) {
                inside += 1;
                let (tmin, tmax) =
                    hits.iter().flatten().fold((f32::MAX, f32::MIN), |(a, b), &(t, _)| (a.min(t), b.max(t)));
                let slack = f64::from(sagitta / 0.3);
                assert_eq!(m.albedo, ALBEDO.as_dvec3(), "pixel ({x}, {y}) albedo");
                assert_eq!(m.coverage, 1.0, "pixel ({x}, {y}) coverage");
                assert!(
                    m.depth > f64::from(tmin) - slack && m.depth < f64::from(tmax) + slack,
                    "pixel ({x}, {y}) depth {} outside the corners' [{tmin}, {tmax}] ± {slack}",
                    m.depth
                );
                // The mean of unit normals spread over the pixel: within the corners' spread of
                // the centre's radial normal (plus the shading normals' interpolation error).
                let centre = hits[4].unwrap().1.as_dvec3();
                let spread =
                    hits.iter().flatten().map(|&(_, n)| (n.as_dvec3() - centre).length()).fold(0.0, f64::max);
                assert!(
                    (m.normal - centre).length() < spread + 2e-3,
                    "pixel ({x}, {y}) normal {:?} vs radial {centre:?} (corner spread {spread})",
                    m.normal
                );
            } else if hits.iter().all(Option::is_none) {
                outside += 1;
                assert_eq!(m.albedo, DVec3::ONE, "pixel ({x}, {y}): a miss has albedo 1");
                assert_eq!(m.normal, DVec3::ZERO, "pixel ({x}, {y}): a miss has no normal");
                assert_eq!((m.depth, m.coverage), (f64::INFINITY, 0.0), "pixel ({x}, {y})");
            }
        }
    }
    eprintln!("{inside} pixels wholly on the sphere, {outside} wholly off it, of {}", SIZE * SIZE);
    // The sphere spans about half the view's height: both kinds are plentiful.
    assert!(inside > 300 && outside > 800, "too few checked pixels: {inside} on, {outside} off");
}

#[test]
fn aovs_leave_the_image_bit_identical() {
    let scene = builtin::cornell_box().unwrap();
    let (off, on) = (render_cpu(&scene, settings(24, false), 4), render_cpu(&scene, settings(24, true), 4));
    assert_eq!(off.sums(), on.sums());
    assert_eq!(off.counts(), on.counts());
    let camera = scene.default_camera();
    let mut films = Vec::new();
    for aovs in [false, true] {
        let Some(ctx) = test_context() else { return };
        let mut gpu = GpuRenderer::new(ctx, &scene, &camera, settings(24, aovs)).unwrap();
        gpu.render_pass(0, 4).unwrap();
        films.push(gpu.film().unwrap());
    }
    assert!(!films[0].has_aovs() && films[1].has_aovs());
    assert_eq!(films[0].sums(), films[1].sums(), "GPU colour sums with and without AOVs");
}

/// Per-pixel comparison of two films' AOV means: (pixels within `tol` on every channel, the
/// largest difference), with the first few outliers printed.
fn compare_aovs(a: &Film, b: &Film, tol: f64) -> (usize, f64) {
    let n = a.counts().len();
    let (mut close, mut worst, mut shown) = (0, 0.0f64, 0);
    for i in 0..n {
        let (p, q) = (a.aov(i).unwrap(), b.aov(i).unwrap());
        let depth = if p.depth.is_infinite() || q.depth.is_infinite() {
            if p.depth == q.depth { 0.0 } else { f64::INFINITY }
        } else {
            (p.depth - q.depth).abs() / p.depth.max(1.0)
        };
        let d = (p.albedo - q.albedo)
            .abs()
            .max_element()
            .max((p.normal - q.normal).abs().max_element())
            .max(depth)
            .max((p.coverage - q.coverage).abs());
        if d < tol {
            close += 1;
        } else if shown < 5 {
            shown += 1;
            eprintln!("pixel {i}: {p:?} vs {q:?}");
        }
        worst = worst.max(d);
    }
    (close, worst)
}

#[test]
fn gpu_aovs_match_the_cpu_reference_sample_for_sample() {
    const SIZE: u32 = 32;
    const SPP: u32 = 8;
    for (name, scene) in [("cbox", builtin::cornell_box().unwrap()), ("sphere", sphere())] {
        let s = settings(SIZE, true);
        let cpu = render_cpu(&scene, s, SPP);
        for f64_film in [true, false] {
            let Some(mut ctx) = test_context() else { return };
            // An adapter without f64 sums each pass in f32 and folds it on the host.
            ctx.shader_f64 &= f64_film;
            let mut gpu = GpuRenderer::new(ctx, &scene, &scene.default_camera(), s).unwrap();
            // Two passes: the F32Pass film folds the first into its host sums.
            gpu.render_pass(0, SPP / 2).unwrap();
            gpu.render_pass(SPP / 2, SPP / 2).unwrap();
            let g = Integrator::film(&mut gpu).unwrap();
            let (close, worst) = compare_aovs(&cpu, &g, 1e-5);
            let n = (SIZE * SIZE) as usize;
            eprintln!(
                "{name}, {:?} film: {close}/{n} pixels' AOVs within 1e-5 of the CPU's, largest difference {worst:e}",
                gpu.film_precision()
            );
            // The same sample points give the same first hits; a pixel differs only where a ray
            // grazes a triangle edge and the two backends' floats pick different triangles
            // (1e-5: f32 sums of ≤ 8 samples differ from f64 ones by ~1e-7 relative).
            assert!(close * 100 >= n * 98, "{name}: only {close}/{n} pixels agree");
        }
    }
}

/// Resuming a film with AOVs (read back, loaded into a new renderer) continues it exactly, and
/// a film without AOVs is refused by a render with them (and the other way round).
#[test]
fn gpu_aovs_resume_exactly_and_mismatches_are_refused() {
    let Some(ctx) = test_context() else { return };
    let context = || test_context().expect("a second context");
    let scene = builtin::cornell_box().unwrap();
    let camera = scene.default_camera();
    let s = settings(16, true);
    let mut whole = GpuRenderer::new(ctx, &scene, &camera, s).unwrap();
    whole.render_pass(0, 6).unwrap();
    let mut first = GpuRenderer::new(context(), &scene, &camera, s).unwrap();
    first.render_pass(0, 2).unwrap();
    let saved = first.film().unwrap();
    let mut second = GpuRenderer::new(context(), &scene, &camera, s).unwrap();
    second.load_film(&saved).unwrap();
    second.render_pass(2, 4).unwrap();
    assert_eq!(second.film().unwrap(), whole.film().unwrap(), "resumed film with AOVs");
    let e = second.load_film(&Film::new(16, 16)).unwrap_err().to_string();
    assert!(e.contains("no AOVs"), "{e}");
    let mut plain = GpuRenderer::new(context(), &scene, &camera, settings(16, false)).unwrap();
    let e = plain.load_film(&saved).unwrap_err().to_string();
    assert!(e.contains("has AOVs"), "{e}");
    // The CPU integrator refuses alike.
    let mut cpu = CpuRenderer::with_default_camera(scene, s).unwrap();
    assert!(cpu.set_film(&Film::new(16, 16)).is_err());
}

/// `sample_with_aovs` is `sample` plus the record of the first hit.
#[test]
fn a_sample_and_its_aovs() {
    let scene = sphere();
    let cpu = CpuRenderer::with_default_camera(scene, settings(8, true)).unwrap();
    let (value, aov) = cpu.sample_with_aovs(4, 4, 3);
    assert_eq!(value, cpu.sample(4, 4, 3));
    assert_eq!(aov.albedo, ALBEDO);
    // Pixel (4, 4) of 8 looks within 6° of the centre: the sphere's front, 3 to 3.07 away.
    assert!(aov.depth.is_some_and(|d| (2.99..3.08).contains(&d)), "{aov:?}");
    let (_, corner) = cpu.sample_with_aovs(0, 0, 0);
    assert_eq!(corner, AovSample::MISS);
}

/// The emitting side of an emitter has albedo 1 (its base colour, black here, would tell a
/// denoiser the light has no colour), on both backends.
#[test]
fn an_emitter_seen_directly_has_albedo_one() {
    let path = furnace_tests::data::reference("lights/cbox_area.gltf");
    let scene = Scene::load(&path).unwrap();
    let s = settings(64, true);
    let cpu = CpuRenderer::with_default_camera(scene.clone(), s).unwrap();
    // The ceiling panel covers the pixels around (32, 11) of the 64² view (x 25–39, y 9–14 at
    // 256² scaled by 1/4).
    let (_, aov) = cpu.sample_with_aovs(32, 11, 0);
    assert_eq!(aov.albedo, Vec3::ONE, "{aov:?}");
    let film = render_cpu(&scene, s, 4);
    let i = 11 * 64 + 32;
    assert_eq!(film.aov(i).unwrap().albedo, DVec3::ONE);
    let Some(ctx) = test_context() else { return };
    let mut gpu = GpuRenderer::new(ctx, &scene, &scene.default_camera(), s).unwrap();
    gpu.render_pass(0, 4).unwrap();
    assert_eq!(gpu.film().unwrap().aov(i).unwrap().albedo, DVec3::ONE);
}
