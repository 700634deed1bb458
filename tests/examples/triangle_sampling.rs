//! Which way to sample an emissive triangle for next-event estimation: uniformly by **area**
//! (what furnace does) or uniformly by **solid angle** (the spherical triangle, Arvo 1995, in
//! the form of pbrt-v4's `SampleSphericalTriangle`)? Measured here by the variance of the
//! one-sample estimate of the irradiance `E = L ∫ cos θ dω` a Lambert point receives from one
//! triangle, for geometries from "small and far" to "large and close", and by the time per
//! sample of each method.
//!
//! ```sh
//! cargo run --release -p furnace-tests --example triangle_sampling
//! ```
//!
//! Both estimators are unbiased; their means are printed against a 1024² midpoint quadrature of
//! the same integral (the area form) as a check. The relative standard deviation is per sample
//! (independent uniform samples; a stratified sampler lowers both).

use furnace_sampling::warp::square_to_uniform_triangle;
use furnace_tests::Rng;
use glam::{DVec3, Vec2, Vec3};
use std::f32::consts::PI;
use std::time::Instant;

/// A direction uniform in the solid angle the triangle `v` subtends at `p`, and that solid
/// angle (pbrt-v4, `SampleSphericalTriangle`); `None` for a degenerate one.
fn sample_spherical_triangle(v: [Vec3; 3], p: Vec3, u: Vec2) -> Option<(Vec3, f32)> {
    let (a, b, c) = ((v[0] - p).normalize(), (v[1] - p).normalize(), (v[2] - p).normalize());
    let (n_ab, n_bc, n_ca) = (a.cross(b), b.cross(c), c.cross(a));
    if n_ab.length_squared() == 0.0 || n_bc.length_squared() == 0.0 || n_ca.length_squared() == 0.0 {
        return None;
    }
    let (n_ab, n_bc, n_ca) = (n_ab.normalize(), n_bc.normalize(), n_ca.normalize());
    let angle = |x: Vec3, y: Vec3| {
        // pbrt's AngleBetween: accurate for nearly (anti)parallel vectors.
        if x.dot(y) < 0.0 {
            PI - 2.0 * ((x + y).length() / 2.0).asin()
        } else {
            2.0 * ((y - x).length() / 2.0).asin()
        }
    };
    let alpha = angle(n_ab, -n_ca);
    let beta = angle(n_bc, -n_ab);
    let gamma = angle(n_ca, -n_bc);
    let a_pi = alpha + beta + gamma;
    let ap_pi = (1.0 - u.x) * PI + u.x * a_pi;
    let area = a_pi - PI;
    if !(area > 0.0) {
        return None;
    }
    let (sin_alpha, cos_alpha) = alpha.sin_cos();
    let sin_phi = ap_pi.sin() * cos_alpha - ap_pi.cos() * sin_alpha;
    let cos_phi = ap_pi.cos() * cos_alpha + ap_pi.sin() * sin_alpha;
    let k1 = cos_phi + cos_alpha;
    let k2 = sin_phi - sin_alpha * a.dot(b);
    let cos_bp = ((k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha)
        / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha))
        .clamp(-1.0, 1.0);
    let sin_bp = (1.0 - cos_bp * cos_bp).max(0.0).sqrt();
    let cp = cos_bp * a + sin_bp * (c - c.dot(a) * a).normalize();
    let cos_theta = 1.0 - u.y * (1.0 - cp.dot(b));
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let w = cos_theta * b + sin_theta * (cp - cp.dot(b) * b).normalize();
    Some((w, area))
}

/// The ray `p + t·w` against the triangle: the hit point's distance, or `None`.
fn hits(v: [Vec3; 3], p: Vec3, w: Vec3) -> bool {
    let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
    let q = w.cross(e2);
    let det = e1.dot(q);
    let s = p - v[0];
    let (bu, bv) = (s.dot(q) / det, w.dot(s.cross(e1)) / det);
    bu >= -1e-4 && bv >= -1e-4 && bu + bv <= 1.0 + 1e-4
}

struct Stats {
    mean: f64,
    rel_std: f64,
    ns: f64,
}

fn run(n: usize, mut sample: impl FnMut(Vec2) -> f32) -> Stats {
    let mut rng = Rng(0x5eed_0001);
    let us: Vec<Vec2> = (0..n).map(|_| Vec2::new(rng.f32(), rng.f32())).collect();
    let start = Instant::now();
    let (mut s, mut s2) = (0.0f64, 0.0f64);
    for &u in &us {
        let x = f64::from(sample(u));
        s += x;
        s2 += x * x;
    }
    let ns = start.elapsed().as_secs_f64() * 1e9 / n as f64;
    let mean = s / n as f64;
    let var = (s2 / n as f64 - mean * mean).max(0.0);
    Stats { mean, rel_std: var.sqrt() / mean, ns }
}

/// `∫ cos θ_p cos θ_l / d² dA` by a midpoint rule over the triangle (f64).
fn quadrature(v: [Vec3; 3], p: Vec3, n: Vec3) -> f64 {
    let v = v.map(Vec3::as_dvec3);
    let (p, n) = (p.as_dvec3(), n.as_dvec3());
    let nl = (v[1] - v[0]).cross(v[2] - v[0]);
    let area = nl.length() / 2.0;
    let nl = nl.normalize();
    let k = 1024;
    let mut sum = 0.0;
    for i in 0..k {
        for j in 0..k - i {
            // Midpoints of the k² sub-triangles' upward half.
            let (b1, b2) =
                ((f64::from(i) + 1.0 / 3.0) / f64::from(k), (f64::from(j) + 1.0 / 3.0) / f64::from(k));
            let q = (1.0 - b1 - b2) * v[0] + b1 * v[1] + b2 * v[2];
            let d: DVec3 = q - p;
            let d2 = d.length_squared();
            let w = d / d2.sqrt();
            sum += (w.dot(n)).max(0.0) * (-w.dot(nl)).max(0.0) / d2;
        }
    }
    sum * area / (f64::from(k) * f64::from(k + 1) / 2.0)
}

fn main() {
    let p = Vec3::ZERO;
    let n = Vec3::Y;
    // Triangles facing down (−Y) above the point, from small and far to large and close.
    // Counter-clockwise seen from below: the front (the emitting side) faces −Y.
    let facing_down =
        |c: Vec3, s: f32| [c + Vec3::new(-s, 0.0, -s), c + Vec3::new(s, 0.0, -s), c + Vec3::new(0.0, 0.0, s)];
    let cases: Vec<(&str, [Vec3; 3])> = vec![
        ("small, far (side 0.1 at 2 m)", facing_down(Vec3::new(0.3, 2.0, 0.1), 0.05)),
        ("the cbox quad from the floor (0.47 m at 1.97 m)", facing_down(Vec3::new(0.0, 1.97, 0.0), 0.235)),
        ("the cbox quad seen 0.4 m below and 0.8 m aside", facing_down(Vec3::new(0.8, 0.4, 0.0), 0.235)),
        ("large, close (side 2 at 0.2 m)", facing_down(Vec3::new(0.0, 0.2, 0.0), 1.0)),
        ("large, very close (side 2 at 0.02 m)", facing_down(Vec3::new(0.0, 0.02, 0.0), 1.0)),
        ("grazing (1 m wide, 0.05 m above, 1 m away)", facing_down(Vec3::new(1.5, 0.05, 0.0), 0.5)),
    ];
    const N: usize = 2_000_000;
    println!(
        "| geometry | quadrature | area: mean, rel. std, ns | solid angle: mean, rel. std, ns | variance ratio area/solid angle | time × variance ratio |"
    );
    println!("|---|---|---|---|---|---|");
    for (name, v) in cases {
        let nl = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
        let area = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length();
        let by_area = run(N, |u| {
            let b = square_to_uniform_triangle(u);
            let q = (1.0 - b.x - b.y) * v[0] + b.x * v[1] + b.y * v[2];
            let d = q - p;
            let d2 = d.length_squared();
            let w = d / d2.sqrt();
            w.dot(n).max(0.0) * (-w.dot(nl)).max(0.0) / d2 * area
        });
        // One-sided: a direction reaching the back of the triangle carries nothing.
        let by_angle = run(N, |u| match sample_spherical_triangle(v, p, u) {
            Some((w, omega)) if hits(v, p, w) && w.dot(nl) < 0.0 => w.dot(n).max(0.0) * omega,
            _ => 0.0,
        });
        let exact = quadrature(v, p, n);
        let ratio = (by_area.rel_std / by_angle.rel_std).powi(2);
        println!(
            "| {name} | {exact:.6} | {:.6}, {:.4}, {:.1} | {:.6}, {:.4}, {:.1} | {ratio:.3} | {:.3} |",
            by_area.mean,
            by_area.rel_std,
            by_area.ns,
            by_angle.mean,
            by_angle.rel_std,
            by_angle.ns,
            ratio * by_area.ns / by_angle.ns
        );
    }
}
