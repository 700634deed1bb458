//! The ray-triangle test shared by the BVH queries and the brute-force references.

use glam::{Vec2, Vec3, Vec3A};

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

/// A triangle as the CPU traversal tests it: its first vertex and the edges `v1 − v0`,
/// `v2 − v0` from it, formed once at build time (the same subtractions
/// [`intersect_triangle`] makes on every test), in 16-byte vectors.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EdgeTriangle {
    v0: Vec3A,
    e1: Vec3A,
    e2: Vec3A,
}

impl EdgeTriangle {
    pub(crate) fn new([v0, v1, v2]: [Vec3; 3]) -> Self {
        EdgeTriangle { v0: v0.into(), e1: (v1 - v0).into(), e2: (v2 - v0).into() }
    }

    /// [`intersect_triangle`] with the edges formed: the same operations in the same order
    /// (glam's SSE cross and dot products round like its scalar ones: each lane is one IEEE
    /// product or difference, and the dot product sums `x + y` first, then `+ z`), so the
    /// same hit to the bit — on targets without FMA, where glam's `Vec3A::cross` does not
    /// fuse (the default x86-64 target has none).
    #[inline(always)]
    pub(crate) fn intersect(&self, origin: Vec3A, dir: Vec3A, t_max: f32) -> Option<TriangleHit> {
        let p = dir.cross(self.e2);
        let det = self.e1.dot(p);
        if !(det != 0.0) {
            return None;
        }
        let inv_det = 1.0 / det;
        let s = origin - self.v0;
        let u = s.dot(p) * inv_det;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(self.e1);
        let v = dir.dot(q) * inv_det;
        if !(v >= 0.0 && u + v <= 1.0) {
            return None;
        }
        let t = self.e2.dot(q) * inv_det;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        Some(TriangleHit { t, barycentrics: Vec2::new(u, v) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The edge form gives [`intersect_triangle`]'s hits to the bit (the brute-force references
    /// of the BVH tests use the latter): random rays against random triangles of mixed scales,
    /// near-degenerate ones and grazing rays included, from a fixed seed.
    #[test]
    fn edge_triangle_matches_intersect_triangle_bit_for_bit() {
        let mut rng = furnace_tests::Rng::new(0x2545_f491_4f6c_dd1d);
        let mut next = || rng.range(-1.0, 1.0);
        let (mut hits, mut total) = (0, 0);
        for k in 0..200_000 {
            let scale = [1e-3f32, 1.0, 1e3][k % 3];
            let mut v = || Vec3::new(next(), next(), next()) * scale;
            let tri = [v(), v(), v()];
            // Every fourth triangle is a sliver: its third vertex near the first edge.
            let tri =
                if k % 4 == 0 { [tri[0], tri[1], tri[0].lerp(tri[1], 0.5) + tri[2] * 1e-6] } else { tri };
            let origin = v() * 2.0;
            // Half the rays aimed at a point of the triangle's plane near it, so that many hit.
            let (a, b) = (next().abs(), next().abs());
            let aim = tri[0] + (tri[1] - tri[0]) * a + (tri[2] - tri[0]) * b;
            let dir = if k % 2 == 0 { aim - origin } else { Vec3::new(next(), next(), next()) };
            let t_max = if k % 5 == 0 { 0.5 } else { f32::INFINITY };
            let reference = intersect_triangle(origin, dir, tri, t_max);
            let edges = EdgeTriangle::new(tri).intersect(origin.into(), dir.into(), t_max);
            let bits = |h: Option<TriangleHit>| {
                h.map(|h| [h.t, h.barycentrics.x, h.barycentrics.y].map(f32::to_bits))
            };
            assert_eq!(bits(edges), bits(reference), "triangle {tri:?}, ray {origin} {dir}, t_max {t_max}");
            hits += usize::from(reference.is_some());
            total += 1;
        }
        // The comparison means something only if many rays hit (about a fifth do).
        assert!(hits > total / 10, "{hits} hits of {total}");
    }
}
