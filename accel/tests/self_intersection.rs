//! Secondary rays leaving a surface must not hit the surface they leave.
//!
//! At scene scales 1e-3 … 1e5, rays start at random points on random triangles of a scene
//! (a sphere and a random soup; hit points interpolated from barycentrics in `f32`, as an
//! integrator computes them), leave at 89.9° from the normal (grazing), on the front or the
//! back side, and are traced with `closest_hit`. We count rays whose closest hit is their own
//! triangle, for origins moved by `offset_ray_origin` (Wächter & Binder) and by the thesis's fixed
//! `p + 1e-3 · n`. The table goes to `target/test-output/accel/self_intersection.md`.

use crate::common;

use common::*;
use furnace_accel::{Bvh, offset_ray_origin};
use glam::Vec3;
use std::fmt::Write as _;

const RAYS_PER_SCALE: usize = 20_000;
const SCALES: [f32; 9] = [1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3, 1e4, 1e5];

struct Count {
    robust: usize,
    epsilon: usize,
}

fn count_self_hits(scale: f32, seed: u64) -> Count {
    let mut tris = sphere(3);
    tris.extend(random_soup(300, 0.3, seed));
    // Off-centre, so coordinates are not symmetric about 0.
    let tris: Vec<Tri> = tris.iter().map(|t| t.map(|v| (v + Vec3::new(0.3, 0.7, 1.1)) * scale)).collect();
    let bvh = Bvh::build(&tris);
    let mut rng = Rng::new(seed);
    let mut c = Count { robust: 0, epsilon: 0 };
    let cos = 89.9f32.to_radians().cos();
    let sin = 89.9f32.to_radians().sin();
    for _ in 0..RAYS_PER_SCALE {
        let id = rng.index(tris.len());
        let [a, b, cc] = tris[id];
        let (mut u, mut v) = (rng.f32(), rng.f32());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let p = a * (1.0 - u - v) + b * u + cc * v;
        let mut n = (b - a).cross(cc - a).normalize();
        if rng.f32() < 0.5 {
            n = -n; // leave through the back
        }
        // A tangent at a random azimuth.
        let r = rng.unit_vector();
        let t = (r - n * r.dot(n)).normalize();
        let dir = n * cos + t * sin;
        let own = |o: Vec3| bvh.closest_hit(o, dir, f32::INFINITY).is_some_and(|h| h.triangle as usize == id);
        c.robust += own(offset_ray_origin(p, n)) as usize;
        c.epsilon += own(p + 1e-3 * n) as usize;
    }
    c
}

#[test]
fn robust_offsets_never_self_intersect_at_any_scale() {
    let mut table = format!(
        "Self-hits out of {RAYS_PER_SCALE} rays at 89.9° from the normal (half front, half back side)\n\n| scene scale | offset_ray_origin | p + 1e-3·n |\n|---|---|---|\n"
    );
    let mut robust_total = 0;
    let mut eps_failing_scales = Vec::new();
    for (i, &s) in SCALES.iter().enumerate() {
        let c = count_self_hits(s, 100 + i as u64);
        writeln!(table, "| {s:e} | {} | {} |", c.robust, c.epsilon).unwrap();
        robust_total += c.robust;
        if c.epsilon > 0 {
            eps_failing_scales.push(s);
        }
    }
    let path = output_dir().join("self_intersection.md");
    std::fs::write(&path, &table).unwrap();
    println!("{table}\n(written to {})", path.display());
    assert_eq!(robust_total, 0, "robust offsets self-intersected:\n{table}");
    // The fixed epsilon is expected to fail once ULPs of the coordinates exceed 1e-3.
    assert!(
        !eps_failing_scales.is_empty(),
        "expected the fixed 1e-3 epsilon to self-intersect at some scale:\n{table}"
    );
}
