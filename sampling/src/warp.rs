//! Warps from the unit square `[0, 1)²` to the disk and the hemisphere, each with its pdf and
//! its inverse.
//!
//! | warp | sample | pdf (measure) | inverse |
//! |---|---|---|---|
//! | concentric disk | [`square_to_concentric_disk`] | [`concentric_disk_pdf`] (area) | [`concentric_disk_to_square`] |
//! | uniform hemisphere | [`square_to_uniform_hemisphere`] | [`uniform_hemisphere_pdf`] (solid angle) | [`uniform_hemisphere_to_square`] |
//! | cosine hemisphere | [`square_to_cosine_hemisphere`] | [`cosine_hemisphere_pdf`] (solid angle) | [`cosine_hemisphere_to_square`] |
//! | uniform triangle | [`square_to_uniform_triangle`] (barycentrics) | `1 / area` (area) | — |
//! | uniform cone | [`square_to_uniform_cone`] | [`uniform_cone_pdf`] (solid angle) | — |
//! | spherical triangle | [`square_to_spherical_triangle`] (direction, barycentrics) | `1 / ` [`spherical_triangle_solid_angle`] (solid angle) | — |
//!
//! Directions are in the local shading frame: the hemisphere is `z ≥ 0` and `θ` is measured from
//! `+z`, so `cos θ = w.z`.
//!
//! ## Sources
//!
//! * The concentric map is Shirley & Chiu, "A Low Distortion Map Between Disk and Square",
//!   *Journal of Graphics Tools* 2(3), 1997, in the form of pbrt-v4's
//!   `SampleUniformDiskConcentric` (Pharr, Jakob & Humphreys, *Physically Based Rendering*,
//!   4th ed., §A.5.1). The inverse is derived here from the forward map (see
//!   [`concentric_disk_to_square`]).
//! * The uniform hemisphere follows pbrt-v4's `SampleUniformHemisphere` /
//!   `InvertUniformHemisphereSample` exactly in its convention (`z = u.x`, `φ = 2π·u.y`).
//! * The cosine hemisphere is Malley's method — a uniform disk point lifted to the hemisphere,
//!   `z = √(1 − x² − y²)` — with the disk sampled in polar coordinates, as in the thesis
//!   (`φ = 2π·u.x`, `sin θ = √u.y`). *Deviation from pbrt-v4*, whose `SampleCosineHemisphere`
//!   lifts the concentric disk instead; both have the same pdf `cos θ / π`.
//!
//! ## Robustness
//!
//! For every input in `[0, 1)²` — including `0` and the largest `f32` below one, `1 − 2⁻²⁴` —
//! the sample functions return finite points; hemisphere directions have unit length to within
//! a few ulp (`|‖w‖ − 1| < 1e-6`). Every `sqrt` argument is clamped at `0`. Azimuths are
//! computed from a signed turn `t ∈ [−½, ½)` (see `sin_cos_turns`), so that `u` just below one
//! gives `sin φ < 0` and is not rounded past `2π` onto the start of the circle.
//!
//! The inverses return points in `[0, 1)²` (results that round to `1.0` are clamped to
//! `1 − 2⁻²⁴`, never wrapped to `0`), so `invert(sample(u)) == u` to within `1e-5` for all `u`
//! in `[0, 1)²`, except where the map is not injective: at a pole (`w = ±z`, reached only by
//! `u.y = 0` of the cosine warp) or at the disk centre (`u = (½, ½)`) the azimuth is lost, and
//! the inverse returns `0` for it (disk: the centre `(½, ½)`). Close to a pole the azimuth is
//! ill-conditioned: perturbing `w` by `δ` moves it by about `δ / (2π sin θ)`.

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, TAU};

/// The largest `f32` below one, `1 − 2⁻²⁴`: inverses clamp their results to it.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// `1 / (2π)`.
const INV_TAU: f32 = 0.5 * FRAC_1_PI;

/// Slack on `‖p‖² ≤ 1` in [`concentric_disk_pdf`]: points that the sampler puts on the rim may
/// round a few ulp outside it.
const DISK_RIM_SLACK: f32 = 1e-6;

/// `(sin φ, cos φ)` for the azimuth `φ = 2π·t` of a turn fraction `t ∈ [0, 1)`.
///
/// For `t ≥ ½` the angle is formed as `2π·(t − 1)` — the subtraction is exact in `f32`
/// (Sterbenz) — so `φ ∈ [−π, π)`. Forming `2π·t` directly could round to `2π` or above for
/// `t = 1 − 2⁻²⁴`, making `sin φ ≥ 0`, and the inverse would then return `≈ 0` instead of `≈ 1`.
fn sin_cos_turns(t: f32) -> (f32, f32) {
    let signed = if t < 0.5 { t } else { t - 1.0 };
    (TAU * signed).sin_cos()
}

/// The inverse of [`sin_cos_turns`]: `t = atan2(y, x) / (2π)`, mapped into `[0, 1)`.
///
/// `atan2` gives `(−π, π]`; negative angles are moved up by one turn. A result that rounds to
/// `1.0` (angles within half an ulp below `2π`) is clamped to `1 − 2⁻²⁴`, not wrapped to `0`.
/// `x = y = 0` (no azimuth) and NaN give `0`.
fn turns_from_xy(y: f32, x: f32) -> f32 {
    let t = y.atan2(x) * INV_TAU; // (−½, ½]
    if t < 0.0 {
        (t + 1.0).min(ONE_MINUS_EPSILON)
    } else if t > 0.0 {
        t
    } else {
        0.0 // +0, −0 and NaN
    }
}

/// Clamps a coordinate returned by an inverse into `[0, 1)`; NaN gives `0`.
fn clamp_unit(v: f32) -> f32 {
    if v > 0.0 { v.min(ONE_MINUS_EPSILON) } else { 0.0 }
}

/// Maps the unit square to the unit disk with Shirley & Chiu's concentric map.
///
/// Measure: the result is uniform in **area** on the disk `‖p‖ ≤ 1`; pdf `1/π`
/// ([`concentric_disk_pdf`]). The map preserves area fractions, so strata stay compact.
///
/// With `s = 2u − 1 ∈ [−1, 1)²` (pbrt-v4, `SampleUniformDiskConcentric`):
///
/// * `s = 0` → `p = 0`;
/// * `|s.x| > |s.y|` → `r = s.x`, `θ = (π/4)·(s.y / s.x)`;
/// * otherwise → `r = s.y`, `θ = π/2 − (π/4)·(s.x / s.y)`;
///
/// and `p = r·(cos θ, sin θ)` (a negative `r` puts the point in the opposite wedge).
///
/// Robustness: both divisions have a non-zero denominator once `s = 0` is excluded, and both
/// ratios lie in `[−1, 1]`; the result is finite for every finite input and `‖p‖ ≤ 1` to within
/// rounding for inputs in `[0, 1)²`.
pub fn square_to_concentric_disk(u: Vec2) -> Vec2 {
    let s = 2.0 * u - Vec2::ONE;
    if s.x == 0.0 && s.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if s.x.abs() > s.y.abs() {
        (s.x, FRAC_PI_4 * (s.y / s.x))
    } else {
        (s.y, FRAC_PI_2 - FRAC_PI_4 * (s.x / s.y))
    };
    let (sin, cos) = theta.sin_cos();
    r * Vec2::new(cos, sin)
}

/// The density of [`square_to_concentric_disk`] with respect to **area**: `1/π` inside the unit
/// disk, `0` outside.
///
/// "Inside" is `‖p‖² ≤ 1 + 10⁻⁶`: the slack absorbs the rounding of points that the sampler
/// puts on the rim. Non-finite points have density `0`.
pub fn concentric_disk_pdf(p: Vec2) -> f32 {
    if p.length_squared() <= 1.0 + DISK_RIM_SLACK { FRAC_1_PI } else { 0.0 }
}

/// The inverse of [`square_to_concentric_disk`]: maps a point of the unit disk back to `[0, 1)²`.
///
/// Derived from the forward map (*not* a transcription of pbrt-v4's
/// `InvertUniformDiskConcentricSample`): in the wedges `|p.x| ≥ |p.y|` the forward map has
/// `p.y / p.x = tan θ` with `θ = (π/4)·(s.y / s.x)` and `|s.x| = ‖p‖`, so
///
/// * `|p.x| ≥ |p.y|` → `s.x = ±‖p‖` (sign of `p.x`), `s.y = s.x · atan(p.y / p.x) / (π/4)`;
/// * otherwise → `s.y = ±‖p‖` (sign of `p.y`), `s.x = s.y · atan(p.x / p.y) / (π/4)`,
///
/// and `u = (s + 1) / 2`. Using `atan` of the in-wedge ratio rather than `atan2` avoids
/// cancellation when subtracting wedge offsets.
///
/// Robustness: `‖p‖` is clamped to `1`, the centre maps to `(½, ½)`, and the result is clamped
/// into `[0, 1)²`, so the output is always a valid sampler input (the rim point `(1, 0)` maps
/// to `(1 − 2⁻²⁴, ½)`). For `u ∈ [0, 1)²`, `invert(sample(u)) == u` to within `1e-5`.
pub fn concentric_disk_to_square(p: Vec2) -> Vec2 {
    let r = p.length().min(1.0);
    if r == 0.0 || !r.is_finite() {
        return Vec2::splat(0.5);
    }
    let s = if p.x.abs() >= p.y.abs() {
        let sx = r.copysign(p.x);
        Vec2::new(sx, sx * (p.y / p.x).atan() / FRAC_PI_4)
    } else {
        let sy = r.copysign(p.y);
        Vec2::new(sy * (p.x / p.y).atan() / FRAC_PI_4, sy)
    };
    let u = 0.5 * (s + Vec2::ONE);
    Vec2::new(clamp_unit(u.x), clamp_unit(u.y))
}

/// Maps the unit square to the upper hemisphere (`z ≥ 0`), uniformly in solid angle.
///
/// Measure: **solid angle**; pdf `1/(2π)` ([`uniform_hemisphere_pdf`]).
///
/// pbrt-v4's convention (`SampleUniformHemisphere`): the first coordinate is the height and
/// the second the azimuth,
///
/// `z = cos θ = u.x`, `r = sin θ = √(1 − z²)`, `φ = 2π·u.y`, `w = (r cos φ, r sin φ, z)`.
///
/// (Archimedes: `z` uniform on `[0, 1]` is uniform in solid angle.) Note that the roles of the
/// coordinates are swapped relative to [`square_to_cosine_hemisphere`]; the pole `z = 1` is
/// the limit `u.x → 1`, which `[0, 1)` never reaches.
///
/// Robustness: `1 − z²` is computed as `(1 − z)(1 + z)` (exact subtraction for `z ≥ ½`; pbrt
/// writes `1 − z²`) and clamped at `0`; the azimuth uses a signed turn so that `u.y` just below
/// one stays just below `2π`. `|‖w‖ − 1| < 1e-6` for `u ∈ [0, 1)²`.
pub fn square_to_uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = u.x;
    let r = ((1.0 - z) * (1.0 + z)).max(0.0).sqrt();
    let (sin_phi, cos_phi) = sin_cos_turns(u.y);
    Vec3::new(r * cos_phi, r * sin_phi, z)
}

/// The density of [`square_to_uniform_hemisphere`] with respect to **solid angle**:
/// `1/(2π)` for `w.z ≥ 0`, `0` below the horizon.
///
/// `w` is assumed to be a unit vector; only its sign of `z` is read (NaN gives `0`).
pub fn uniform_hemisphere_pdf(w: Vec3) -> f32 {
    if w.z >= 0.0 { INV_TAU } else { 0.0 }
}

/// The inverse of [`square_to_uniform_hemisphere`] (pbrt-v4, `InvertUniformHemisphereSample`):
///
/// `u.x = w.z`, `u.y = φ / (2π)` with `φ = atan2(w.y, w.x)` mapped into `[0, 2π)`.
///
/// Robustness: the result is clamped into `[0, 1)²` (a result rounding to `1` becomes
/// `1 − 2⁻²⁴`, not `0`); directions below the horizon give `u.x = 0`. At the pole `w = +z` the
/// azimuth is undefined and `u.y = 0`. For `u ∈ [0, 1)²`, `invert(sample(u)) == u` to within
/// `1e-5`.
pub fn uniform_hemisphere_to_square(w: Vec3) -> Vec2 {
    Vec2::new(clamp_unit(w.z), turns_from_xy(w.y, w.x))
}

/// Maps the unit square to the upper hemisphere with density proportional to `cos θ`.
///
/// Measure: **solid angle**; pdf `cos θ / π` ([`cosine_hemisphere_pdf`]).
///
/// The thesis's polar form of Malley's method: a disk point in polar coordinates
/// (`ρ = √u.y`, `φ = 2π·u.x`), uniform in area, lifted to the hemisphere:
///
/// `φ = 2π·u.x`, `sin θ = √u.y`, `cos θ = √(1 − u.y)`,
/// `w = (sin θ cos φ, sin θ sin φ, cos θ)`.
///
/// *Deviation from pbrt-v4*, which lifts the concentric disk ([`square_to_concentric_disk`])
/// instead; the distribution is the same.
///
/// Robustness: both square-root arguments are clamped at `0`; for `u.y < 1`, `1 − u.y > 0`
/// exactly, so `cos θ > 0` and every sample has a positive pdf. The azimuth uses a signed turn
/// so that `u.x` just below one stays just below `2π`. `|‖w‖ − 1| < 1e-6` for `u ∈ [0, 1)²`.
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let sin_theta = u.y.max(0.0).sqrt();
    let cos_theta = (1.0 - u.y).max(0.0).sqrt();
    let (sin_phi, cos_phi) = sin_cos_turns(u.x);
    Vec3::new(sin_theta * cos_phi, sin_theta * sin_phi, cos_theta)
}

/// The density of [`square_to_cosine_hemisphere`] with respect to **solid angle**:
/// `max(cos θ, 0) / π = max(w.z, 0) / π`.
///
/// `w` is assumed to be a unit vector. It integrates to one over the sphere:
/// `∫₀^{2π} ∫₀^1 z/π dz dφ = 1`.
pub fn cosine_hemisphere_pdf(w: Vec3) -> f32 {
    w.z.max(0.0) * FRAC_1_PI
}

/// The inverse of [`square_to_cosine_hemisphere`]:
///
/// `u.x = φ / (2π)` with `φ = atan2(w.y, w.x)` mapped into `[0, 2π)`, and
/// `u.y = sin² θ`, computed as `w.x² + w.y²` near the pole (`sin² θ < ½`, where `1 − z²` would
/// cancel) and as `1 − w.z²` near the horizon (where `w.x² + w.y² ≈ 1` carries the rounding of
/// both components).
///
/// Robustness: the result is clamped into `[0, 1)²` (a result rounding to `1` becomes
/// `1 − 2⁻²⁴`, not `0`). At the pole `w = +z` the azimuth is undefined and `u.x = 0`. For
/// `u ∈ [0, 1)²`, `invert(sample(u)) == u` to within `1e-5`, except that `u.y = 0` loses `u.x`.
pub fn cosine_hemisphere_to_square(w: Vec3) -> Vec2 {
    let sin2_xy = w.x * w.x + w.y * w.y;
    let sin2_theta = if sin2_xy < 0.5 { sin2_xy } else { (1.0 - w.z) * (1.0 + w.z) };
    Vec2::new(turns_from_xy(w.y, w.x), clamp_unit(sin2_theta))
}

/// Maps the unit square uniformly onto a triangle, as barycentrics `(b1, b2)` of the point
/// `(1 − b1 − b2)·v0 + b1·v1 + b2·v2`: Heitz's low-distortion map ("A Low-Distortion Map
/// Between Triangle and Square", 2019), as pbrt-v4's `SampleUniformTriangle` writes it. The
/// density is `1 / area` with respect to area, whatever the triangle.
///
/// Unlike the square-root map it keeps neighbouring `u` neighbouring on the triangle, so a
/// stratified pattern stays stratified. For `u ∈ [0, 1)²` the result has `b1, b2 ≥ 0`,
/// `b1 + b2 ≤ 1`.
pub fn square_to_uniform_triangle(u: Vec2) -> Vec2 {
    // pbrt's (b0, b1); our b1 is its b1 and our b2 its 1 − b0 − b1.
    let (b0, b1) = if u.x < u.y {
        let b0 = u.x / 2.0;
        (b0, u.y - b0)
    } else {
        let b1 = u.y / 2.0;
        (u.x - b1, b1)
    };
    Vec2::new(b1, (1.0 - b0 - b1).max(0.0))
}

/// Maps the unit square uniformly (in solid angle) onto the cone of directions within `θmax`
/// of `+z`, given as `one_minus_cos = 1 − cos θmax ∈ (0, 2]` (pbrt-v4's `SampleUniformCone`).
///
/// The cone is given by `1 − cos θmax`, not by `cos θmax`, so that tiny cones keep their size:
/// the sun's 0.53° disc has `1 − cos θ = 2.1·10⁻⁵` and a 0.001° disc `3.8·10⁻¹¹`, where
/// `cos θmax` rounds to 1 in `f32`. The sample's `sin θ = √(t(2 − t))` with `t = u.x·(1 −
/// cos θmax)` is formed from `t` directly, so the directions of a tiny cone are exact to
/// float rounding rather than collapsed onto the axis.
pub fn square_to_uniform_cone(u: Vec2, one_minus_cos: f32) -> Vec3 {
    let t = u.x * one_minus_cos;
    let sin_theta = (t * (2.0 - t)).max(0.0).sqrt();
    let (sin_phi, cos_phi) = sin_cos_turns(u.y);
    Vec3::new(sin_theta * cos_phi, sin_theta * sin_phi, 1.0 - t)
}

/// The density of [`square_to_uniform_cone`] with respect to solid angle, inside the cone:
/// `1 / (2π (1 − cos θmax))`.
pub fn uniform_cone_pdf(one_minus_cos: f32) -> f32 {
    INV_TAU / one_minus_cos
}

/// Whether unit direction `w` lies within the cone of `1 − cos θmax = one_minus_cos` around
/// unit `axis`: `‖w − axis‖² ≤ 2(1 − cos θmax)`, the chord form of `w·axis ≥ cos θmax`, which
/// stays exact for cones too small for `cos θmax` to be told from 1 in `f32`.
pub fn in_cone(w: Vec3, axis: Vec3, one_minus_cos: f32) -> bool {
    (w - axis).length_squared() <= 2.0 * one_minus_cos
}

/// The solid angle a triangle subtends at a point, given its vertices relative to that point
/// (`a = v0 − p`, …; any lengths): Van Oosterom & Strackee's formula ("The Solid Angle of a
/// Plane Triangle", *IEEE Trans. Biomed. Eng.* 30(2), 1983),
///
/// `tan(Ω/2) = |a·(b×c)| / (|a||b||c| + (a·b)|c| + (a·c)|b| + (b·c)|a|)`.
///
/// The triple product is formed from the edges, `a·((b − a)×(c − a))`, and the directions are
/// never normalised, so a tiny or distant triangle keeps its relative precision (no `α + β + γ
/// − π` cancellation): this is the pdf [`square_to_spherical_triangle`] is used with.
pub fn spherical_triangle_solid_angle(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let det = a.dot((b - a).cross(c - a)).abs();
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * det.atan2(denominator)
}

/// Solid angles below which [`square_to_spherical_triangle`] is not used (sr; pbrt-v4's
/// `MinSphericalSampleArea`). Not for precision — the construction here keeps its distribution
/// down to 10⁻¹⁰ sr — but for cost: a triangle this small (side ≈ 1/60 of its distance) has an
/// area pdf within a few % of uniform in solid angle, and area sampling is far cheaper.
pub const SPHERICAL_TRIANGLE_MIN_SOLID_ANGLE: f32 = 3e-4;

/// Solid angles above which [`square_to_spherical_triangle`] is not used (sr): a triangle
/// covering nearly a hemisphere, where its construction divides by almost zero. pbrt-v4's
/// `MaxSphericalSampleArea`.
pub const SPHERICAL_TRIANGLE_MAX_SOLID_ANGLE: f32 = 6.22;

/// Maps the unit square uniformly, in solid angle, onto the spherical triangle that the triangle
/// with vertices `a`, `b`, `c` (relative to the viewpoint, any lengths) subtends: Arvo's method
/// ("Stratified Sampling of Spherical Triangles", SIGGRAPH 1995). `u.x` chooses the sub-triangle
/// `a b c'` holding that fraction of the solid angle, `u.y` the direction on the arc from `b` to
/// `c'`, uniform in `1 − cos θ` from `b` (as pbrt-v4's `SampleSphericalTriangle`).
///
/// *Deviation from Arvo and pbrt*, for `f32` (and a GPU's trigonometry): `c'` is not found from
/// the angles `α, β, γ` (whose sum minus π cancels, and whose `cos b'` near 1 loses the arc's
/// length), but as the point `a + t(c − a)` of the edge whose sub-triangle has the solid angle
/// `x = u.x·Ω` in Van Oosterom & Strackee's formula ([`spherical_triangle_solid_angle`]): with
/// `T = tan(x/2)` that is a quadratic in `t` whose other root is 0, so `t` is one quotient and
/// the only trigonometry is the sine and cosine of `x/2`. Every `1 − cos` of an arc is half
/// its chord squared.
///
/// Returns the unit direction and the barycentrics `(b1, b2)` of the point it reaches on the
/// triangle (clamped onto it), or `None` for a degenerate triangle (an edge seen end-on). Use it
/// for solid angles in [`SPHERICAL_TRIANGLE_MIN_SOLID_ANGLE`, `SPHERICAL_TRIANGLE_MAX_SOLID_ANGLE`];
/// `omega` is the triangle's solid angle, [`spherical_triangle_solid_angle`]`(a, b, c)`, which
/// the caller has formed to choose the method and the pdf `1 / omega`.
pub fn square_to_spherical_triangle(u: Vec2, a: Vec3, b: Vec3, c: Vec3, omega: f32) -> Option<(Vec3, Vec2)> {
    let (ua, ub) = (a.normalize(), b.normalize());
    let ca = c - a;
    // With p(t) = a + t(c − a), L = |p|, cab = ua·ub, the sub-triangle (ua, ub, p) has
    // tan(x/2) = t·D / ((1 + cab)·L + (ua + ub)·p), D = |ua·(ub × (c − a))|. Squared, with
    // s, k = sin, cos of x/2, a quadratic in t with the root 0 (x = 0) and
    // t = 2K(|a|Q + K a·(c − a)) / (Q² − K²|c − a|²), K = (1 + cab)·s, Q = D·k − s (ua + ub)·(c − a)
    // (multiplied through by k², so x/2 = π/2 needs no infinite tangent).
    let (sin_half, cos_half) = (0.5 * u.x * omega).sin_cos();
    let one_plus_cab = 2.0 - 0.5 * (ua - ub).length_squared();
    let d = ua.dot(ub.cross(ca)).abs();
    let q = d * cos_half - sin_half * (ua + ub).dot(ca);
    let k = one_plus_cab * sin_half;
    let numerator = 2.0 * k * (a.length() * q + k * a.dot(ca));
    let denominator = q * q - k * k * ca.length_squared();
    let t = (numerator / denominator).clamp(0.0, 1.0);
    if t.is_nan() {
        return None;
    }
    let cp = (a + t * ca).normalize();
    // The direction on the arc from b to c': 1 − cos θ = u.y·(1 − cos(b c')).
    let versine_theta = u.y * 0.5 * (cp - ub).length_squared();
    let sin_theta = (versine_theta * (2.0 - versine_theta)).max(0.0).sqrt();
    let w = (1.0 - versine_theta) * ub + sin_theta * (cp - cp.dot(ub) * ub).normalize();
    // Where the ray from the viewpoint along w meets the triangle's plane (Möller–Trumbore with
    // the origin at the viewpoint), clamped onto the triangle.
    let (e1, e2) = (b - a, c - a);
    let s1 = w.cross(e2);
    let divisor = s1.dot(e1);
    if !(divisor.abs() > 0.0) {
        return None;
    }
    let s = -a;
    let mut b1 = (s.dot(s1) / divisor).clamp(0.0, 1.0);
    let mut b2 = (w.dot(s.cross(e1)) / divisor).clamp(0.0, 1.0);
    if b1 + b2 > 1.0 {
        let sum = b1 + b2;
        b1 /= sum;
        b2 /= sum;
    }
    // A NaN above (a direction not finite) makes the sample invalid.
    if b1.is_nan() || b2.is_nan() {
        return None;
    }
    Some((w, Vec2::new(b1, b2)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Coordinates that stress the edges: zero, the smallest steps away from it, the middle, and
    /// the values just below one (`1 − 2⁻²⁴` is the largest `f32` below one).
    const EDGES: [f32; 12] = [
        0.0,
        1e-30,
        f32::EPSILON / 2.0, // 2⁻²⁴
        1e-6,
        0.25,
        0.5 - f32::EPSILON / 4.0,
        0.5,
        0.75,
        1.0 - 1e-6,
        1.0 - 2.0 * f32::EPSILON, // 1 − 2⁻²²
        1.0 - f32::EPSILON,       // 1 − 2⁻²³
        ONE_MINUS_EPSILON,        // 1 − 2⁻²⁴
    ];

    /// Test points: every pair of [`EDGES`], a 65 × 65 grid `i / 64` (with `1` replaced by
    /// `1 − 2⁻²⁴`), and 100 000 points from a fixed-seed generator.
    fn test_points() -> Vec<Vec2> {
        let mut points = Vec::new();
        for &a in &EDGES {
            for &b in &EDGES {
                points.push(Vec2::new(a, b));
            }
        }
        for i in 0..=64 {
            for j in 0..=64 {
                let g = |k: i32| (k as f32 / 64.0).min(ONE_MINUS_EPSILON);
                points.push(Vec2::new(g(i), g(j)));
            }
        }
        let mut rng = crate::RandomStream::new(0, 0, 0x5EED_0001);
        for _ in 0..100_000 {
            points.push(Vec2::new(rng.next_f32(), rng.next_f32()));
        }
        points
    }

    /// Tolerance of the round trip `invert(sample(u)) == u`, per coordinate.
    const ROUND_TRIP_TOL: f32 = 1e-5;

    /// Tolerance on the 3-D direction where the azimuth is lost (poles): `sample(invert(w))`
    /// must reproduce `w` to within a few ulp of a unit vector.
    const DIRECTION_TOL: f32 = 1e-6;

    fn assert_in_unit_square(u: Vec2, context: &str) {
        assert!(
            (0.0..1.0).contains(&u.x) && (0.0..1.0).contains(&u.y),
            "{context}: inverse {u:?} is outside [0, 1)²"
        );
    }

    #[test]
    fn concentric_disk_round_trip() {
        for u in test_points() {
            let p = square_to_concentric_disk(u);
            assert!(p.is_finite(), "sample({u:?}) = {p:?}");
            assert!(p.length_squared() <= 1.0 + DISK_RIM_SLACK, "sample({u:?}) = {p:?}");
            let back = concentric_disk_to_square(p);
            assert_in_unit_square(back, &format!("u = {u:?}"));
            if p == Vec2::ZERO {
                // Only the centre maps there; its azimuth is lost.
                assert_eq!(back, Vec2::splat(0.5), "u = {u:?}");
                assert!((u - back).abs().max_element() <= ROUND_TRIP_TOL, "u = {u:?}");
            } else {
                let err = (u - back).abs().max_element();
                assert!(err <= ROUND_TRIP_TOL, "u = {u:?} → {p:?} → {back:?} (err {err})");
            }
        }
    }

    /// Round trip of a hemisphere warp. Where the sample sits on the pole (`x = y = 0`) the
    /// azimuth is lost, so there the height coordinate is compared in `u` and the azimuth is
    /// checked on the 3-D direction instead ([`DIRECTION_TOL`]).
    fn check_hemisphere_round_trip(sample: fn(Vec2) -> Vec3, invert: fn(Vec3) -> Vec2, height_is_x: bool) {
        for u in test_points() {
            let w = sample(u);
            assert!(w.is_finite(), "sample({u:?}) = {w:?}");
            assert!((w.length() - 1.0).abs() < 1e-6, "sample({u:?}) = {w:?} not unit");
            assert!(w.z >= 0.0, "sample({u:?}) = {w:?} below the horizon");
            let back = invert(w);
            assert_in_unit_square(back, &format!("u = {u:?}"));
            let err = (u - back).abs();
            let (height_err, azimuth_err) = if height_is_x { (err.x, err.y) } else { (err.y, err.x) };
            assert!(height_err <= ROUND_TRIP_TOL, "u = {u:?} → {w:?} → {back:?}");
            if w.x == 0.0 && w.y == 0.0 {
                // On the pole: the azimuth is lost, the direction must survive.
                let w_again = sample(back);
                let dir_err = (w_again - w).abs().max_element();
                assert!(dir_err <= DIRECTION_TOL, "u = {u:?}: sample(invert(w)) = {w_again:?} ≠ {w:?}");
            } else {
                assert!(azimuth_err <= ROUND_TRIP_TOL, "u = {u:?} → {w:?} → {back:?}");
            }
        }
    }

    #[test]
    fn uniform_hemisphere_round_trip() {
        check_hemisphere_round_trip(square_to_uniform_hemisphere, uniform_hemisphere_to_square, true);
    }

    #[test]
    fn cosine_hemisphere_round_trip() {
        check_hemisphere_round_trip(square_to_cosine_hemisphere, cosine_hemisphere_to_square, false);
    }

    /// The azimuth wrap: `u` just below one must come back just below one (not as `0`), and
    /// the inverses never return `1.0`.
    #[test]
    fn azimuth_wrap_near_one() {
        for &t in &[ONE_MINUS_EPSILON, 1.0 - f32::EPSILON, 1.0 - 1e-6, 0.0] {
            let (sin, cos) = sin_cos_turns(t);
            let back = turns_from_xy(sin, cos);
            assert!(back < 1.0 && (back - t).abs() <= 1e-6, "t = {t} → {back}");
            if t > 0.5 {
                assert!(sin < 0.0, "t = {t}: sin φ = {sin} should be negative");
            }
        }
        // Exactly on the positive x axis from below (−0) and the angle 2π − ½ ulp.
        assert_eq!(turns_from_xy(-0.0, 1.0), 0.0);
        assert!(turns_from_xy(-1e-9, 1.0) < 1.0);
        assert_eq!(turns_from_xy(0.0, 0.0), 0.0);
        assert_eq!(turns_from_xy(f32::NAN, 1.0), 0.0);
    }

    /// Finite, normalised outputs at the corners and edges of the square, and a positive pdf
    /// at every sample.
    #[test]
    fn edges_are_finite_and_normalised() {
        for &a in &EDGES {
            for &b in &EDGES {
                let u = Vec2::new(a, b);
                let p = square_to_concentric_disk(u);
                assert!(p.is_finite() && p.length() <= 1.0 + 1e-6, "disk({u:?}) = {p:?}");
                assert!(concentric_disk_pdf(p) > 0.0, "disk pdf 0 at {p:?}");
                for (name, w, pdf) in [
                    ("uniform", square_to_uniform_hemisphere(u), uniform_hemisphere_pdf as fn(Vec3) -> f32),
                    ("cosine", square_to_cosine_hemisphere(u), cosine_hemisphere_pdf as fn(Vec3) -> f32),
                ] {
                    assert!(w.is_finite(), "{name}({u:?}) = {w:?}");
                    assert!((w.length() - 1.0).abs() < 1e-6, "{name}({u:?}) = {w:?}");
                    assert!(pdf(w) > 0.0, "{name} pdf is 0 at its own sample {w:?}");
                }
            }
        }
        // Specific values: the corner u = 0 and the pole.
        assert_eq!(square_to_uniform_hemisphere(Vec2::ZERO), Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(square_to_cosine_hemisphere(Vec2::ZERO), Vec3::Z);
        assert_eq!(square_to_concentric_disk(Vec2::splat(0.5)), Vec2::ZERO);
        // u.y → 1 on the cosine warp approaches the horizon but stays above it.
        let w = square_to_cosine_hemisphere(Vec2::new(0.3, ONE_MINUS_EPSILON));
        assert!(w.z > 0.0 && w.z < 1e-3, "{w:?}");
    }

    /// The inverses map anything, including out-of-range input, into `[0, 1)²`.
    #[test]
    fn inverses_stay_in_unit_square() {
        let disk = [
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, -1.0),
            Vec2::new(2.0, 2.0),
            Vec2::new(-1e-30, 1e-30),
            Vec2::NAN,
        ];
        for p in disk {
            assert_in_unit_square(concentric_disk_to_square(p), &format!("disk {p:?}"));
        }
        let dirs = [Vec3::Z, -Vec3::Z, Vec3::X, -Vec3::X, Vec3::new(0.6, -0.8, 0.0)];
        for w in dirs {
            assert_in_unit_square(uniform_hemisphere_to_square(w), &format!("uniform {w:?}"));
            assert_in_unit_square(cosine_hemisphere_to_square(w), &format!("cosine {w:?}"));
        }
    }

    /// Integral of a solid-angle pdf over the whole sphere by the midpoint rule in `(z, φ)`
    /// (the Jacobian from `(z, φ)` to solid angle is 1), accumulated in `f64`.
    fn integrate_sphere(pdf: fn(Vec3) -> f32, nz: usize, nphi: usize) -> f64 {
        let dz = 2.0 / nz as f64;
        let dphi = 2.0 * PI / nphi as f64;
        let mut sum = 0.0;
        for i in 0..nz {
            let z = -1.0 + (i as f64 + 0.5) * dz;
            let r = (1.0 - z * z).sqrt();
            for j in 0..nphi {
                let phi = (j as f64 + 0.5) * dphi;
                let w = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
                sum += pdf(w) as f64;
            }
        }
        sum * dz * dphi
    }

    /// Both hemisphere pdfs integrate to one over the sphere (and so are zero below the
    /// horizon). With an even number of `z` cells the horizon `z = 0`, where both pdfs have a
    /// kink or jump, is a cell edge; inside each cell the pdfs are constant (uniform) or
    /// linear in `z` (cosine), which the midpoint rule integrates exactly. What is left is the
    /// `f32` rounding of the directions and pdf values (relative ~1e-7), hence `1e-5`.
    #[test]
    fn hemisphere_pdfs_integrate_to_one() {
        for (name, pdf) in [
            ("uniform", uniform_hemisphere_pdf as fn(Vec3) -> f32),
            ("cosine", cosine_hemisphere_pdf as fn(Vec3) -> f32),
        ] {
            let integral = integrate_sphere(pdf, 200, 400);
            assert!((integral - 1.0).abs() < 1e-5, "{name}: ∫ pdf dω = {integral}");
        }
    }

    /// The disk pdf integrates to one over `[−1.25, 1.25]²` (so it is zero outside the disk).
    /// Midpoint rule on an `n × n` grid of cell size `h`: only cells cut by the unit circle
    /// contribute error, each at most `h²/π`; they all lie within the annulus `|ρ − 1| ≤ h/√2`
    /// (half a cell diagonal) of area `2π·√2·h`, so `|error| ≤ 2√2·h` (plus `f64` rounding).
    /// For `n = 4096`, `h ≈ 6.1e-4` and the bound is `1.73e-3`; the observed error is far
    /// smaller because over- and under-counted cells cancel.
    #[test]
    fn disk_pdf_integrates_to_one() {
        let n = 4096;
        let extent = 1.25;
        let h = 2.0 * extent / n as f64;
        let mut sum = 0.0;
        for i in 0..n {
            let y = -extent + (i as f64 + 0.5) * h;
            for j in 0..n {
                let x = -extent + (j as f64 + 0.5) * h;
                sum += concentric_disk_pdf(Vec2::new(x as f32, y as f32)) as f64;
            }
        }
        let integral = sum * h * h;
        let bound = 2.0 * std::f64::consts::SQRT_2 * h;
        assert!((integral - 1.0).abs() <= bound, "∫ pdf dA = {integral}, bound {bound}");
    }

    /// `pdf(sample(u)) · |det ∂sample/∂u| = 1`: the pdf is the reciprocal of the warp's area
    /// (disk) or solid-angle (hemisphere) Jacobian. Central differences with step `h = 1e-3`
    /// (truncation `O(h²)`, `f32` rounding `~1e-7 / h = 1e-4`), tolerance `1e-2`. Points within
    /// `2h` of the concentric map's diagonals and centre are skipped: its derivative jumps
    /// there, although the map is continuous.
    #[test]
    fn pdf_is_inverse_jacobian() {
        let h = 1e-3_f32;
        let n = 40;
        for i in 0..n {
            for j in 0..n {
                // Cell centres of an n × n grid, away from the square's edges.
                let u = Vec2::new(
                    (i as f32 + 0.5) / n as f32 * 0.98 + 0.01,
                    (j as f32 + 0.5) / n as f32 * 0.98 + 0.01,
                );
                let dx = Vec2::new(h, 0.0);
                let dy = Vec2::new(0.0, h);

                let s = 2.0 * u - Vec2::ONE;
                let near_diagonal = (s.x.abs() - s.y.abs()).abs() < 4.0 * h;
                if !near_diagonal && s.length() > 4.0 * h {
                    let ddx =
                        (square_to_concentric_disk(u + dx) - square_to_concentric_disk(u - dx)) / (2.0 * h);
                    let ddy =
                        (square_to_concentric_disk(u + dy) - square_to_concentric_disk(u - dy)) / (2.0 * h);
                    let jac = ddx.perp_dot(ddy).abs();
                    let p = square_to_concentric_disk(u);
                    let prod = concentric_disk_pdf(p) * jac;
                    assert!((prod - 1.0).abs() < 1e-2, "disk at {u:?}: pdf·J = {prod}");
                }

                for (name, sample, pdf) in [
                    (
                        "uniform",
                        square_to_uniform_hemisphere as fn(Vec2) -> Vec3,
                        uniform_hemisphere_pdf as fn(Vec3) -> f32,
                    ),
                    (
                        "cosine",
                        square_to_cosine_hemisphere as fn(Vec2) -> Vec3,
                        cosine_hemisphere_pdf as fn(Vec3) -> f32,
                    ),
                ] {
                    let ddx = (sample(u + dx) - sample(u - dx)) / (2.0 * h);
                    let ddy = (sample(u + dy) - sample(u - dy)) / (2.0 * h);
                    let jac = ddx.cross(ddy).length();
                    let prod = pdf(sample(u)) * jac;
                    assert!((prod - 1.0).abs() < 1e-2, "{name} at {u:?}: pdf·J = {prod}");
                }
            }
        }
    }

    /// `spherical_triangle_solid_angle` in f64, for reference.
    fn solid_angle_f64(a: glam::DVec3, b: glam::DVec3, c: glam::DVec3) -> f64 {
        let det = a.dot((b - a).cross(c - a)).abs();
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        2.0 * det.atan2(la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la)
    }

    #[test]
    fn solid_angles_are_exact_from_an_octant_to_a_speck() {
        // The octant: π/2 exactly (to rounding).
        let octant = spherical_triangle_solid_angle(Vec3::X, Vec3::Y, Vec3::Z);
        assert!((octant - FRAC_PI_2).abs() <= 2e-7, "octant: {octant}");
        // The same triangle seen from either side, and at any scale of its vertex vectors.
        assert_eq!(spherical_triangle_solid_angle(Vec3::X, Vec3::Z, Vec3::Y), octant);
        let scaled = spherical_triangle_solid_angle(3.0 * Vec3::X, 0.5 * Vec3::Y, 7.0 * Vec3::Z);
        assert!((scaled - octant).abs() <= 1e-6, "scaled octant: {scaled}");
        // Triangles of side s at distance 1, down to specks of 10⁻¹² sr: relative error of the
        // f32 formula against f64 stays at f32 rounding (no cancellation).
        for k in 0..=12 {
            let side = 10f32.powf(-(k as f32) / 2.0);
            let v =
                [Vec3::new(0.3, 0.2, 1.0), Vec3::new(0.3 + side, 0.2, 1.0), Vec3::new(0.3, 0.2 + side, 1.0)];
            let got = spherical_triangle_solid_angle(v[0], v[1], v[2]);
            let exact = solid_angle_f64(v[0].as_dvec3(), v[1].as_dvec3(), v[2].as_dvec3());
            let rel = (f64::from(got) - exact).abs() / exact;
            assert!(rel <= 1e-5, "side {side:e}: {got:e} against {exact:e} (relative error {rel:e})");
        }
    }

    /// Where does `f32` spherical-triangle sampling break? Triangles of shrinking solid angle, a
    /// 256² grid of `u`: the fraction of samples in each quarter of the triangle (midpoint
    /// subdivision) against that quarter's share of the solid angle (f64), largest deviation
    /// printed per solid angle. The grid alone gives up to ~10⁻³ (a quarter's edge cuts grid
    /// rows); pbrt's angle-based construction in `f32` reached 8.5·10⁻⁴ at 3·10⁻⁴ sr, 2·10⁻² at
    /// 10⁻⁵ sr and lost the quarters below 10⁻⁷ sr. Ours must stay below 2·10⁻³ from 0.2 sr down
    /// to 10⁻¹⁰ sr — a share off by δ biases an emitter term by at most δ times the integrand's
    /// spread over the triangle, a few % for triangles that small.
    #[test]
    fn spherical_triangle_sampling_holds_for_tiny_triangles() {
        use glam::DVec3;
        let n = 256;
        let mut rows = Vec::new();
        for k in 0..=18 {
            let side = 0.8 * 10f32.powf(-(k as f32) / 4.0);
            let v = [
                Vec3::new(0.2, 0.1, 1.0),
                Vec3::new(0.2 + side, 0.1, 1.0),
                Vec3::new(0.2 + 0.3 * side, 0.1 + side, 1.0),
            ];
            let vd = v.map(Vec3::as_dvec3);
            let omega = solid_angle_f64(vd[0], vd[1], vd[2]);
            // The four midpoint sub-triangles, and which one a barycentric point is in.
            let m = [(vd[0] + vd[1]) / 2.0, (vd[1] + vd[2]) / 2.0, (vd[2] + vd[0]) / 2.0];
            let quarters: [[DVec3; 3]; 4] =
                [[vd[0], m[0], m[2]], [m[0], vd[1], m[1]], [m[2], m[1], vd[2]], [m[0], m[1], m[2]]];
            let expected = quarters.map(|q| solid_angle_f64(q[0], q[1], q[2]) / omega);
            let mut counts = [0usize; 4];
            let mut invalid = 0;
            for i in 0..n {
                for j in 0..n {
                    let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    let Some((_, b)) = square_to_spherical_triangle(
                        u,
                        v[0],
                        v[1],
                        v[2],
                        spherical_triangle_solid_angle(v[0], v[1], v[2]),
                    ) else {
                        invalid += 1;
                        continue;
                    };
                    let b0 = 1.0 - b.x - b.y;
                    let q = if b0 > 0.5 {
                        0
                    } else if b.x > 0.5 {
                        1
                    } else if b.y > 0.5 {
                        2
                    } else {
                        3
                    };
                    counts[q] += 1;
                }
            }
            let total = (n * n) as f64;
            let deviation =
                (0..4).map(|q| (counts[q] as f64 / total - expected[q]).abs()).fold(0.0, f64::max);
            rows.push(format!(
                "  Ω = {omega:.3e} sr: largest quarter deviation {deviation:.2e}, invalid {invalid}"
            ));
            assert!(
                deviation < 2e-3 && invalid == 0,
                "spherical triangle sampling at Ω = {omega:e}:\n{}",
                rows.join("\n")
            );
        }
        eprintln!("spherical triangle sampling in f32, by solid angle:\n{}", rows.join("\n"));
    }
}
