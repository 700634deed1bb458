//! Where the CPU integrator could fail, measured (the figures and
//! what the program does at each edge are in `docs/stability.md`).
//!
//! * `scaled_cornell_box_renders_the_same_image` — the reference Cornell box with every length
//!   (vertex positions, camera position) multiplied by `s` renders the image of `s = 1`: robust
//!   ray offsets (`furnace_accel::offset_ray_origin_scaled`, Wächter & Binder with the constants
//!   scaled by the scene's `offset_scale`) instead of the thesis's fixed `p + 1e-3·n`. Asserted
//!   from 1e-12 to 1e12 (the range asked for was 1e-3 … 1e4); measured and printed, not asserted,
//!   for s ∈ {1e-15, 1e-14, 1e-13, 1e13}, where it breaks: the f32 Möller–Trumbore products
//!   underflow to subnormals below ~2e-13 (a triple product of three lengths) and overflow above
//!   ~1e13 (edge² × distance ≈ 1e39). With the paper's absolute constants the range ended at 1e-3:
//!   below 1e-4 the float step (`FLOAT_SCALE` = 2⁻¹⁶ for coordinates under 1/32) was a sizeable
//!   fraction of the box and light leaked through corners (mean ratio 1.65 at 1e-6).
//!
//! Each image is 128 independent passes of one random-sampler sample per pixel at 48×48, so every
//! pixel has a standard error from its pass spread (`furnace_tests::cbox::render_passes`); two
//! images are compared per pixel and channel by `z = (a − b)/√(se_a² + se_b²)` and by the ratio
//! of their means. Both use the same sampler and seed, so where the scaled render traces the same
//! paths the pixels are equal and z = 0; a broken offset or a lost hit shows as a biased mean
//! (light leaks, acne, black pixels) and large |z|.
//!
//! On failure the images, the z image and the table are written to
//! `target/test-output/stability/stability_scale_*`.

use furnace_accel::{BuildOptions, Bvh, offset_ray_origin_scaled};
use furnace_cpu::CpuRenderer;
use furnace_render::RenderSettings;
use furnace_sampling::SamplerKind;
use furnace_scene::Scene;
use furnace_tests::cbox::{self, Estimate, Reference};
use glam::{Vec2, Vec3};
use std::fmt::Write as _;

fn output_dir() -> std::path::PathBuf {
    furnace_tests::data::output_dir("stability")
}

/// Image size and passes (× 1 spp) of the scale test: 295k paths per scale.
const SIZE: u32 = 48;
const PASSES: u32 = 128;

/// The Cornell box with every length multiplied by `s` ([`Scene::scale_lengths`]; its cameras
/// are pinholes with no near plane, so the image does not change).
fn scaled_cbox(s: f32) -> Scene {
    let mut scene = furnace_scene::builtin::cornell_box().expect("the built-in Cornell box");
    scene.scale_lengths(s);
    scene
}

fn render(scene: &Scene) -> Estimate {
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        bounces: 4,
        sampler: SamplerKind::Random,
        seed: 7,
        ..Default::default()
    };
    let mut renderer =
        CpuRenderer::with_default_camera(scene.clone(), settings).expect("a progressive sampler");
    cbox::render_passes(&mut renderer, PASSES, 1)
}

/// The diagnosis: of the camera rays through the pixel centres that hit a triangle, the
/// fraction whose secondary ray, started at the hit (interpolated from the barycentrics, as the
/// integrator does) moved by `offset_ray_origin` and leaving the surface at 45°, hits the same
/// triangle again. A flat triangle cannot be hit by a ray leaving it, so any such hit is
/// self-intersection.
fn self_hit_fraction(scene: &Scene) -> f64 {
    let g = &scene.geometry;
    let bvh = Bvh::from_indexed(&g.positions, &g.triangles, BuildOptions::default());
    let camera = scene.default_camera();
    let (mut hits, mut self_hits) = (0u32, 0u32);
    for j in 0..SIZE {
        for i in 0..SIZE {
            let ray = camera.generate_ray(Vec2::new(i as f32 + 0.5, j as f32 + 0.5), SIZE, SIZE);
            let Some(hit) = bvh.closest_hit(ray.origin, ray.direction, f32::INFINITY) else { continue };
            let Some([v0, v1, v2]) = g.triangle(hit.triangle as usize) else { continue };
            let (b1, b2) = (hit.barycentrics.x, hit.barycentrics.y);
            let p = (1.0 - b1 - b2) * v0 + b1 * v1 + b2 * v2;
            // The cross product scaled before normalising, as the integrator does at any scale.
            let c = (v1 - v0).cross(v2 - v0);
            let mut n = (c / c.abs().max_element()).normalize_or_zero();
            if n.dot(ray.direction) > 0.0 {
                n = -n;
            }
            // 45° from the normal, towards a fixed tangent direction.
            let d = (n + n.any_orthonormal_vector()).normalize();
            hits += 1;
            let origin = offset_ray_origin_scaled(p, n, {
                let (lo, hi) = scene.geometry.bounds();
                furnace_accel::offset_scale_of_bounds(lo, hi)
            });
            let again = bvh.closest_hit(origin, d, f32::INFINITY);
            self_hits += u32::from(again.is_some_and(|h| h.triangle == hit.triangle));
        }
    }
    f64::from(self_hits) / f64::from(hits.max(1))
}

/// What one scale did against `s = 1`.
struct Row {
    scale: f32,
    ratio: Vec3,
    ratio_se: f64,
    z_std: f64,
    z_max: f64,
    z_over_4: f64,
    identical: f64,
    self_hits: f64,
}

fn compare(scale: f32, base: &Estimate, candidate: &Estimate, self_hits: f64) -> (Row, cbox::Comparison) {
    let reference = Reference { name: "s = 1".into(), mean: base.mean.clone(), stderr: base.stderr.clone() };
    let c = cbox::compare(candidate, &reference);
    let identical = base.mean.pixels.iter().zip(&candidate.mean.pixels).filter(|(a, b)| a == b).count()
        as f64
        / base.mean.pixels.len() as f64;
    let z_over_4 = c.z_image.pixels.iter().flat_map(|z| z.to_array()).filter(|z| z.abs() > 4.0).count()
        as f64
        / (3 * base.mean.pixels.len()) as f64;
    let row = Row {
        scale,
        ratio: c.ratio().as_vec3(),
        ratio_se: c.ratio_se.max_element(),
        z_std: c.z_std,
        z_max: c.z_max.0,
        z_over_4,
        identical,
        self_hits,
    };
    (row, c)
}

fn table(rows: &[Row]) -> String {
    let mut t = String::from(
        "| scale | mean ratio R, G, B vs s = 1 (± se) | z std | max \\|z\\| | \\|z\\| > 4 | identical pixels | self-hits after offset |\n|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            t,
            "| {:e} | {:.4}, {:.4}, {:.4} (± {:.4}) | {:.3} | {:.1} | {:.4} | {:.3} | {:.4} |",
            r.scale,
            r.ratio.x,
            r.ratio.y,
            r.ratio.z,
            r.ratio_se,
            r.z_std,
            r.z_max,
            r.z_over_4,
            r.identical,
            r.self_hits
        );
    }
    t
}

#[test]
fn scaled_cornell_box_renders_the_same_image() {
    // Asserted: the range asked for, 1e-3 … 1e4, every decade, and on to 1e12 (measured to hold
    // since the integrator's geometric normal no longer overflows, see `geometric_normal`).
    const HELD: [f32; 18] = [
        1e-12, 1e-10, 1e-8, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e8, 1e10, 1e12,
    ];
    // Measured only (printed; the edge is reported in docs/stability.md).
    const PROBED: [f32; 4] = [1e-15, 1e-14, 1e-13, 1e13];
    let base_scene = scaled_cbox(1.0);
    let base = render(&base_scene);
    let base_self_hits = self_hit_fraction(&base_scene);
    let mut rows = vec![];
    let mut failures = vec![];
    let dir = output_dir();
    for &s in HELD.iter().chain(&PROBED) {
        let scene = scaled_cbox(s);
        let candidate = render(&scene);
        let (row, c) = compare(s, &base, &candidate, self_hit_fraction(&scene));
        let held = HELD.contains(&s);
        // The bar: the image mean within 4 standard errors of the ratio (or 0.5%, the
        // Mitsuba-reference bar of tests/mitsuba.rs, whichever is larger) and no pixel
        // channel beyond |z| = 6. Both renders trace the same sampler numbers, so an unbroken
        // scale gives z ≈ 0 except where rounding sends a path elsewhere; independent
        // renders would give max |z| ≈ 4.5 over the 6912 values, so 6 is not reached by noise
        // either way.
        let ratio_bar = (4.0 * row.ratio_se).max(5e-3);
        let ratio_ok = (row.ratio - Vec3::ONE).abs().max_element() as f64 <= ratio_bar;
        let z_ok = row.z_max <= 6.0;
        // And no self-intersection beyond s = 1's (which is 0).
        let offsets_ok = row.self_hits <= base_self_hits;
        if held && !(ratio_ok && z_ok && offsets_ok) {
            failures.push(format!(
                "s = {s:e}: mean ratio {} (bar ±{ratio_bar:.4}), max |z| {:.1} (bar 6), self-hits {:.4} \
                 (s = 1: {base_self_hits:.4})",
                row.ratio, row.z_max, row.self_hits
            ));
            let stem = format!("stability_scale_{s:e}");
            candidate.mean.write_exr(&dir.join(format!("{stem}.exr")));
            c.z_image.write_exr(&dir.join(format!("{stem}_z.exr")));
        }
        rows.push(row);
    }
    let text = format!(
        "Cornell box scaled by s, {SIZE}×{SIZE}, {PASSES} passes × 1 spp (random sampler, seed 7), 4 bounces, \
         compared with s = 1 (same seed)\n\n{}",
        table(&rows)
    );
    println!("{text}");
    std::fs::write(dir.join("stability_scale.md"), &text).expect("writing the table");
    if !failures.is_empty() {
        base.mean.write_exr(&dir.join("stability_scale_1.exr"));
        panic!("{}\n{text}\n(images in {})", failures.join("\n"), dir.display());
    }
}

/// The Cornell box with its sun and sky (and any emission) multiplied by `k`.
fn brighter_cbox(k: f32) -> Scene {
    let mut scene = furnace_scene::builtin::cornell_box().expect("the built-in Cornell box");
    for light in &mut scene.lights {
        match light {
            furnace_scene::Light::Sun(sun) => sun.irradiance *= k,
            furnace_scene::Light::Sky(sky) => sky.radiance *= k,
            other => panic!("a light the test does not scale: {other:?}"),
        }
    }
    for m in &mut scene.materials {
        m.emissive *= k;
    }
    scene
}

/// Renders `scene` at 32×32, 8 Sobol samples per pixel, and writes the film through
/// `furnace_post::write_exr`; returns the film and the EXR's pixels as read back.
fn render_to_exr(scene: Scene, name: &str) -> (furnace_render::Film, Vec<Vec3>) {
    let settings = RenderSettings { width: 32, height: 32, ..Default::default() };
    let renderer = CpuRenderer::with_default_camera(scene, settings).expect("a progressive sampler");
    let mut film = renderer.new_film();
    renderer.render_into(&mut film, 0, 8).expect("render");
    let rgb = film.to_rgb_f32();
    let pixels: Vec<Vec3> = rgb.chunks_exact(3).map(Vec3::from_slice).collect();
    let path = output_dir().join(format!("stability_radiance_{name}.exr"));
    let meta = furnace_post::Metadata { rejected_samples: Some(film.rejected()), ..Default::default() };
    furnace_post::write_exr(&path, 32, 32, &pixels, &meta).expect("writing the EXR");
    let (w, h, back, back_meta) = furnace_post::read_exr(&path).expect("reading the EXR back");
    assert_eq!((w, h, back_meta.rejected_samples), (32, 32, Some(film.rejected())));
    (film, back)
}

/// A sun (and sky) of extreme radiance: the film and the EXR stay finite and scale exactly.
///
/// * k = 2²⁰ (≈ 1.05e6), 2⁶⁴ (≈ 1.8e19) and 2¹⁰⁰ (≈ 1.3e30): every f32 product
///   of the path scales by a power of two exactly, so each pixel must be **bit-for-bit** k× the
///   k = 1 pixel (f64 sums of f32 samples scale exactly too), in the film and in the EXR read
///   back (32-bit float channels: `furnace_post::write_exr` writes f32, never f16, so nothing
///   saturates at f16's 65504).
/// * k = 1e6 (not a power of two): every pixel within 1e-5 relative of k× (a few f32 roundings
///   of 6e-8 per path vertex).
/// * k = `f32::MAX` (the sun at 3.4e38 × its colour): a sample whose radiance
///   overflows f32 becomes +∞, which the film rejects and counts (`Film::rejected`, written to
///   the EXR's `furnace.rejectedSamples`, reported by `furnace render` as a warning); what it
///   accepts stays finite, and so does the EXR. The rejected fraction is printed: that is the
///   edge (per-sample radiance must stay below 3.4e38; measured: 1248 of 8192 samples
///   rejected, the image mean 0.94 of k× the k = 1 mean).
#[test]
fn extreme_radiance_stays_finite_and_scales_exactly() {
    let (base, base_exr) = render_to_exr(brighter_cbox(1.0), "1");
    assert_eq!(base.rejected(), 0);
    let mut text = String::from(
        "| sun × k | rejected samples | max pixel | mean pixel / k ÷ mean at k = 1 |\n|---|---|---|---|\n",
    );
    let mut failures = vec![];
    let base_mean = base_exr.iter().map(|p| p.as_dvec3()).sum::<glam::DVec3>();
    for (name, k, exact) in [
        ("2^20", 2f32.powi(20), true),
        ("2^64", 2f32.powi(64), true),
        ("1e6", 1e6, false),
        ("2^100", 2f32.powi(100), true),
        ("f32::MAX", f32::MAX, false),
    ] {
        let (film, exr) = render_to_exr(brighter_cbox(k), name);
        // Up to 2^100 no sample overflows; at f32::MAX some must (the edge).
        if (film.rejected() == 0) != (k < f32::MAX) {
            failures.push(format!("k = {name}: {} samples rejected", film.rejected()));
        }
        let max = exr.iter().map(|p| p.max_element()).fold(0.0f32, f32::max);
        let mean = exr.iter().map(|p| p.as_dvec3()).sum::<glam::DVec3>();
        let _ = writeln!(
            text,
            "| {name} | {} of {} | {max:e} | {:.7} |",
            film.rejected(),
            32 * 32 * 8,
            (mean / f64::from(k) / base_mean).max_element()
        );
        if !exr.iter().all(|p| p.is_finite()) {
            failures.push(format!("k = {name}: non-finite pixel in the EXR"));
        }
        // The EXR holds the film's f32 means bit for bit.
        if exr
            .iter()
            .flat_map(|p| p.to_array())
            .map(f32::to_bits)
            .ne(film.to_rgb_f32().into_iter().map(f32::to_bits))
        {
            failures.push(format!("k = {name}: the EXR read back differs from the film"));
        }
        for (i, (p, b)) in exr.iter().zip(&base_exr).enumerate() {
            let want = *b * k;
            let ok = if exact {
                p.to_array().map(f32::to_bits) == want.to_array().map(f32::to_bits)
            } else if film.rejected() == 0 {
                // 1e-5 relative: see the doc comment.
                ((*p - want).abs().cmple(want.abs() * 1e-5)).all()
            } else {
                true
            };
            if !ok {
                failures.push(format!("k = {name}: pixel {i} = {p}, expected {want}"));
                break;
            }
        }
    }
    println!("{text}");
    std::fs::write(output_dir().join("stability_radiance.md"), &text).expect("writing the table");
    assert!(failures.is_empty(), "{failures:#?}\n{text}\n(EXRs in {})", output_dir().display());
}

/// Bad geometry given to the renderer directly (the loader rejects NaN positions and drops
/// zero-area triangles, `furnace-scene`'s `tests/bad_geometry.rs`; a program that builds a
/// [`Scene`] itself can still pass them): the Cornell box plus
///
/// * 300 zero-area triangles (points, repeated vertices, collinear vertices across the room)
///   and 300 triangles with a NaN or infinite vertex: the image is **bit-identical** to the
///   clean box's (they are skipped by the BVH build and never hit);
/// * a huge triangle (coordinates ±1e30) and one spanning ±`f32::MAX`, behind the camera:
///   the render finishes with no NaN/∞ sample rejected and a finite image (what reaches them is
///   reported in the table: f32 ray tracing loses such hits, which the loader warns about).
#[test]
fn bad_geometry_renders_without_nan_or_panic() {
    let settings = RenderSettings { width: 32, height: 32, ..Default::default() };
    let render = |scene: Scene| {
        let renderer = CpuRenderer::with_default_camera(scene, settings).expect("a progressive sampler");
        let mut film = renderer.new_film();
        renderer.render_into(&mut film, 0, 4).expect("render");
        film
    };
    let clean_scene = furnace_scene::builtin::cornell_box().expect("the built-in Cornell box");
    let clean = render(clean_scene.clone());

    let mut scene = clean_scene.clone();
    let g = &mut scene.geometry;
    let material = g.triangle_materials[0];
    let normal = g.normals[0];
    let push = |g: &mut furnace_scene::Geometry, v: [Vec3; 3]| {
        let base = g.positions.len() as u32;
        g.positions.extend(v);
        g.normals.extend([normal; 3]);
        g.triangles.push([base, base + 1, base + 2]);
        g.triangle_materials.push(material);
    };
    for k in 0..100 {
        let t = k as f32 / 100.0;
        let p = Vec3::new(2.0 * t - 1.0, 2.0 * t, 0.3 - 0.6 * t);
        push(g, [p; 3]); // a point
        push(g, [p, p + Vec3::X * 0.5, p]); // a repeated vertex
        push(g, [p, p + Vec3::new(0.2, 0.1, 0.3), p + Vec3::new(0.4, 0.2, 0.6)]); // collinear
        let bad = [
            Vec3::new(f32::NAN, 0.0, 0.0),
            Vec3::splat(f32::INFINITY),
            Vec3::new(0.0, f32::NEG_INFINITY, 1.0),
        ];
        push(g, [p, bad[k % 3], p + Vec3::Y * 0.3]);
        push(g, [bad[k % 3], bad[(k + 1) % 3], p]);
        push(g, [Vec3::NAN; 3]);
    }
    let degenerate = render(scene);
    assert_eq!(degenerate.rejected(), 0);
    assert!(
        degenerate
            .sums()
            .iter()
            .zip(clean.sums())
            .all(|(a, b)| a.to_array().map(f64::to_bits) == b.to_array().map(f64::to_bits)),
        "600 zero-area and non-finite triangles changed the image"
    );

    let mut text = String::from(
        "| added behind the camera | rejected samples | image mean R, G, B (clean box: {clean}) |\n|---|---|---|\n",
    );
    let clean_mean = clean.sums().iter().sum::<glam::DVec3>();
    text = text.replace("{clean}", &format!("{:.4}", clean_mean / clean.counts().iter().sum::<u64>() as f64));
    for (name, r) in [("triangle of ±1e30", 1e30f32), ("triangle of ±f32::MAX", f32::MAX)] {
        let mut scene = clean_scene.clone();
        let eye = scene.default_camera().world_from_camera.translation;
        // A plane facing the box, behind the camera (beyond it on +z, the camera looks to −z).
        let z = eye.z + 10.0;
        push(&mut scene.geometry, [Vec3::new(-r, -r, z), Vec3::new(r, -r, z), Vec3::new(0.0, r, z)]);
        let film = render(scene);
        let mean = film.sums().iter().sum::<glam::DVec3>() / film.counts().iter().sum::<u64>() as f64;
        let _ = writeln!(text, "| {name} | {} | {:.4} |", film.rejected(), mean);
        assert_eq!(film.rejected(), 0, "{name}: non-finite samples\n{text}");
        assert!(film.to_rgb_f32().iter().all(|v| v.is_finite()), "{name}\n{text}");
    }
    println!("{text}");
}
