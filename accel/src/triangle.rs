//! The ray-triangle test shared by the BVH queries and the brute-force references.

use glam::{Vec2, Vec3, Vec3A, Vec4};

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

/// Up to four triangles of one leaf as the CPU traversal tests them: each one's first vertex
/// `v0` and its edges `v1 − v0`, `v2 − v0` (formed once at build time: the subtractions
/// [`intersect_triangle`] makes on every test), one lane per triangle (structure of arrays, `[x, y, z]` of 4 lanes), so
/// that one pass of 4-wide arithmetic tests them all with no branch per triangle. Unused lanes
/// hold zero edges: their determinant is exactly 0, which no ray hits.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tri4 {
    v0: [Vec4; 3],
    e1: [Vec4; 3],
    e2: [Vec4; 3],
}

/// The lanes of [`Tri4::intersect`] that hit, with their distances and barycentrics.
pub(crate) struct Hits4 {
    /// Bit `k` set: lane `k` hit at `0 < t < t_max`.
    pub mask: u32,
    pub t: [f32; 4],
    pub u: [f32; 4],
    pub v: [f32; 4],
}

impl Tri4 {
    /// `triangles` (at most 4) in lanes `0..triangles.len()`.
    pub(crate) fn new(triangles: &[[Vec3; 3]]) -> Self {
        assert!(triangles.len() <= 4, "a leaf block holds at most 4 triangles");
        let mut lanes = [[[0.0f32; 4]; 3]; 3];
        for (k, &[v0, v1, v2]) in triangles.iter().enumerate() {
            for (c, vector) in [v0, v1 - v0, v2 - v0].into_iter().enumerate() {
                for axis in 0..3 {
                    lanes[c][axis][k] = vector[axis];
                }
            }
        }
        let soa = |c: usize| lanes[c].map(Vec4::from_array);
        Tri4 { v0: soa(0), e1: soa(1), e2: soa(2) }
    }

    /// [`intersect_triangle`] on each lane: the same IEEE operations in the same order per
    /// lane (its cross products `a.y·b.z − a.z·b.y`, …, its dot products `(x + y) + z`, neither
    /// fused: Rust does not contract `a·b + c`), so each lane's hit is the scalar test's to the
    /// bit.
    #[inline(always)]
    pub(crate) fn intersect(&self, origin: Vec3A, dir: Vec3A, t_max: f32) -> Hits4 {
        let [dx, dy, dz] = dir.to_array().map(Vec4::splat);
        let [e1x, e1y, e1z] = self.e1;
        let [e2x, e2y, e2z] = self.e2;
        // p = dir × e2
        let px = dy * e2z - dz * e2y;
        let py = dz * e2x - dx * e2z;
        let pz = dx * e2y - dy * e2x;
        let det = e1x * px + e1y * py + e1z * pz;
        let inv_det = Vec4::ONE / det;
        let sx = Vec4::splat(origin.x) - self.v0[0];
        let sy = Vec4::splat(origin.y) - self.v0[1];
        let sz = Vec4::splat(origin.z) - self.v0[2];
        let u = (sx * px + sy * py + sz * pz) * inv_det;
        // q = s × e1
        let qx = sy * e1z - sz * e1y;
        let qy = sz * e1x - sx * e1z;
        let qz = sx * e1y - sy * e1x;
        let v = (dx * qx + dy * qy + dz * qz) * inv_det;
        let t = (e2x * qx + e2y * qy + e2z * qz) * inv_det;
        // The scalar test's conditions; NaN fails each comparison as it fails there.
        let hit = det.cmpne(Vec4::ZERO)
            & u.cmpge(Vec4::ZERO)
            & u.cmple(Vec4::ONE)
            & v.cmpge(Vec4::ZERO)
            & (u + v).cmple(Vec4::ONE)
            & t.cmpgt(Vec4::ZERO)
            & t.cmplt(Vec4::splat(t_max));
        Hits4 { mask: hit.bitmask(), t: t.to_array(), u: u.to_array(), v: v.to_array() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 4-lane test gives [`intersect_triangle`]'s hits to the bit on every lane (the
    /// brute-force references of the BVH tests use the latter): random rays against blocks of
    /// 1–4 random triangles of mixed scales, near-degenerate ones and grazing rays included, from
    /// a fixed seed; lanes beyond the block's triangles never hit.
    #[test]
    fn tri4_matches_intersect_triangle_bit_for_bit() {
        let mut rng = furnace_tests::Rng::new(0x2545_f491_4f6c_dd1d);
        let mut next = || rng.range(-1.0, 1.0);
        let (mut hits, mut total) = (0, 0);
        for k in 0..100_000 {
            let scale = [1e-3f32, 1.0, 1e3][k % 3];
            let mut v = || Vec3::new(next(), next(), next()) * scale;
            let count = 1 + k % 4;
            let tris: Vec<[Vec3; 3]> = (0..count)
                .map(|j| {
                    let tri = [v(), v(), v()];
                    // Every fourth triangle is a sliver: its third vertex near the first edge.
                    if (k + j) % 4 == 0 {
                        [tri[0], tri[1], tri[0].lerp(tri[1], 0.5) + tri[2] * 1e-6]
                    } else {
                        tri
                    }
                })
                .collect();
            let origin = v() * 2.0;
            // Half the rays aimed at a point of one triangle's plane near it, so that many hit.
            let tri = tris[k % count];
            let (a, b) = (next().abs(), next().abs());
            let aim = tri[0] + (tri[1] - tri[0]) * a + (tri[2] - tri[0]) * b;
            let dir = if k % 2 == 0 { aim - origin } else { Vec3::new(next(), next(), next()) };
            let t_max = if k % 5 == 0 { 0.5 } else { f32::INFINITY };
            let got = Tri4::new(&tris).intersect(origin.into(), dir.into(), t_max);
            for lane in 0..4 {
                let reference = tris.get(lane).and_then(|&tri| intersect_triangle(origin, dir, tri, t_max));
                let lane_hit = (got.mask & (1 << lane) != 0).then(|| TriangleHit {
                    t: got.t[lane],
                    barycentrics: Vec2::new(got.u[lane], got.v[lane]),
                });
                let bits = |h: Option<TriangleHit>| {
                    h.map(|h| [h.t, h.barycentrics.x, h.barycentrics.y].map(f32::to_bits))
                };
                assert_eq!(
                    bits(lane_hit),
                    bits(reference),
                    "lane {lane} of {tris:?}, ray {origin} {dir}, t_max {t_max}"
                );
                hits += usize::from(reference.is_some());
                total += usize::from(lane < count);
            }
        }
        // The comparison means something only if many lanes hit (about 9% do: half the rays
        // aim at one of the 2.5 triangles of a block on average).
        assert!(hits > total / 20, "{hits} hits of {total}");
    }
}
