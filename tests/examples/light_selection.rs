//! Would a **light BVH** (pbrt-v4's `BVHLightSampler`, Conty Estevez & Kulla, "Importance
//! Sampling of Many Lights with Adaptive Tree Splitting", 2018) pay on the many-lights Cornell
//! box (`tests/data/references/lights/cbox_many_lights.gltf`: 64 emissive squares, 128
//! triangles, powers log-spaced over 100×), compared with furnace's power-proportional emitter
//! selection ([`furnace_scene::Emitters`]) and with uniform selection (Mitsuba's)?
//!
//! ```sh
//! cargo run --release -p furnace-tests --example light_selection
//! ```
//!
//! Options: `--size N` (64: N×N pixel-centre camera rays), `--strata K` (16: K×K stratified
//! area samples per emitter triangle).
//!
//! Method: the shading points are the first hits of the default camera's rays; each is a
//! Lambert surface (BRDF 1/π). The next-event estimator picks triangle `t` with probability
//! `p_t`, a point uniform on its area, and returns `g / p_t` with
//! `g = L · cos θ_x · cos θ_y / d² · V · area / π` (one-sided emitters, shadow ray through
//! furnace-accel as the CPU integrator casts it). Its variance is computed *exactly* for any
//! pmf from per-triangle moments `m_t = E[g]`, `s_t = E[g²]` (K² stratified samples, the same
//! for every strategy): `Var = Σ s_t / p_t − (Σ m_t)²`. Strategies:
//!
//! * (a) power: `luminance(L) · area / Σ`, exactly [`furnace_scene::Emitters::selection_pdf`];
//! * (b) uniform: `1 / 128`;
//! * (c) per-point importance, pbrt-v4's `LightBounds::Importance` with every triangle its own
//!   leaf, evaluated for all 128 (the best a light BVH with that importance can do: a real one
//!   merges bounds and is worse); (c′) the same with the receiver's cosine one-sided (pbrt
//!   takes `|cos|`, which a reflect-only surface wastes on lights behind it);
//! * (d) ideal: `p_t ∝ √s_t`, which minimises `Σ s_t / p_t` (the floor for any selection).
//!
//! Luminance stands in for RGB throughout. A second table puts the selection cost in context:
//! one exhaustive importance pass over 128 triangles against one alias-table sample (a BVH
//! evaluates two children per level, ~2·log₂ 128 = 14 importances per sample).

use furnace_accel::{BuildOptions, Bvh, offset_ray_origin_scaled, offset_scale_of_bounds};
use furnace_sampling::warp::square_to_uniform_triangle;
use furnace_scene::{Emitters, Scene, geometric_normal, luminance, triangle_area};
use furnace_tests::Rng;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::f32::consts::PI;
use std::hint::black_box;
use std::time::Instant;

/// pbrt-v4's `LightBounds` (src/pbrt/lights.h) for one emitter triangle, as
/// `DiffuseAreaLight::Bounds` (src/pbrt/lights.cpp) makes it: the triangle's AABB, its power,
/// its normal (`Triangle::NormalBounds`: a cone of `cosTheta = 1`), `cosTheta_e = cos(π/2)`.
#[derive(Clone, Copy)]
struct LightBounds {
    lo: Vec3,
    hi: Vec3,
    w: Vec3,
    phi: f32,
    cos_theta_o: f32,
    cos_theta_e: f32,
    two_sided: bool,
}

fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

impl LightBounds {
    /// pbrt-v4 `LightBounds::Importance(Point3f p, Normal3f n)` (src/pbrt/lights.cpp, commit
    /// 5f7a606 of github.com/mmp/pbrt-v4), line for line, in `f32` as pbrt's `Float`. Kept as
    /// written, including its `d2 = max(d2, |diagonal| / 2)` clamp (a length against a squared
    /// length) and `|wi · n|` for the receiver (pbrt's surfaces may transmit). `one_sided`:
    /// the receiver's cosine signed instead (`−wi · n`, light behind the surface's plane
    /// clamped to 0 by the final `max`), the variant (c′) for a reflect-only surface.
    fn importance(&self, p: Vec3, n: Vec3, one_sided: bool) -> f32 {
        let pc = (self.lo + self.hi) / 2.0;
        let d2 = p.distance_squared(pc).max((self.hi - self.lo).length() / 2.0);
        let cos_sub_clamped = |sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32| {
            if cos_a > cos_b { 1.0 } else { cos_a * cos_b + sin_a * sin_b }
        };
        let sin_sub_clamped = |sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32| {
            if cos_a > cos_b { 0.0 } else { sin_a * cos_b - cos_a * sin_b }
        };
        let wi = (p - pc).normalize();
        let mut cos_theta_w = self.w.dot(wi);
        if self.two_sided {
            cos_theta_w = cos_theta_w.abs();
        }
        let sin_theta_w = safe_sqrt(1.0 - cos_theta_w * cos_theta_w);
        // BoundSubtendedDirections (src/pbrt/util/vecmath.h): the cone of the bounds' sphere.
        let radius = (self.hi - pc).length();
        let cos_theta_b = if p.distance_squared(pc) < radius * radius {
            -1.0 // DirectionCone::EntireSphere
        } else {
            safe_sqrt(1.0 - radius * radius / p.distance_squared(pc))
        };
        let sin_theta_b = safe_sqrt(1.0 - cos_theta_b * cos_theta_b);
        let sin_theta_o = safe_sqrt(1.0 - self.cos_theta_o * self.cos_theta_o);
        let cos_theta_x = cos_sub_clamped(sin_theta_w, cos_theta_w, sin_theta_o, self.cos_theta_o);
        let sin_theta_x = sin_sub_clamped(sin_theta_w, cos_theta_w, sin_theta_o, self.cos_theta_o);
        let cos_theta_p = cos_sub_clamped(sin_theta_x, cos_theta_x, sin_theta_b, cos_theta_b);
        if cos_theta_p <= self.cos_theta_e {
            return 0.0;
        }
        let mut importance = self.phi * cos_theta_p / d2;
        if n != Vec3::ZERO {
            let cos_theta_i = if one_sided { -wi.dot(n) } else { wi.dot(n).abs() };
            let sin_theta_i = safe_sqrt(1.0 - cos_theta_i * cos_theta_i);
            importance *= cos_sub_clamped(sin_theta_i, cos_theta_i, sin_theta_b, cos_theta_b);
        }
        importance.max(0.0)
    }
}

/// One emitter triangle.
struct Light {
    v: [Vec3; 3],
    normal: Vec3,
    area: f32,
    /// Luminance of the emitted radiance.
    radiance: f32,
    /// Strategy (a)'s probability, from [`Emitters::selection_pdf`].
    power_pdf: f64,
    bounds: LightBounds,
}

/// A shading point: the offset origin shadow rays leave from, the hit point and its normal
/// (facing the camera ray).
#[derive(Clone, Copy)]
struct Point {
    leave: Vec3,
    position: Vec3,
    normal: Vec3,
}

/// Per strategy, at one point: the estimator's mean (over the triangles the pmf can pick) and
/// variance; and whether a triangle with `m_t > 0` had `p_t = 0` (biased).
#[derive(Clone, Copy, Default)]
struct Moments {
    mean: f64,
    variance: f64,
    biased: bool,
}

fn moments(m: &[f64], s: &[f64], p: impl Fn(usize) -> f64) -> Moments {
    let (mut mean, mut second, mut biased) = (0.0, 0.0, false);
    for t in 0..m.len() {
        if s[t] == 0.0 {
            continue;
        }
        let pt = p(t);
        if pt > 0.0 {
            mean += m[t];
            second += s[t] / pt;
        } else {
            biased = true;
        }
    }
    Moments { mean, variance: second - mean * mean, biased }
}

const STRATEGIES: [&str; 5] = [
    "(a) power (Emitters)",
    "(b) uniform (Mitsuba)",
    "(c) pbrt importance, exhaustive",
    "(c′) (c) with a one-sided receiver cosine",
    "(d) ideal p ∝ √s_t (floor)",
];

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let opt = |name: &str, default: u32| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .and_then(|s| s.parse().ok())
            .unwrap_or(default)
    };
    let (size, strata) = (opt("--size", 64), opt("--strata", 16));
    let path = furnace_tests::data::reference("lights/cbox_many_lights.gltf");
    let scene = Scene::load(&path).expect("the many-lights Cornell box");
    let g = &scene.geometry;
    let bvh = Bvh::from_indexed(&g.positions, &g.triangles, BuildOptions::default());
    let (lo, hi) = g.bounds();
    let offset_scale = offset_scale_of_bounds(lo, hi);
    let emitters = Emitters::new(&scene).expect("emitters");
    let lights: Vec<Light> = emitters
        .triangles()
        .iter()
        .map(|&t| {
            let t = t as usize;
            let v = g.triangle(t).expect("an emitter triangle");
            let material = scene.triangle_material(t);
            let area = triangle_area(v[0], v[1], v[2]);
            let normal = geometric_normal(v[0], v[1], v[2]);
            let radiance = luminance(scene.materials[material].emissive);
            let bounds = LightBounds {
                lo: v[0].min(v[1]).min(v[2]),
                hi: v[0].max(v[1]).max(v[2]),
                w: normal,
                phi: PI * area * radiance,
                cos_theta_o: 1.0,
                cos_theta_e: (PI / 2.0).cos(),
                two_sided: false,
            };
            let power_pdf = f64::from(emitters.selection_pdf(material, area));
            Light { v, normal, area, radiance, power_pdf, bounds }
        })
        .collect();
    let n_lights = lights.len();

    // Shading points: first hits of pixel-centre rays (misses and backs of one-sided surfaces
    // are skipped, as the integrator stops there).
    let camera = scene.default_camera();
    let points: Vec<Point> = (0..size * size)
        .filter_map(|i| {
            let (x, y) = (i % size, i / size);
            let ray = camera.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), size, size);
            let hit = bvh.closest_hit(ray.origin, ray.direction, f32::INFINITY)?;
            let t = hit.triangle as usize;
            let material = &scene.materials[scene.triangle_material(t)];
            let (b1, b2) = (hit.barycentrics.x, hit.barycentrics.y);
            let s =
                scene.surface_point(None, t, (b1, b2), material, &Default::default(), ray.direction, None)?;
            let leave = offset_ray_origin_scaled(s.position, s.geometric, offset_scale);
            Some(Point { leave, position: s.position, normal: s.geometric })
        })
        .collect();

    // K×K jittered strata of the unit square, mapped to every triangle the same way.
    let mut rng = Rng(0x11_6e75);
    let k = strata as f32;
    let us: Vec<Vec2> = (0..strata * strata)
        .map(|i| Vec2::new(((i % strata) as f32 + rng.f32()) / k, ((i / strata) as f32 + rng.f32()) / k))
        .collect();

    let start = Instant::now();
    // Per point: every strategy's moments.
    let results: Vec<[Moments; 5]> = points
        .par_iter()
        .map(|pt| {
            let (mut m, mut s) = (vec![0.0f64; n_lights], vec![0.0f64; n_lights]);
            for (t, l) in lights.iter().enumerate() {
                // Seen from the offset origin, as the CPU integrator does: points of the
                // emitter's own plane are strictly behind or in front.
                if !((l.v[0] - pt.leave).dot(l.normal) < 0.0) {
                    continue;
                }
                let (mut sum, mut sum2) = (0.0f64, 0.0f64);
                for &u in &us {
                    let b = square_to_uniform_triangle(u);
                    let y = (1.0 - b.x - b.y) * l.v[0] + b.x * l.v[1] + b.y * l.v[2];
                    let to_light = y - pt.leave;
                    let d2 = to_light.length_squared();
                    if !(d2 > 0.0) {
                        continue;
                    }
                    let d = d2.sqrt();
                    let wi = to_light / d;
                    let (cos_x, cos_y) = (wi.dot(pt.normal), -l.normal.dot(wi));
                    if !(cos_x > 0.0 && cos_y > 0.0)
                        || bvh.occluded(pt.leave, wi, d * (1.0 - furnace_render::SHADOW_EPSILON))
                    {
                        continue;
                    }
                    let g = f64::from(l.radiance) * f64::from(cos_x) * f64::from(cos_y) / f64::from(d2)
                        * f64::from(l.area)
                        / std::f64::consts::PI;
                    sum += g;
                    sum2 += g * g;
                }
                let n = us.len() as f64;
                (m[t], s[t]) = (sum / n, sum2 / n);
            }
            let importances = |one_sided: bool| -> Vec<f64> {
                let imp: Vec<f64> = lights
                    .iter()
                    .map(|l| f64::from(l.bounds.importance(pt.position, pt.normal, one_sided)))
                    .collect();
                let total: f64 = imp.iter().sum();
                imp.iter().map(|x| if total > 0.0 { x / total } else { 0.0 }).collect()
            };
            let (imp, imp_one_sided) = (importances(false), importances(true));
            let sqrt_total: f64 = s.iter().map(|x| x.sqrt()).sum();
            let uniform = 1.0 / n_lights as f64;
            [
                moments(&m, &s, |t| lights[t].power_pdf),
                moments(&m, &s, |_| uniform),
                moments(&m, &s, |t| imp[t]),
                moments(&m, &s, |t| imp_one_sided[t]),
                moments(&m, &s, |t| s[t].sqrt() / sqrt_total),
            ]
        })
        .collect();
    let seconds = start.elapsed().as_secs_f64();

    println!(
        "{} shading points ({size}² pixel centres), {n_lights} emitter triangles, {} area samples each \
         ({:.1} s)\n",
        points.len(),
        us.len(),
        seconds
    );
    println!(
        "| strategy | image-mean variance / (a) | mean rel. variance (var/mean²) | its ratio to (a) | median rel. variance | median per-point var / (a) | points better than (a) | image-mean estimate | biased points |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let lit: Vec<&[Moments; 5]> = results.iter().filter(|r| r[0].mean > 0.0).collect();
    let mean_var = |i: usize| results.iter().map(|r| r[i].variance).sum::<f64>() / results.len() as f64;
    let mean_rel = |i: usize| {
        lit.iter().map(|r| r[i].variance / (r[0].mean * r[0].mean)).sum::<f64>() / lit.len() as f64
    };
    for (i, name) in STRATEGIES.iter().enumerate() {
        let mut ratios: Vec<f64> = lit.iter().map(|r| r[i].variance / r[0].variance).collect();
        ratios.sort_by(f64::total_cmp);
        let median = ratios[ratios.len() / 2];
        // The mean relative variance is dominated by a few dark points (the sphere's underside):
        // the median says what a typical pixel sees.
        let mut rel: Vec<f64> = lit.iter().map(|r| r[i].variance / (r[0].mean * r[0].mean)).collect();
        rel.sort_by(f64::total_cmp);
        let median_rel = rel[rel.len() / 2];
        let better = lit.iter().filter(|r| r[i].variance < r[0].variance).count();
        let estimate = results.iter().map(|r| r[i].mean).sum::<f64>() / results.len() as f64;
        let biased = results.iter().filter(|r| r[i].biased).count();
        println!(
            "| {name} | {:.3} | {:.3} | {:.3} | {median_rel:.3} | {median:.3} | {:.1} % | {estimate:.6} | {biased} |",
            mean_var(i) / mean_var(0),
            mean_rel(i),
            mean_rel(i) / mean_rel(0),
            100.0 * better as f64 / lit.len() as f64
        );
    }
    // Sanity: the floor is below every strategy at every point (up to rounding).
    let floor_violations = results
        .iter()
        .filter(|r| (0..4).any(|i| r[4].variance > r[i].variance * (1.0 + 1e-9) + 1e-300))
        .count();
    println!(
        "\n{} of {} points lit (mean > 0); points where (d) exceeds another strategy: {floor_violations}\n",
        lit.len(),
        results.len()
    );

    // Selection cost. Exhaustive: 128 importances, their sum and a linear CDF walk with one
    // uniform (what sampling from (c) takes); alias: one `Emitters::select`.
    let reps = 200usize;
    let mut rng = Rng(0xa11a5);
    let coins: Vec<f32> = (0..points.len()).map(|_| rng.f32()).collect();
    let mut imp = vec![0.0f32; n_lights];
    let start = Instant::now();
    for _ in 0..reps {
        for (pt, &coin) in points.iter().zip(&coins) {
            let (p, n) = black_box((pt.position, pt.normal));
            let mut total = 0.0f32;
            for (i, l) in lights.iter().enumerate() {
                imp[i] = l.bounds.importance(p, n, false);
                total += imp[i];
            }
            let mut target = coin * total;
            let mut chosen = n_lights - 1;
            for (i, &w) in imp.iter().enumerate() {
                if target < w {
                    chosen = i;
                    break;
                }
                target -= w;
            }
            black_box(chosen);
        }
    }
    let exhaustive_ns = start.elapsed().as_secs_f64() * 1e9 / (reps * points.len()) as f64;
    let draws: Vec<(u32, f32)> = (0..1 << 16).map(|_| (rng.u32(), rng.f32())).collect();
    let alias_reps = 200usize;
    let start = Instant::now();
    for _ in 0..alias_reps {
        for &(bits, coin) in &draws {
            black_box(emitters.select(black_box(bits), black_box(coin)));
        }
    }
    let alias_ns = start.elapsed().as_secs_f64() * 1e9 / (alias_reps * draws.len()) as f64;
    let per_importance = exhaustive_ns / n_lights as f64;
    let levels = (n_lights as f64).log2().ceil();
    println!("| selection | ns per sample | × alias |");
    println!("|---|---|---|");
    println!("| alias table (`Emitters::select`) | {alias_ns:.1} | 1 |");
    println!(
        "| exhaustive importance over {n_lights} + CDF walk | {exhaustive_ns:.1} | {:.0} |",
        exhaustive_ns / alias_ns
    );
    println!(
        "| light BVH estimate: 2·{levels:.0} importances ({per_importance:.1} ns each) | {:.1} | {:.0} |",
        2.0 * levels * per_importance,
        2.0 * levels * per_importance / alias_ns
    );
}
