//! Chi-square tests of the warps through the public API: each hemisphere warp against its own
//! pdf, the concentric disk lifted to the hemisphere by Malley's method, the uniform cone, and
//! the uniform triangle seen from a point (its area pdf turned into solid angle, as next-event
//! estimation of an emissive triangle does), and the spherical triangle (uniform in solid angle)
//! of a moderate and of a large, close triangle.
//!
//! Every test draws 10⁶ samples from a fixed seed, at a family-wise significance of 1% with
//! the Šidák correction over the [`TESTS`] tests of this file. On failure the report is printed
//! and the tables are written to `target/test-output/chi2/<name>.{txt,csv,ppm}`.

use furnace_sampling::warp::{
    concentric_disk_pdf, cosine_hemisphere_pdf, spherical_triangle_solid_angle, square_to_concentric_disk,
    square_to_cosine_hemisphere, square_to_spherical_triangle, square_to_uniform_cone,
    square_to_uniform_hemisphere, square_to_uniform_triangle, uniform_cone_pdf, uniform_hemisphere_pdf,
};
use furnace_tests::chi2::{ChiSquareResult, ChiSquareTest};
use glam::{Vec2, Vec3};
use std::path::PathBuf;

/// Number of chi-square tests in this file (the Šidák family).
const TESTS: usize = 8;

/// The harness as every test here uses it; only the seed differs.
fn harness(seed: u32) -> ChiSquareTest {
    ChiSquareTest {
        sample_count: 1_000_000,
        significance: 0.01,
        test_count: TESTS,
        seed,
        ..ChiSquareTest::default()
    }
}

/// `target/test-output/chi2` of the workspace.
fn output_dir() -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().unwrap_or(&manifest).join("target/test-output/chi2")
}

/// Passes, or writes the tables and fails with the report.
fn check(name: &str, result: &ChiSquareResult) {
    result.assert_passed(name, &output_dir());
}

/// Malley's method: a point of the unit disk lifted to the hemisphere, `z = √(1 − x² − y²)`.
fn lift(p: Vec2) -> Vec3 {
    Vec3::new(p.x, p.y, (1.0 - p.length_squared()).max(0.0).sqrt())
}

#[test]
fn chi2_uniform_hemisphere() {
    let result = harness(11).run(|u, _| Some(square_to_uniform_hemisphere(u)), uniform_hemisphere_pdf);
    check("uniform_hemisphere", &result);
}

#[test]
fn chi2_cosine_hemisphere() {
    let result = harness(12).run(|u, _| Some(square_to_cosine_hemisphere(u)), cosine_hemisphere_pdf);
    check("cosine_hemisphere", &result);
}

/// A uniform disk lifted to the hemisphere is cosine-distributed (Malley), so the concentric
/// disk is tested against [`cosine_hemisphere_pdf`].
#[test]
fn chi2_concentric_disk_lifted_against_cosine_pdf() {
    let result = harness(13).run(|u, _| Some(lift(square_to_concentric_disk(u))), cosine_hemisphere_pdf);
    check("concentric_disk_malley", &result);
}

/// The same lifted samples against the disk's own area pdf, converted to solid angle: the
/// projection `ω ↦ (x, y)` has `dA = cos θ dω`, so `p_ω(ω) = p_A(x, y) · cos θ`. This checks
/// [`concentric_disk_pdf`] itself, not just the sampler.
#[test]
fn chi2_concentric_disk_lifted_against_disk_pdf() {
    let result = harness(14).run(
        |u, _| Some(lift(square_to_concentric_disk(u))),
        |w| {
            if w.z > 0.0 { concentric_disk_pdf(Vec2::new(w.x, w.y)) * w.z } else { 0.0 }
        },
    );
    check("concentric_disk_area_pdf", &result);
}

/// A 40° cone: uniform inside (`1/(2π(1 − cos 40°))`), nothing outside.
#[test]
fn chi2_uniform_cone() {
    let t = 1.0 - 40f32.to_radians().cos();
    let result = harness(15).run(
        |u, _| Some(square_to_uniform_cone(u, t)),
        |w| if 1.0 - w.z <= t { uniform_cone_pdf(t) } else { 0.0 },
    );
    check("uniform_cone", &result);
}

/// Points uniform on a triangle in the plane z = 1, seen from the origin: the direction
/// `w = p/|p|` has solid-angle pdf `|p|²/(A cos θ) = 1/(A w_z³)` inside the triangle's
/// projection (`|p| = 1/w_z` on that plane).
#[test]
fn chi2_uniform_triangle_seen_from_a_point() {
    let [a, b, c] = [Vec3::new(-0.5, -0.5, 1.0), Vec3::new(0.8, -0.3, 1.0), Vec3::new(0.0, 0.7, 1.0)];
    let area = 0.5 * (b - a).cross(c - a).length();
    let inside = |p: Vec3| {
        let edge = |o: Vec3, d: Vec3| (d - o).cross(p - o).z;
        edge(a, b) >= 0.0 && edge(b, c) >= 0.0 && edge(c, a) >= 0.0
    };
    let result = harness(16).run(
        |u, _| {
            let bary = square_to_uniform_triangle(u);
            Some(((1.0 - bary.x - bary.y) * a + bary.x * b + bary.y * c).normalize())
        },
        |w| if w.z > 0.0 && inside(w / w.z) { 1.0 / (area * w.z * w.z * w.z) } else { 0.0 },
    );
    check("uniform_triangle", &result);
}

/// Directions uniform in the solid angle of the triangle `v` (in a plane `z = const > 0`) seen
/// from the origin, against `1/Ω` inside its projection. The barycentrics returned with each
/// direction must name the point the direction reaches (to 1e-4 of the triangle's size); the
/// direction tested is that point's, as a light sample uses it.
fn spherical_triangle_case(v: [Vec3; 3], seed: u32) -> ChiSquareResult {
    let [a, b, c] = v;
    let omega = spherical_triangle_solid_angle(a, b, c);
    let size = (b - a).length();
    // The triangle's edges cut cells in slivers that 5 quadrature points per axis can miss.
    let harness = |seed| ChiSquareTest { quadrature_order: 12, ..harness(seed) };
    // Inside, with a rounding slack: samples whose direction rounds just past an edge are
    // clamped onto it (about 1 in 10⁵), and must not count as outside.
    let slack = -1e-5 * size * size;
    let inside = |p: Vec3| {
        let edge = |o: Vec3, d: Vec3| (d - o).cross(p - o).z;
        edge(a, b) >= slack && edge(b, c) >= slack && edge(c, a) >= slack
    };
    harness(seed).run(
        |u, _| {
            let (w, bary) = square_to_spherical_triangle(u, a, b, c, omega)?;
            let p = (1.0 - bary.x - bary.y) * a + bary.x * b + bary.y * c;
            let along = w * (p.z / w.z);
            assert!(
                (p - along).length() <= 1e-4 * size,
                "u = {u:?}: barycentrics {bary:?} reach {p:?}, w reaches {along:?}"
            );
            Some(p.normalize())
        },
        |w| if w.z > 0.0 && inside(w * (a.z / w.z)) { 1.0 / omega } else { 0.0 },
    )
}

/// A triangle of 0.60 sr (the one the area test above uses).
#[test]
fn chi2_spherical_triangle() {
    let v = [Vec3::new(-0.5, -0.5, 1.0), Vec3::new(0.8, -0.3, 1.0), Vec3::new(0.0, 0.7, 1.0)];
    check("spherical_triangle", &spherical_triangle_case(v, 17));
}

/// A large triangle close to the point (4.46 sr of the hemisphere's 2π), where area sampling's
/// solid-angle pdf varies by 350× over it (as 1/cos³) and solid-angle sampling matters most.
#[test]
fn chi2_spherical_triangle_large_and_close() {
    let v = [Vec3::new(-1.5, -1.5, 0.3), Vec3::new(1.5, -1.5, 0.3), Vec3::new(0.0, 1.5, 0.3)];
    check("spherical_triangle_close", &spherical_triangle_case(v, 18));
}
