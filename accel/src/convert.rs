//! The BVH2 → CWBVH conversion of a large tree in parallel.
//!
//! obvhs's conversion (`bvh2_to_cwbvh`: a cost table over every BVH2 node, then the 8-wide nodes
//! top-down) is serial; on a tree of 10⁷ triangles it takes a third of the build and does not
//! shrink with cores. Here the BVH2 is cut three levels below its root: each of the (up to
//! eight) subtrees below the cut is copied out and converted by obvhs on its own, in parallel,
//! and the root is made here, with obvhs's quantisation and child order, from the subtrees' roots
//! and any leaf above the cut. The subtrees' nodes are appended after the root's, their indices
//! moved; each subtree's root is stored in the root's block of children (a CWBVH node's internal
//! children are contiguous). The tree differs from obvhs's own only where its cost table would
//! have made the root otherwise; traced, a 10⁶-triangle interior runs as fast (docs/gltf.md).

use glam::{UVec3, Vec3A};
use obvhs::{
    PerComponent,
    bvh2::{Bvh2, node::Bvh2Node},
    cwbvh::{CwBvh, bvh2_to_cwbvh::bvh2_to_cwbvh, node::CwBvhNode},
};
use rayon::prelude::*;

/// The BVH2 depth at which the tree is cut: up to 2³ subtrees, the 8-wide root's children. A cut
/// off the 3-level boundaries of 8-wide nodes leaves the top's lowest nodes half filled, and
/// deeper cuts take the cost-driven collapse away from more of the tree: cut at 6 or 8, a
/// 10⁶-triangle interior traced 5 % and 11 % slower; at 3, as fast as obvhs's own conversion.
const CUT_DEPTH: usize = 3;

/// Trees of fewer primitives keep obvhs's serial conversion (they convert in milliseconds).
const PARALLEL_PRIMITIVES: usize = 1 << 18;

/// The 8-bit quantisation's step: obvhs's `1 / 255`.
const DENOM: f32 = 1.0 / 255.0;

/// `bvh2_to_cwbvh(bvh2, max_prims_per_leaf, true, false)`, in parallel for a large tree.
pub(crate) fn to_cwbvh(bvh2: &Bvh2, max_prims_per_leaf: u32) -> CwBvh {
    to_cwbvh_cut(bvh2, max_prims_per_leaf, CUT_DEPTH, PARALLEL_PRIMITIVES)
}

/// [`to_cwbvh`] cut at `cut_depth`, in parallel from `parallel_primitives` primitives.
pub(crate) fn to_cwbvh_cut(
    bvh2: &Bvh2,
    max_prims_per_leaf: u32,
    cut_depth: usize,
    parallel_primitives: usize,
) -> CwBvh {
    let root_is_leaf = bvh2.nodes.first().is_none_or(Bvh2Node::is_leaf);
    if bvh2.primitive_indices.len() < parallel_primitives || root_is_leaf || cut_depth == 0 {
        return bvh2_to_cwbvh(bvh2, max_prims_per_leaf, true, false);
    }
    let mut roots = Vec::new();
    collect_cut(bvh2, 0, 0, cut_depth, &mut roots);
    let subtrees: Vec<CwBvh> = roots
        .par_iter()
        .map(|&root| bvh2_to_cwbvh(&subtree(bvh2, root), max_prims_per_leaf, true, false))
        .collect();
    let cut_of = roots.iter().enumerate().map(|(k, &root)| (root, k)).collect();
    let mut top = Top {
        bvh2,
        cut_depth,
        cut_of,
        nodes: vec![CwBvhNode::default()],
        primitives: Vec::new(),
        cuts: Vec::new(),
    };
    top.node(0, 0, 0);
    let Top { mut nodes, mut primitives, cuts, .. } = top;
    // Each subtree's nodes after the top's (its root in its parent's block, the rest appended),
    // its primitives after the top's leaves' primitives.
    let mut base_node = vec![0u32; subtrees.len()];
    let mut base_primitive = vec![0u32; subtrees.len()];
    let (mut n, mut p) = (nodes.len() as u32, primitives.len() as u32);
    for (k, s) in subtrees.iter().enumerate() {
        // Node i ≥ 1 of the subtree lands at base + i − 1.
        base_node[k] = n;
        base_primitive[k] = p;
        n += s.nodes.len() as u32 - 1;
        p += s.primitive_indices.len() as u32;
    }
    let moved = |node: &CwBvhNode, k: usize| {
        let mut node = *node;
        node.child_base_idx = node.child_base_idx + base_node[k] - 1;
        node.primitive_base_idx += base_primitive[k];
        node
    };
    for &(slot, k) in &cuts {
        nodes[slot] = moved(&subtrees[k].nodes[0], k);
    }
    nodes.reserve(n as usize - nodes.len());
    primitives.reserve(p as usize - primitives.len());
    for (k, s) in subtrees.iter().enumerate() {
        nodes.extend(s.nodes[1..].iter().map(|node| moved(node, k)));
        primitives.extend_from_slice(&s.primitive_indices);
    }
    CwBvh {
        nodes,
        primitive_indices: primitives,
        total_aabb: *bvh2.nodes[0].aabb(),
        exact_node_aabbs: None,
        uses_spatial_splits: bvh2.uses_spatial_splits,
    }
}

/// The roots of the subtrees below the cut, in depth-first order: the inner nodes at
/// `cut_depth` (the top's leaves stay in the top).
fn collect_cut(bvh2: &Bvh2, index: usize, depth: usize, cut_depth: usize, roots: &mut Vec<usize>) {
    let node = &bvh2.nodes[index];
    if node.is_leaf() {
        return;
    }
    if depth == cut_depth {
        roots.push(index);
        return;
    }
    let first = node.first_index as usize;
    collect_cut(bvh2, first, depth + 1, cut_depth, roots);
    collect_cut(bvh2, first + 1, depth + 1, cut_depth, roots);
}

/// The subtree at `root` as a BVH2 of its own: its nodes renumbered from 0 (siblings kept
/// adjacent) and its leaves' primitives, which keep their indices into the whole input.
fn subtree(bvh2: &Bvh2, root: usize) -> Bvh2 {
    let mut nodes = vec![Bvh2Node::default()];
    let mut primitive_indices = Vec::new();
    let mut stack = vec![(root, 0usize)];
    while let Some((from, to)) = stack.pop() {
        let node = bvh2.nodes[from];
        if node.is_leaf() {
            let first = primitive_indices.len() as u32;
            let range = node.first_index as usize..(node.first_index + node.prim_count) as usize;
            primitive_indices.extend_from_slice(&bvh2.primitive_indices[range]);
            nodes[to] = Bvh2Node::new(*node.aabb(), node.prim_count, first);
        } else {
            let children = nodes.len();
            nodes.extend([Bvh2Node::default(); 2]);
            nodes[to] = Bvh2Node::new(*node.aabb(), 0, children as u32);
            stack.push((node.first_index as usize, children));
            stack.push((node.first_index as usize + 1, children + 1));
        }
    }
    Bvh2 {
        nodes,
        primitive_indices,
        max_depth: bvh2.max_depth,
        uses_spatial_splits: bvh2.uses_spatial_splits,
        ..Bvh2::default()
    }
}

/// The 8-wide nodes above the cut, made top-down.
struct Top<'a> {
    bvh2: &'a Bvh2,
    cut_depth: usize,
    /// Each subtree root's index in the cut's order.
    cut_of: std::collections::HashMap<usize, usize>,
    nodes: Vec<CwBvhNode>,
    primitives: Vec<u32>,
    /// Where each subtree's root goes: its slot in `nodes`, and its index in the cut's order.
    cuts: Vec<(usize, usize)>,
}

/// A child of a top node: a BVH2 node and its depth.
#[derive(Clone, Copy)]
struct Child {
    index: usize,
    depth: usize,
}

impl Top<'_> {
    /// Whether `c` is an inner node above the cut (made here), not a leaf or a subtree's root.
    fn is_top(&self, c: Child) -> bool {
        c.depth < self.cut_depth && !self.bvh2.nodes[c.index].is_leaf()
    }

    /// Makes the 8-wide node at `slot` for the BVH2 inner node `index` (at `depth`), then its
    /// internal children above the cut; a subtree root's slot is recorded in `cuts`.
    fn node(&mut self, slot: usize, index: usize, depth: usize) {
        let first = self.bvh2.nodes[index].first_index as usize;
        let mut children =
            vec![Child { index: first, depth: depth + 1 }, Child { index: first + 1, depth: depth + 1 }];
        // Open the largest top child until there are eight.
        while children.len() < 8 {
            let largest = (0..children.len())
                .filter(|&k| self.is_top(children[k]))
                .max_by(|&a, &b| self.half_area(children[a]).total_cmp(&self.half_area(children[b])));
            let Some(k) = largest else { break };
            let c = children.swap_remove(k);
            let first = self.bvh2.nodes[c.index].first_index as usize;
            children.push(Child { index: first, depth: c.depth + 1 });
            children.push(Child { index: first + 1, depth: c.depth + 1 });
        }
        let aabb = *self.bvh2.nodes[index].aabb();
        let slots = ordered(self.bvh2, &aabb, &children);
        let mut node = CwBvhNode { p: aabb.min.into(), ..CwBvhNode::default() };
        // obvhs's quantisation: a power-of-two step per axis, boxes rounded outwards.
        let e = ((aabb.max - aabb.min).max(Vec3A::splat(1e-20)) * DENOM).log2().ceil().exp2();
        let rcp_e = 1.0 / e;
        let e: UVec3 = e.per_comp(|c: f32| c.to_bits() >> 23);
        node.e = [e.x as u8, e.y as u8, e.z as u8];
        node.primitive_base_idx = self.primitives.len() as u32;
        node.child_base_idx = self.nodes.len() as u32;
        let mut internal = Vec::new();
        for (i, c) in slots.iter().enumerate() {
            let Some(c) = c else { continue };
            let b = self.bvh2.nodes[c.index];
            let lo = ((b.aabb().min - aabb.min) * rcp_e).floor().clamp(Vec3A::ZERO, Vec3A::splat(255.0));
            let hi = ((b.aabb().max - aabb.min) * rcp_e).ceil().clamp(Vec3A::ZERO, Vec3A::splat(255.0));
            node.child_min_x[i] = lo.x as u8;
            node.child_min_y[i] = lo.y as u8;
            node.child_min_z[i] = lo.z as u8;
            node.child_max_x[i] = hi.x as u8;
            node.child_max_y[i] = hi.y as u8;
            node.child_max_z[i] = hi.z as u8;
            if b.is_leaf() {
                // A BVH2 leaf holds one primitive (as obvhs's conversion requires).
                let offset = self.primitives.len() as u32 - node.primitive_base_idx;
                node.child_meta[i] = offset as u8 | 0b0010_0000;
                self.primitives.push(self.bvh2.primitive_indices[b.first_index as usize]);
            } else {
                node.imask |= 1 << i;
                node.child_meta[i] = (24 + i as u8) | 0b0010_0000;
                internal.push(*c);
            }
        }
        let base = self.nodes.len();
        self.nodes.resize(base + internal.len(), CwBvhNode::default());
        self.nodes[slot] = node;
        for (offset, c) in internal.into_iter().enumerate() {
            if self.is_top(c) {
                self.node(base + offset, c.index, c.depth);
            } else {
                self.cuts.push((base + offset, self.cut_of[&c.index]));
            }
        }
    }

    fn half_area(&self, c: Child) -> f32 {
        self.bvh2.nodes[c.index].aabb().half_area()
    }
}

/// `children` in the 8 slots by obvhs's rule: slot `s` stands for the ray octant whose signs are
/// its bits (x: 4, y: 2, z: 1, set for negative), and the child whose centre lies farthest
/// against that direction, the one such a ray meets first, takes it (greedily, cheapest pair
/// first: what `order_children` does). The traversal visits a node's children in slot order
/// for the ray's octant, so nearer children are tested first and cull the farther ones.
fn ordered(bvh2: &Bvh2, parent: &obvhs::aabb::Aabb, children: &[Child]) -> [Option<Child>; 8] {
    let centre = parent.center();
    let direction = |s: usize| {
        let sign = |bit: usize| if s & bit != 0 { -1.0 } else { 1.0 };
        Vec3A::new(sign(4), sign(2), sign(1))
    };
    let cost = |c: &Child, s: usize| direction(s).dot(bvh2.nodes[c.index].aabb().center() - centre);
    let mut slots = [None; 8];
    let mut assigned = vec![false; children.len()];
    loop {
        let mut best: Option<(f32, usize, usize)> = None;
        for (k, c) in children.iter().enumerate() {
            if assigned[k] {
                continue;
            }
            for (s, slot) in slots.iter().enumerate() {
                let v = cost(c, s);
                if slot.is_none() && best.is_none_or(|(b, _, _)| v < b) {
                    best = Some((v, k, s));
                }
            }
        }
        let Some((_, k, s)) = best else { break };
        assigned[k] = true;
        slots[s] = Some(children[k]);
    }
    slots
}

#[cfg(test)]
mod tests {
    use super::*;
    use obvhs::BvhBuildParams;
    use obvhs::ray::{Ray, RayHit};
    use obvhs::triangle::Triangle;

    /// `n` small triangles scattered in a cube, from a fixed seed.
    fn soup(n: usize) -> Vec<Triangle> {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n)
            .map(|_| {
                let c = Vec3A::new(next(), next(), next()) * 100.0;
                let mut v = || c + Vec3A::new(next(), next(), next()) * 2.0 - Vec3A::ONE;
                Triangle { v0: v(), v1: v(), v2: v() }
            })
            .collect()
    }

    /// Cut at several depths, the parallel conversion gives a CWBVH obvhs's validator accepts
    /// (every node and primitive reached once, every child inside its quantised box) and the
    /// same closest hit as obvhs's serial conversion, to the bit, for every one of 4 000 rays
    /// (the same triangles are tested with the same arithmetic, only in another order; the
    /// soup is random, so two triangles at one distance along a ray do not occur).
    #[test]
    fn the_parallel_conversion_traces_as_the_serial_one() {
        let tris = soup(40_000);
        let bvh2 = crate::build::build_ploc(&tris, &BvhBuildParams::medium_build());
        let serial = bvh2_to_cwbvh(&bvh2, 3, true, false);
        let closest = |bvh: &CwBvh, ray: Ray| {
            let mut hit = RayHit::none();
            bvh.ray_traverse(ray, &mut hit, |r, slot| {
                tris[bvh.primitive_indices[slot] as usize].intersect(r)
            });
            (
                hit.t.to_bits(),
                (hit.t < f32::INFINITY).then(|| bvh.primitive_indices[hit.primitive_id as usize]),
            )
        };
        let mut rng = soup(4_000).into_iter();
        for cut in [1, 3, 6, 40] {
            let parallel = to_cwbvh_cut(&bvh2, 3, cut, 0);
            parallel.validate(&tris, false);
            let mut sorted = parallel.primitive_indices.clone();
            sorted.sort_unstable();
            assert!(
                sorted.iter().enumerate().all(|(i, &p)| p as usize == i),
                "cut {cut}: every primitive once"
            );
            let mut hits = 0;
            for _ in 0..1_000 {
                let t = rng.next().unwrap();
                let (o, d) = (t.v0 * 1.2 - Vec3A::splat(10.0), (t.v1 - t.v2).normalize());
                let ray = Ray::new_inf(o, d);
                let (a, b) = (closest(&parallel, ray), closest(&serial, ray));
                assert_eq!(a, b, "cut {cut}: ray {o} {d}");
                hits += usize::from(a.1.is_some());
            }
            assert!(hits > 100, "cut {cut}: {hits} of 1 000 rays hit: the test must see hits");
        }
    }
}
