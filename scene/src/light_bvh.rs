//! [`LightBvh`]: a bounding volume hierarchy over one-sided emitters that chooses one for a light
//! sample in proportion to a bound of what it sends to the shading point (Conty Estevez & Kulla,
//! "Importance Sampling of Many Lights with Adaptive Tree Splitting", 2018; pbrt-v4's
//! `BVHLightSampler` and `LightBounds`).
//!
//! Each node bounds its emitters by an axis-aligned box, their total power `φ` and a cone of
//! their normals (axis, half-angle `θo`). The *importance* of a node at a point `p` with
//! receiver normal `n` ([`LightBounds::importance`]) is
//!
//! ```text
//! φ · cos θ′ · cos θ′ᵢ / max(d², r²)
//! ```
//!
//! where `d` is the distance from `p` to the box's centre, `r` the radius of the box's bounding
//! sphere, `θ′ = max(0, θw − θo − θb)` the smallest angle any emitter's normal can make with
//! the direction to `p` (`θw`: the cone axis against that direction, `θb`: the half-angle the
//! sphere subtends at `p`), and `θ′ᵢ = max(0, θi − θb)` the smallest angle the direction to
//! any emitter can make with `n`. Emission is one-sided (θe = π/2): a node whose `θ′ ≥ π/2` or
//! `θ′ᵢ ≥ π/2` is behind every emitter or the receiver, importance 0. Sampling descends from
//! the root, choosing each child with probability `importance / (sum of both)`; the probability
//! of a leaf is the product of the choices on its path ([`LightBvh::pmf`] walks the same path
//! with the same arithmetic, so it returns the sampled probability bit for bit).
//!
//! *Deviations from pbrt-v4, deliberate:*
//! * pbrt clamps `d²` by `|diagonal| / 2`, a length against a squared length; here by the
//!   bounding sphere's `r² = |diagonal|² / 4`, which keeps the importance scale-invariant (a
//!   scene scaled by 10⁶ chooses the same lights).
//! * pbrt takes `|cos θi|` at the receiver (its surfaces may transmit); furnace's BSDFs only
//!   reflect, so the receiver's cosine is one-sided: lights behind the surface get nothing.
//!   [`Vec3::ZERO`] as `n` leaves the receiver out (pbrt's convention for media).
//! * A point inside a node's bounding sphere gets `φ / r²` at once (every angle bound is 0
//!   there; pbrt forms them from a direction that is undefined at the centre).
//! * Trees deeper than 32 levels are cut by count below level 32, so that a path fits 64 bits.
//!
//! Build (pbrt's `buildBVH`): top-down; each node is split in the bucket (12 per axis over
//! the centroids) that minimises the summed cost `φ · M_Ω · area · K_r` of its two children,
//! `M_Ω` the orientation cone's solid-angle measure and `K_r` the node's aspect along the split
//! axis; one emitter per leaf.

use glam::{DVec3, Vec3};

/// The bounds of a set of one-sided emitters (each emitting into the hemisphere around its
/// normal): what [`LightBounds::importance`] needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightBounds {
    /// Lower corner of the box.
    pub lo: Vec3,
    /// Upper corner of the box.
    pub hi: Vec3,
    /// Total power, in any unit shared by every emitter (only ratios matter).
    pub phi: f32,
    /// Unit axis of the cone holding every emitter's normal.
    pub axis: Vec3,
    /// `cos θo` of that cone's half-angle (1: one normal; −1: any).
    pub cos_theta_o: f32,
}

/// `cos(max(0, a − b))` from the sines and cosines of `a` and `b` (pbrt's `cosSubClamped`).
#[inline]
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b { 1.0 } else { cos_a * cos_b + sin_a * sin_b }
}

/// `sin(max(0, a − b))` (pbrt's `sinSubClamped`).
#[inline]
fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b { 0.0 } else { sin_a * cos_b - cos_a * sin_b }
}

#[inline]
fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

impl LightBounds {
    /// The bounds of one triangle emitting `phi` from the front of `v0 v1 v2` (the side its
    /// winding's normal points to); `None` for a degenerate triangle (no normal).
    pub fn triangle(v0: Vec3, v1: Vec3, v2: Vec3, phi: f32) -> Option<Self> {
        let axis = (v1 - v0).cross(v2 - v0).try_normalize()?;
        Some(Self { lo: v0.min(v1).min(v2), hi: v0.max(v1).max(v2), phi, axis, cos_theta_o: 1.0 })
    }

    /// A bound of the power these emitters send to `p`, a point whose receiving side is
    /// `n` (unit; [`Vec3::ZERO`]: any side), up to a constant shared by every node; 0 when none
    /// of them can light `p` (the formula and its deviations from pbrt-v4 open
    /// `scene/src/light_bvh.rs`). The WGSL twin is
    /// `light_bvh_importance` in furnace-gpu's `light_bvh.wgsl`.
    pub fn importance(&self, p: Vec3, n: Vec3) -> f32 {
        let centre = 0.5 * (self.lo + self.hi);
        let half = 0.5 * (self.hi - self.lo);
        let r2 = half.dot(half);
        let to_p = p - centre;
        let dist2 = to_p.dot(to_p);
        if !(dist2 > r2) {
            // Inside the bounding sphere every direction is possible: no angle bound.
            return if r2 > 0.0 { self.phi / r2 } else { 0.0 };
        }
        // One division and one square root serve every ratio below.
        let inv_dist2 = 1.0 / dist2;
        let wi = to_p * (1.0 / dist2.sqrt());
        // θb: the half-angle the bounding sphere subtends at p.
        let sin2_b = r2 * inv_dist2;
        let sin_b = sin2_b.sqrt();
        let cos_b = safe_sqrt(1.0 - sin2_b);
        // θ′ = max(0, θw − θo − θb): the emitters' normals against the direction to p.
        let cos_w = self.axis.dot(wi);
        let sin_w = safe_sqrt(1.0 - cos_w * cos_w);
        // A leaf's cone is one normal (cos θo = 1): no square root.
        let sin_o =
            if self.cos_theta_o >= 1.0 { 0.0 } else { safe_sqrt(1.0 - self.cos_theta_o * self.cos_theta_o) };
        let cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, self.cos_theta_o);
        let sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, self.cos_theta_o);
        let cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
        if !(cos_p > 0.0) {
            return 0.0; // p is behind every emitter (θe = π/2)
        }
        let mut importance = self.phi * cos_p * inv_dist2;
        if n != Vec3::ZERO {
            // θ′ᵢ = max(0, θi − θb): the receiver's normal against the direction to the lights.
            let cos_i = -wi.dot(n);
            let sin_i = safe_sqrt(1.0 - cos_i * cos_i);
            let cos_pi = cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
            if !(cos_pi > 0.0) {
                return 0.0; // every emitter is behind the receiver
            }
            importance *= cos_pi;
        }
        importance
    }

    /// The bounds of both sets (f64 where the cone union needs it).
    fn union(&self, other: &Self) -> Self {
        let (axis, cos_theta_o) = cone_union(self.axis, self.cos_theta_o, other.axis, other.cos_theta_o);
        Self {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
            phi: (f64::from(self.phi) + f64::from(other.phi)) as f32,
            axis,
            cos_theta_o,
        }
    }

    fn centroid(&self) -> Vec3 {
        0.5 * (self.lo + self.hi)
    }
}

/// The smallest cone holding cones `(a, cos_a)` and `(b, cos_b)` (pbrt's `Union(DirectionCone,
/// DirectionCone)`), in f64, its half-angle widened by 10⁻⁶ rad against the rounding of the
/// `f32` result (a cone that misses a normal makes the importance less conservative: the
/// estimator stays unbiased, since [`LightBvh::pmf`] agrees with the sampling, only noisier).
fn cone_union(a: Vec3, cos_a: f32, b: Vec3, cos_b: f32) -> (Vec3, f32) {
    use std::f64::consts::PI;
    if a == b {
        // Same axis (emitters facing one way, the common case): the wider cone, no trigonometry.
        return (a, cos_a.min(cos_b));
    }
    let (wa, wb) = (a.as_dvec3(), b.as_dvec3());
    let theta_a = f64::from(cos_a).clamp(-1.0, 1.0).acos();
    let theta_b = f64::from(cos_b).clamp(-1.0, 1.0).acos();
    let theta_d = angle_between(wa, wb);
    let widen = |w: DVec3, theta: f64| (w.as_vec3(), (theta + 1e-6).min(PI).cos() as f32);
    if (theta_d + theta_b).min(PI) <= theta_a {
        return (a, cos_a);
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return (b, cos_b);
    }
    let theta_o = (theta_a + theta_d + theta_b) / 2.0;
    if theta_o >= PI {
        return (Vec3::Z, -1.0);
    }
    // Rotate a's axis towards b's by θo − θa about a × b.
    let wr = wa.cross(wb);
    if wr.length_squared() == 0.0 {
        return (Vec3::Z, -1.0);
    }
    let w = rotate(wa, wr.normalize(), theta_o - theta_a);
    widen(w.normalize(), theta_o)
}

/// The angle between unit vectors, precise near 0 and π (pbrt's `AngleBetween`).
fn angle_between(a: DVec3, b: DVec3) -> f64 {
    if a.dot(b) < 0.0 {
        std::f64::consts::PI - 2.0 * ((a + b).length() / 2.0).clamp(-1.0, 1.0).asin()
    } else {
        2.0 * ((b - a).length() / 2.0).clamp(-1.0, 1.0).asin()
    }
}

/// `v` rotated by `angle` about the unit `axis` (Rodrigues).
fn rotate(v: DVec3, axis: DVec3, angle: f64) -> DVec3 {
    let (s, c) = angle.sin_cos();
    v * c + axis.cross(v) * s + axis * axis.dot(v) * (1.0 - c)
}

/// pbrt's `LightBVHNode`: the bounds of a subtree and where its children are. A node's first
/// child is the next node; `child` is the second child's index, or, in a leaf ([`LEAF`] set),
/// the item it holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightBvhNode {
    /// The bounds of every item below.
    pub bounds: LightBounds,
    /// Second child's index, or [`LEAF`] | item.
    pub child: u32,
}

/// [`LightBvhNode::child`]: the node is a leaf holding the item in the other bits.
pub const LEAF: u32 = 1 << 31;

/// Levels below which the build splits by count (so every path fits the 64-bit trail).
const COUNT_SPLIT_DEPTH: u32 = 32;

/// Buckets per axis of the build's split search (pbrt's 12).
const BUCKETS: usize = 12;

/// A light BVH over items `0 … n−1` given by their [`LightBounds`] (the importance, the
/// sampling and the build are described at the top of `scene/src/light_bvh.rs`).
///
/// ```
/// use furnace_scene::{LightBounds, LightBvh};
/// use glam::Vec3;
/// // Two unit triangles facing down at heights 1 and 10, equally powerful.
/// let tri = |h: f32| {
///     LightBounds::triangle(Vec3::new(0.0, h, 0.0), Vec3::new(1.0, h, 0.0), Vec3::new(0.0, h, 1.0), 1.0)
/// };
/// let bvh = LightBvh::new(&[tri(1.0).unwrap(), tri(10.0).unwrap()]).unwrap();
/// let (p, n) = (Vec3::new(0.3, 0.0, 0.3), Vec3::Y);
/// // The near light is far more likely; the pmf is the sampled probability.
/// let (item, pmf) = bvh.sample(p, n, 0.1).unwrap();
/// assert_eq!(item, 0);
/// assert!(pmf > 0.9);
/// assert_eq!(bvh.pmf(p, n, 0), pmf);
/// assert!((bvh.pmf(p, n, 0) + bvh.pmf(p, n, 1) - 1.0).abs() < 1e-6);
/// ```
#[derive(Debug, Clone)]
pub struct LightBvh {
    nodes: Vec<LightBvhNode>,
    /// Per item, the choices from the root to its leaf: bit `k` set = second child at level `k`.
    trails: Vec<u64>,
    depth: u32,
}

impl LightBvh {
    /// The BVH of `items` (one leaf each); `None` when there are none or more than 2³¹. Items of
    /// zero or non-finite power are never chosen (their leaves have importance 0).
    pub fn new(items: &[LightBounds]) -> Option<Self> {
        if items.is_empty() || items.len() >= LEAF as usize {
            return None;
        }
        let clean = |b: &LightBounds| LightBounds {
            phi: if b.phi.is_finite() && b.phi > 0.0 { b.phi } else { 0.0 },
            ..*b
        };
        let mut order: Vec<(u32, LightBounds)> =
            items.iter().enumerate().map(|(i, b)| (i as u32, clean(b))).collect();
        let mut bvh =
            Self { nodes: Vec::with_capacity(2 * items.len()), trails: vec![0; items.len()], depth: 0 };
        bvh.build(&mut order, 0, 0);
        Some(bvh)
    }

    /// Builds the subtree of `items` at `depth` with path `trail`; returns its node's index.
    fn build(&mut self, items: &mut [(u32, LightBounds)], depth: u32, trail: u64) -> usize {
        self.depth = self.depth.max(depth + 1);
        let index = self.nodes.len();
        if let [(item, bounds)] = items {
            self.nodes.push(LightBvhNode { bounds: *bounds, child: LEAF | *item });
            self.trails[*item as usize] = trail;
            return index;
        }
        let bounds = items[1..].iter().fold(items[0].1, |acc, (_, b)| acc.union(b));
        let mid = split(items, &bounds, depth);
        self.nodes.push(LightBvhNode { bounds, child: 0 });
        let (first, second) = items.split_at_mut(mid);
        self.build(first, depth + 1, trail);
        let second_index = self.build(second, depth + 1, trail | (1u64 << depth));
        self.nodes[index].child = second_index as u32;
        index
    }

    /// The nodes, depth first (a node's first child follows it).
    pub fn nodes(&self) -> &[LightBvhNode] {
        &self.nodes
    }

    /// Per item, its path from the root: bit `k` set means the second child at level `k`.
    pub fn trails(&self) -> &[u64] {
        &self.trails
    }

    /// Number of levels (1: the root is the only leaf).
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// Chooses an item for a point `p` with receiving side `n` ([`LightBounds::importance`]) by
    /// one uniform number `u ∈ [0, 1)`, rescaled at each level (pbrt's `SampleDiscrete`):
    /// `(item, probability)`, or `None` when no item can light `p`.
    pub fn sample(&self, p: Vec3, n: Vec3, mut u: f32) -> Option<(usize, f32)> {
        let mut index = 0;
        let mut pmf = 1.0f32;
        loop {
            let node = &self.nodes[index];
            if node.child & LEAF != 0 {
                // A root leaf was not weighed against a sibling: check it can light p.
                return (index > 0 || node.bounds.importance(p, n) > 0.0)
                    .then_some(((node.child & !LEAF) as usize, pmf));
            }
            let (second, c0, c1, sum) = self.children(index, p, n);
            if !(sum > 0.0) {
                return None;
            }
            let p0 = c0 / sum;
            if u < p0 {
                u = (u / p0).min(ONE_MINUS_EPSILON);
                pmf *= c0 / sum;
                index += 1;
            } else {
                u = ((u - p0) / (1.0 - p0)).min(ONE_MINUS_EPSILON);
                pmf *= c1 / sum;
                index = second;
            }
        }
    }

    /// Interior node `index`'s second child and both children's importances at `p`, `n`, with
    /// their sum: one level of a descent, shared by [`LightBvh::sample`] and [`LightBvh::pmf`]
    /// so that both form the same numbers.
    fn children(&self, index: usize, p: Vec3, n: Vec3) -> (usize, f32, f32, f32) {
        let second = self.nodes[index].child as usize;
        let c0 = self.nodes[index + 1].bounds.importance(p, n);
        let c1 = self.nodes[second].bounds.importance(p, n);
        (second, c0, c1, c0 + c1)
    }

    /// The probability with which [`LightBvh::sample`] chooses `item` at `p`, `n` (0 when it
    /// cannot), formed by the same arithmetic along the item's path.
    pub fn pmf(&self, p: Vec3, n: Vec3, item: usize) -> f32 {
        let Some(&trail) = self.trails.get(item) else { return 0.0 };
        let mut index = 0;
        let mut pmf = 1.0f32;
        let mut level = 0;
        loop {
            let node = &self.nodes[index];
            if node.child & LEAF != 0 {
                return if index > 0 || node.bounds.importance(p, n) > 0.0 { pmf } else { 0.0 };
            }
            let (second, c0, c1, sum) = self.children(index, p, n);
            if !(sum > 0.0) {
                return 0.0;
            }
            if trail >> level & 1 == 0 {
                pmf *= c0 / sum;
                index += 1;
            } else {
                pmf *= c1 / sum;
                index = second;
            }
            level += 1;
        }
    }
}

/// The largest `f32` below 1.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// pbrt's `EvaluateCost`: the cost of a child `b` of a node of box `node_lo..node_hi` split
/// along `axis`.
fn cost(b: &LightBounds, extent: DVec3, axis: usize) -> f64 {
    use std::f64::consts::{FRAC_PI_2, PI};
    let theta_o = f64::from(b.cos_theta_o).clamp(-1.0, 1.0).acos();
    let theta_w = (theta_o + FRAC_PI_2).min(PI);
    let sin_o = theta_o.sin();
    let m_omega = 2.0 * PI * (1.0 - theta_o.cos())
        + FRAC_PI_2
            * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o
                + theta_o.cos());
    let k_r = extent.max_element() / extent[axis];
    let d = (b.hi - b.lo).as_dvec3();
    let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
    f64::from(b.phi) * m_omega * k_r * area
}

/// Orders `items` so that the first `mid` go to the first child; returns `mid` (0 < mid < len).
fn split(items: &mut [(u32, LightBounds)], bounds: &LightBounds, depth: u32) -> usize {
    let n = items.len();
    let (mut clo, mut chi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for (_, b) in items.iter() {
        clo = clo.min(b.centroid());
        chi = chi.max(b.centroid());
    }
    let widest = (chi - clo).max_position();
    let by_count = |items: &mut [(u32, LightBounds)], axis: usize| {
        items.select_nth_unstable_by(n / 2, |a, b| a.1.centroid()[axis].total_cmp(&b.1.centroid()[axis]));
        n / 2
    };
    if depth >= COUNT_SPLIT_DEPTH {
        return by_count(items, widest);
    }
    let extent = (bounds.hi - bounds.lo).as_dvec3();
    let bucket_of = |c: f32, axis: usize| {
        let t = (c - clo[axis]) / (chi[axis] - clo[axis]);
        ((BUCKETS as f32 * t) as usize).min(BUCKETS - 1)
    };
    let mut best: Option<(f64, usize, usize)> = None;
    for axis in 0..3 {
        if !(chi[axis] > clo[axis]) || !(extent[axis] > 0.0) {
            continue;
        }
        let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
        for (_, b) in items.iter() {
            let k = bucket_of(b.centroid()[axis], axis);
            buckets[k] = Some(buckets[k].map_or(*b, |acc| acc.union(b)));
        }
        for split_after in 0..BUCKETS - 1 {
            let merge = |range: std::ops::Range<usize>| {
                buckets[range]
                    .iter()
                    .flatten()
                    .fold(None, |acc: Option<LightBounds>, b| Some(acc.map_or(*b, |a| a.union(b))))
            };
            let (Some(below), Some(above)) = (merge(0..split_after + 1), merge(split_after + 1..BUCKETS))
            else {
                continue;
            };
            let c = cost(&below, extent, axis) + cost(&above, extent, axis);
            if best.is_none_or(|(bc, _, _)| c < bc) {
                best = Some((c, axis, split_after));
            }
        }
    }
    let Some((_, axis, split_after)) = best else { return by_count(items, widest) };
    // Partition: items whose bucket is at or below `split_after` first.
    let mut mid = 0;
    for i in 0..n {
        if bucket_of(items[i].1.centroid()[axis], axis) <= split_after {
            items.swap(i, mid);
            mid += 1;
        }
    }
    if mid == 0 || mid == n { by_count(items, axis) } else { mid }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rng(seed: &mut u64) -> f32 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (*seed >> 40) as f32 / (1u64 << 24) as f32
    }

    fn random_lights(n: usize, seed: u64) -> Vec<LightBounds> {
        let mut s = seed;
        (0..n)
            .filter_map(|_| {
                let c = Vec3::new(rng(&mut s), rng(&mut s), rng(&mut s)) * 10.0;
                let e = |s: &mut u64| Vec3::new(rng(s), rng(s), rng(s)) - 0.5;
                LightBounds::triangle(c, c + e(&mut s), c + e(&mut s), 0.01 + rng(&mut s).powi(4) * 100.0)
            })
            .collect()
    }

    /// The probabilities `sample` returns are `pmf`'s, bit for bit; the pmfs sum to the
    /// probability that `sample` chooses anything (below 1 where a node's bound is positive but
    /// both its children's are 0: that share of the samples finds no light), measured with
    /// 4000 stratified `u` (the stratification bounds the difference by 1/4000 per item).
    #[test]
    fn pmfs_are_the_sampled_probabilities() {
        let strata = 4000;
        for n in [1, 2, 3, 17, 500] {
            let lights = random_lights(n, n as u64);
            let bvh = LightBvh::new(&lights).unwrap();
            let mut s = 99;
            for _ in 0..100 {
                let p = Vec3::new(rng(&mut s), rng(&mut s), rng(&mut s)) * 14.0 - 2.0;
                let normal = (Vec3::new(rng(&mut s), rng(&mut s), rng(&mut s)) - 0.5).normalize();
                let total: f64 = (0..lights.len()).map(|i| f64::from(bvh.pmf(p, normal, i))).sum();
                let mut chosen = 0;
                for k in 0..strata {
                    if let Some((item, pmf)) = bvh.sample(p, normal, (k as f32 + 0.5) / strata as f32) {
                        assert_eq!(pmf.to_bits(), bvh.pmf(p, normal, item).to_bits());
                        chosen += 1;
                    }
                }
                let found = f64::from(chosen) / f64::from(strata);
                assert!(total <= 1.0 + 1e-5, "n {n}: Σ pmf = {total}");
                assert!(
                    (total - found).abs() <= 1e-5 + n as f64 / f64::from(strata),
                    "n {n}: Σ pmf {total}, found {found}"
                );
            }
        }
    }

    /// Importance is conservative: a node is 0 at `p` only where no emitter below it can light
    /// `p` — checked for every node against its box (all of it behind the receiver's plane)
    /// and, for single-normal nodes, the emitters' plane (`p` behind every point of the box).
    #[test]
    fn zero_importance_only_where_no_emitter_can_light() {
        let lights = random_lights(300, 7);
        let bvh = LightBvh::new(&lights).unwrap();
        let (mut checked, mut unchecked) = (0, 0);
        let mut s = 5;
        for _ in 0..2000 {
            let p = Vec3::new(rng(&mut s), rng(&mut s), rng(&mut s)) * 16.0 - 3.0;
            let normal = (Vec3::new(rng(&mut s), rng(&mut s), rng(&mut s)) - 0.5).normalize();
            for node in bvh.nodes() {
                if node.bounds.importance(p, normal) > 0.0 {
                    continue;
                }
                let corners = (0..8).map(|k| {
                    Vec3::new(
                        if k & 1 == 0 { node.bounds.lo.x } else { node.bounds.hi.x },
                        if k & 2 == 0 { node.bounds.lo.y } else { node.bounds.hi.y },
                        if k & 4 == 0 { node.bounds.lo.z } else { node.bounds.hi.z },
                    )
                });
                // Justified: the whole box behind the receiver's plane, or (one normal) p behind
                // the emitters' plane through every corner. Cones of several normals are not
                // checked here (counted).
                let behind_receiver = corners.clone().all(|c| (c - p).dot(normal) <= 1e-4 * (c - p).length());
                let behind_emitters =
                    corners.clone().all(|c| (p - c).dot(node.bounds.axis) <= 1e-4 * (c - p).length());
                if node.bounds.cos_theta_o == 1.0 {
                    checked += 1;
                    assert!(behind_receiver || behind_emitters, "node {node:?} is 0 at {p} but can light it");
                } else if !behind_receiver {
                    unchecked += 1;
                }
            }
        }
        assert!(checked > 1000, "{checked} zero nodes checked, {unchecked} not");
    }

    /// The choice frequencies follow the pmf (chi-square, 10⁵ stratified `u`, 40 items; the
    /// stratified draw makes the counts nearly exact, so the bound is tight).
    #[test]
    fn sampling_follows_the_pmf() {
        let lights = random_lights(40, 3);
        let bvh = LightBvh::new(&lights).unwrap();
        let (p, normal) = (Vec3::new(5.0, 12.0, 5.0), Vec3::NEG_Y);
        let n = 100_000;
        let mut counts = vec![0u32; lights.len()];
        for k in 0..n {
            if let Some((item, _)) = bvh.sample(p, normal, (k as f32 + 0.5) / n as f32) {
                counts[item] += 1;
            }
        }
        for (i, &c) in counts.iter().enumerate() {
            let expected = f64::from(bvh.pmf(p, normal, i)) * f64::from(n);
            // Stratified u: each count is within the levels' rounding of its expectation.
            assert!(
                (f64::from(c) - expected).abs() <= 2.0 + 1e-3 * expected,
                "item {i}: {c} vs {expected:.1}"
            );
        }
    }

    /// A deep, skewed set (powers over 30 decades along a line) stays within 64 levels.
    #[test]
    fn skewed_powers_stay_within_the_trail() {
        let lights: Vec<LightBounds> = (0..5000)
            .filter_map(|i| {
                let x = i as f32;
                LightBounds::triangle(
                    Vec3::new(x, 0.0, 0.0),
                    Vec3::new(x, 0.0, 1.0),
                    Vec3::new(x + 0.5, 0.0, 0.0),
                    10f32.powf((i % 60) as f32 / 2.0 - 15.0),
                )
            })
            .collect();
        let bvh = LightBvh::new(&lights).unwrap();
        assert!(bvh.depth() <= 64, "depth {}", bvh.depth());
        // Above the lights (they face +y), looking down at them.
        let p = Vec3::new(2500.0, 3.0, 0.5);
        let total: f64 = (0..lights.len()).map(|i| f64::from(bvh.pmf(p, Vec3::NEG_Y, i))).sum();
        assert!((total - 1.0).abs() < 1e-4, "{total}");
    }

    /// Scaling the scene does not change the choice (the d² clamp is a squared length), from
    /// 10⁻¹² to 10¹² (the range furnace renders, `docs/stability.md`): pmfs within 10⁻⁴ of the
    /// unit scene's (f32 rounding of the scaled bounds; a tree that split differently would
    /// differ by far more).
    #[test]
    fn importance_is_scale_invariant() {
        let lights = random_lights(50, 11);
        let a = LightBvh::new(&lights).unwrap();
        let p = Vec3::new(3.0, -1.0, 4.0);
        for scale in [1e-12f32, 1e-6, 1e6, 1e12] {
            let scaled: Vec<LightBounds> = lights
                .iter()
                .map(|b| LightBounds { lo: b.lo * scale, hi: b.hi * scale, phi: b.phi * scale * scale, ..*b })
                .collect();
            let b = LightBvh::new(&scaled).unwrap();
            for i in 0..lights.len() {
                let (pa, pb) = (a.pmf(p, Vec3::Y, i), b.pmf(p * scale, Vec3::Y, i));
                assert!((pa - pb).abs() <= 1e-4 * pa.max(1e-6), "scale {scale:e}, item {i}: {pa} vs {pb}");
            }
        }
    }
}
