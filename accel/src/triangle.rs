//! The ray-triangle test shared by the BVH queries and the brute-force references.

use glam::{Vec2, Vec3};

/// A ray-triangle intersection: distance and barycentrics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter of the hit: the point is `origin + t · dir` (in units of `dir`'s length).
    pub t: f32,
    /// Barycentrics `(u, v)`: the point is `(1 − u − v)·v0 + u·v1 + v·v2`.
    pub barycentrics: Vec2,
}

/// Two-sided Möller–Trumbore ray-triangle test in `f32` (Möller & Trumbore 1997).
///
/// Returns the hit if `0 < t < t_max` and the barycentrics lie in the closed triangle. A
/// degenerate triangle (zero determinant) and any NaN input give `None`. This is the exact
/// function the BVH queries call on each candidate, so a brute-force loop over it is a
/// bit-exact reference for them.
///
/// ```
/// use furnace_accel::intersect_triangle;
/// use glam::Vec3;
/// let hit = intersect_triangle(
///     Vec3::new(0.25, 0.25, 1.0), Vec3::NEG_Z,
///     [Vec3::ZERO, Vec3::X, Vec3::Y], f32::INFINITY,
/// ).unwrap();
/// assert_eq!(hit.t, 1.0);
/// ```
#[inline(always)]
pub fn intersect_triangle(
    origin: Vec3,
    dir: Vec3,
    [v0, v1, v2]: [Vec3; 3],
    t_max: f32,
) -> Option<TriangleHit> {
    let e1 = v1 - v0;
    let e2 = v2 - v0;
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if !(det != 0.0) {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = origin - v0;
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv_det;
    if !(v >= 0.0 && u + v <= 1.0) {
        return None;
    }
    let t = e2.dot(q) * inv_det;
    if !(t > 0.0 && t < t_max) {
        return None;
    }
    Some(TriangleHit { t, barycentrics: Vec2::new(u, v) })
}
