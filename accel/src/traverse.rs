//! CPU traversal of obvhs's CWBVH: obvhs's traversal order (its `traverse!` macro) over nodes
//! whose child boxes are decoded once at build time.
//!
//! obvhs 0.4's `CwBvhNode::intersect_ray` widens the 48 quantised child-box bytes to `f32` on
//! every visit, one byte at a time (48 scalar loads and int-to-float conversions per node), then
//! walks the 8 children with a branch each; under callgrind that was ~60% of the instructions of
//! an incoherent closest-hit query on the Cornell box (`BENCHMARKS.md`). [`WideNode`] keeps the
//! same quantised planes as exact `f32` (256 bytes per node instead of 80), tests the boxes
//! without branches and loops only over the hit leaf children (inner children's mask bits come
//! from a table). The leaf children are looped over rather than masked without branches (lane
//! masks selecting precomputed bits, summed): a ray's traversal is a chain of dependent node
//! visits, and a select-and-sum lengthens each link, where the loop's predicted branches do not
//! (`BENCHMARKS.md`). The arithmetic per child and axis is obvhs's, in the same order
//! (`q · (extent / d) + (p − o) / d`, then max/min), so box decisions are the same except for
//! the entry cut-off: obvhs clamps entry distances to an absolute `1e-4`, this test to `0` (it
//! visits a superset of obvhs's boxes).
//!
//! On CPUs with AVX2, `Bvh`'s queries run a copy of the traversal compiled for it, whose node
//! test takes the 8 children in one pass of 256-bit instructions ([`WideNode::intersect8`]:
//! same operations, same order, same masks) and whose bit counts are `popcnt`s.
//!
//! Each hit leaf child's triangles (at most 3) are tested together, one 4-lane
//! [`Tri4`] block per leaf child in leaf order, with no branch per triangle: the branches of
//! one-at-a-time tests (determinant, `u`, `v`, `t`) were as unpredictable as the rays.

use std::ops::ControlFlow;

use glam::{Vec3, Vec3A, Vec4};

use crate::triangle::Tri4;
use obvhs::{cwbvh::node::CwBvhNode, ray::Ray};

/// A CWBVH node for CPU traversal: obvhs's [`CwBvhNode`] with the 48 quantised child planes
/// widened to `f32` once at build time (exactly: they are integers 0..=255), so that the node
/// test is 4-wide `f32` arithmetic with no per-node decoding.
#[derive(Clone, Copy, Debug)]
pub(crate) struct WideNode {
    /// `[axis][lo, hi][children 0-3, 4-7]`, in the node's quantised grid units.
    planes: [[[Vec4; 2]; 2]; 3],
    /// Node grid origin `p` and cell size `2^e` per axis.
    origin: Vec3A,
    extent: Vec3A,
    /// obvhs's per-child metadata: for a leaf child, its unary triangle count in the high 3
    /// bits and its first triangle's offset from `primitive_base` in the low 5 (0 for an
    /// empty child); inner child `i` sits in slot `24 + i` (`bvh2_to_cwbvh`), which
    /// `INNER_BITS` assumes.
    child_meta: [u8; 8],
    imask: u32,
    child_base: u32,
    primitive_base: u32,
    /// The first of the node's leaf blocks ([`crate::triangle::Tri4`]): its leaf children, in
    /// slot order, have blocks `block_base ..`.
    block_base: u32,
    /// The slots of its non-empty leaf children.
    leaf_mask: u8,
}

// 192 + 32 + 8 + 17, padded to the 16-byte alignment of its vectors.
const _: () = assert!(std::mem::size_of::<WideNode>() == 256);

impl WideNode {
    /// `node`, whose leaf children's blocks start at `block_base`.
    fn from_cwbvh(node: &CwBvhNode, block_base: u32) -> Self {
        let f = |q: [u8; 8]| {
            [
                Vec4::new(q[0] as f32, q[1] as f32, q[2] as f32, q[3] as f32),
                Vec4::new(q[4] as f32, q[5] as f32, q[6] as f32, q[7] as f32),
            ]
        };
        for (i, &meta) in node.child_meta.iter().enumerate() {
            let inner = node.imask & (1 << i) != 0;
            debug_assert!(!inner || meta == 0b0010_0000 | (24 + i as u8), "inner child {i} off its slot");
        }
        WideNode {
            planes: [
                [f(node.child_min_x), f(node.child_max_x)],
                [f(node.child_min_y), f(node.child_max_y)],
                [f(node.child_min_z), f(node.child_max_z)],
            ],
            origin: Vec3A::from(node.p),
            extent: node.compute_extent(),
            child_meta: node.child_meta,
            imask: node.imask as u32,
            child_base: node.child_base_idx,
            primitive_base: node.primitive_base_idx,
            block_base,
            leaf_mask: leaf_mask(node),
        }
    }

    /// The leaf block of leaf child `child` and the leaf slot of its first triangle.
    /// `WIDE`: compiled for AVX2 CPUs, which all have `popcnt` (see [`popcount8`]).
    #[inline(always)]
    fn leaf<const WIDE: bool>(&self, child: usize) -> (usize, usize) {
        let rank = popcount8::<WIDE>(u32::from(self.leaf_mask) & ((1 << child) - 1));
        let first = self.primitive_base + u32::from(self.child_meta[child] & 0x1f);
        ((self.block_base + rank) as usize, first as usize)
    }

    /// The children entered at some `t ∈ [0, t_max]`: obvhs's mask of the inner ones (the top
    /// byte of `CwBvhNode::intersect_ray`'s result: inner children in traversal order) and a
    /// mask of the leaf children by slot. Same arithmetic, in the same order, as obvhs's SSE
    /// test: `q · (extent / d) + (p − o) / d`, then `maxps`/`minps` (glam's `Vec4::max`/`min`
    /// are those instructions), `cmpleps`. Inner children's bits come from a table (their
    /// slots XOR the ray's octant).
    #[inline(always)]
    fn intersect(&self, ray: &NodeRay, t_max: f32) -> (u32, u32) {
        let scale = self.extent * ray.inv_direction;
        let offset = (self.origin - ray.origin) * ray.inv_direction;
        let (s, o) = (scale.to_array(), offset.to_array());
        let half = |half: usize| {
            let t = |axis: usize, far: bool| {
                let side = ray.negative[axis] != far;
                self.planes[axis][side as usize][half] * s[axis] + Vec4::splat(o[axis])
            };
            let enter = t(0, false).max(t(1, false).max(t(2, false))).max(Vec4::ZERO);
            let leave = t(0, true).min(t(1, true).min(t(2, true))).min(Vec4::splat(t_max));
            enter.cmple(leave)
        };
        let (lo, hi) = (half(0), half(1));
        let hit8 = lo.bitmask() | (hi.bitmask() << 4);
        self.masks(ray, hit8)
    }

    /// [`intersect`](Self::intersect) with the 8 children in one pass of 256-bit AVX
    /// instructions: the same operations on the same values in the same order (`mulps`,
    /// `addps`, `maxps`, `minps`, `cmpleps`, each on 8 lanes instead of twice on 4), so the same
    /// bits and the same masks.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    #[inline]
    fn intersect8(&self, ray: &NodeRay, t_max: f32) -> (u32, u32) {
        use std::arch::x86_64::*;
        let scale = self.extent * ray.inv_direction;
        let offset = (self.origin - ray.origin) * ray.inv_direction;
        let (s, o) = (scale.to_array(), offset.to_array());
        let t = |axis: usize, far: bool| {
            let side = ray.negative[axis] != far;
            let [lo, hi] = self.planes[axis][side as usize];
            let p = _mm256_set_m128(hi.into(), lo.into());
            _mm256_add_ps(_mm256_mul_ps(p, _mm256_set1_ps(s[axis])), _mm256_set1_ps(o[axis]))
        };
        let enter = _mm256_max_ps(
            _mm256_max_ps(t(0, false), _mm256_max_ps(t(1, false), t(2, false))),
            _mm256_setzero_ps(),
        );
        let leave = _mm256_min_ps(
            _mm256_min_ps(t(0, true), _mm256_min_ps(t(1, true), t(2, true))),
            _mm256_set1_ps(t_max),
        );
        let hit8 = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OS>(enter, leave)) as u32;
        self.masks(ray, hit8)
    }

    /// The masks [`intersect`](Self::intersect) returns, from the bits of the children hit.
    #[inline(always)]
    fn masks(&self, ray: &NodeRay, hit8: u32) -> (u32, u32) {
        let inner = u32::from(INNER_BITS[ray.octant][(hit8 & self.imask) as usize]) << 24;
        (inner, hit8 & u32::from(self.leaf_mask))
    }
}

/// The slots of `node`'s non-empty leaf children (obvhs gives an empty child metadata 0).
pub(crate) fn leaf_mask(node: &CwBvhNode) -> u8 {
    (0..8).filter(|&i| node.imask & (1 << i) == 0 && node.child_meta[i] != 0).fold(0, |m, i| m | (1 << i))
}

/// The triangle count of leaf child `child` of `node` (its unary count in the metadata's top
/// 3 bits).
pub(crate) fn leaf_count(node: &CwBvhNode, child: usize) -> usize {
    (node.child_meta[child] >> 5).count_ones() as usize
}

/// The CPU form of a CWBVH: its nodes as [`WideNode`]s and the triangles of each leaf child as
/// one [`Tri4`] block, blocks in node order and, within a node, in slot order.
/// `triangle(slot)` gives the vertices of leaf slot `slot`.
pub(crate) fn wide_tree(
    nodes: &[CwBvhNode],
    triangle: impl Fn(usize) -> [Vec3; 3],
) -> (Vec<WideNode>, Vec<Tri4>) {
    let mut blocks = Vec::new();
    let mut wide = Vec::with_capacity(nodes.len());
    let mut tris = Vec::with_capacity(3);
    for node in nodes {
        let base = u32::try_from(blocks.len()).expect("furnace-accel: at most 2^32 leaf blocks");
        wide.push(WideNode::from_cwbvh(node, base));
        let leaves = leaf_mask(node);
        for child in (0..8).filter(|c| leaves & (1 << c) != 0) {
            let first = node.primitive_base_idx as usize + usize::from(node.child_meta[child] & 0x1f);
            tris.clear();
            tris.extend((first..first + leaf_count(node, child)).map(&triangle));
            blocks.push(Tri4::new(&tris));
        }
    }
    (wide, blocks)
}

/// `INNER_BITS[octant][m]`: the byte with bit `i ^ octant` set for each bit `i` of `m`, i.e.
/// the top byte of obvhs's hit mask for hit inner children `m` (child `i` in slot `24 + i`,
/// whose bit is `24 + (i ^ octant)`: children in the ray's traversal order).
const INNER_BITS: [[u8; 256]; 8] = {
    let mut table = [[0u8; 256]; 8];
    let mut octant = 0;
    while octant < 8 {
        let mut m = 0;
        while m < 256 {
            let mut bits = 0u8;
            let mut i = 0;
            while i < 8 {
                if m & (1 << i) != 0 {
                    bits |= 1 << (i ^ octant);
                }
                i += 1;
            }
            table[octant][m] = bits;
            m += 1;
        }
        octant += 1;
    }
    table
};

/// The per-ray constants of the node test.
pub(crate) struct NodeRay {
    origin: Vec3A,
    inv_direction: Vec3A,
    negative: [bool; 3],
    /// obvhs's `ray_get_octant_inv4` in one byte: 4, 2, 1 for a non-negative x, y, z.
    octant: usize,
}

impl NodeRay {
    #[inline(always)]
    pub(crate) fn new(ray: &Ray) -> Self {
        // Sign bits, not `d < 0`: a `-0.0` component has the reciprocal `-2^100`
        // (`Bvh::obvhs_ray`), so it must enter through the far plane like any negative one;
        // with `d < 0` it took the near plane and the ray missed every box.
        let signs = ray.direction.is_negative_bitmask();
        NodeRay {
            origin: ray.origin,
            inv_direction: ray.inv_direction,
            negative: [signs & 1 != 0, signs & 2 != 0, signs & 4 != 0],
            octant: OCTANT_INV[signs as usize],
        }
    }
}

/// obvhs's inverted octant of a ray from its direction's sign bits (x in bit 0): bit 2 for a
/// non-negative x, bit 1 for y, bit 0 for z.
const OCTANT_INV: [usize; 8] = [7, 3, 5, 1, 6, 2, 4, 0];

/// The CWBVH traversal of Ylitie et al. 2017 as obvhs's `traverse!` macro does it (node groups
/// and triangle groups as `(base, mask)` pairs), over [`WideNode`]s.
/// `leaf(block, first)` tests the leaf block `block` (its triangles are leaf slots `first ..`);
/// it returns `Break` to stop, or the new box cull distance (`Continue(t)`, `t < t_max` lowers
/// it). A node's hit leaf children are visited from the highest slot down.
///
/// The stack holds [`STACK`] node groups. A group is pushed at most once per tree level, so a
/// tree of ≤ [`STACK`] levels (every tree obvhs builds for ordinary scenes) never fills it.
/// When a push finds it full, the bottom (shallowest) group is dropped and the ray marked; when
/// the stack then runs empty, a marked ray finishes with a sweep over every node's leaf
/// children, box-tested against the current cull distance, so no hit is lost: the closest hit
/// has the same `t` as with an unbounded stack (a tie between triangles at the same `t` may
/// resolve differently) and an any-hit query finds a hit if there is one. This is the GPU
/// twin's behaviour (`gpu/src/wgsl/traverse.wgsl`, "Traversal stack and its overflow"). A fixed
/// stack that overwrites its top entry when full (obvhs's `StackStack`) would lose every hit
/// below it; the sweep costs almost nothing on trees that never overflow, less than a heap
/// spill.
///
/// `WIDE` picks the node test: [`WideNode::intersect8`] (for code compiled with AVX2) or
/// [`WideNode::intersect`]; both give the same masks.
#[inline(always)]
fn traverse<const WIDE: bool>(
    nodes: &[WideNode],
    ray: &Ray,
    mut leaf: impl FnMut(usize, usize) -> ControlFlow<(), f32>,
) {
    let mut walk = Walk::new(ray);
    while walk.step::<WIDE>(nodes, &mut leaf) {}
}

/// One ray's traversal ([`traverse`]) as a state that advances one node visit at a time.
/// (Interleaving several rays' walks, a node of each in turn, was measured on the Cornell box
/// and gained nothing for closest hits: the traversal is bound by instructions and branches
/// more than by the wait for nodes; see `BENCHMARKS.md`.)
struct Walk {
    r: NodeRay,
    /// The box cull distance.
    t_max: f32,
    /// A ring buffer: groups `bottom..top` are on the stack, group `i` in `stack[i % STACK]`;
    /// `bottom` stays 0 unless the stack overflows (no copying when it does).
    stack: [(u32, u32); STACK],
    top: usize,
    bottom: usize,
    /// Whether a group was dropped from the full stack (then the sweep runs at the end).
    overflowed: bool,
    /// The sweep's next node, and the inner-child mask: all of them, none in the sweep.
    sweep_next: usize,
    follow_inner: u32,
    /// The node group being visited: `(child base, hit mask)`.
    current: (u32, u32),
}

impl Walk {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        Walk {
            r: NodeRay::new(ray),
            t_max: ray.tmax,
            stack: [(0, 0); STACK],
            top: 0,
            bottom: 0,
            overflowed: false,
            sweep_next: 0,
            follow_inner: 0xff00_0000,
            current: (0, 0x8000_0000),
        }
    }

    /// Visits the next node, testing its hit leaf children with `leaf` (see [`traverse`]);
    /// `false` when the traversal has ended (no node left, or `leaf` returned `Break`).
    #[inline(always)]
    fn step<const WIDE: bool>(
        &mut self,
        nodes: &[WideNode],
        leaf: &mut impl FnMut(usize, usize) -> ControlFlow<(), f32>,
    ) -> bool {
        let node = loop {
            if self.current.1 & 0xff00_0000 != 0 {
                let hits_imask = self.current.1;
                let child_index_offset = 31 - hits_imask.leading_zeros();
                self.current.1 &= !(1u32 << child_index_offset);
                if self.current.1 & 0xff00_0000 != 0 {
                    if self.top - self.bottom == STACK {
                        // Full: drop the bottom (shallowest) group; the sweep covers it.
                        self.bottom += 1;
                        self.overflowed = true;
                    }
                    self.stack[self.top % STACK] = self.current;
                    self.top += 1;
                }
                let slot_index = (child_index_offset - 24) ^ self.r.octant as u32;
                // `slot_index < 8`: only the low byte (`imask`) counts.
                let relative_index = popcount8::<WIDE>(hits_imask & !(0xffff_ffffu32 << slot_index) & 0xff);
                match nodes.get((self.current.0 + relative_index) as usize) {
                    Some(node) => break node,
                    // An empty tree (the root group points at node 0).
                    None => return false,
                }
            } else if self.top != self.bottom {
                self.top -= 1;
                self.current = self.stack[self.top % STACK];
            } else if self.overflowed && self.sweep_next < nodes.len() {
                // The fallback: every node's leaf children, box-tested with the current cull
                // distance. Leaves already tested are tested again, which changes no result.
                self.sweep_next += 1;
                // The sweep follows no inner child: every leaf is some node's child.
                self.follow_inner = 0;
                break &nodes[self.sweep_next - 1];
            } else {
                return false;
            }
        };
        #[cfg(target_arch = "x86_64")]
        let (inner, mut leaves) = if WIDE {
            // SAFETY: `WIDE` is true only in `Bvh`'s AVX2 queries, which run only on CPUs with
            // AVX2 (`wide_node_test_available`).
            #[allow(unsafe_code)]
            unsafe {
                node.intersect8(&self.r, self.t_max)
            }
        } else {
            node.intersect(&self.r, self.t_max)
        };
        #[cfg(not(target_arch = "x86_64"))]
        let (inner, mut leaves) = node.intersect(&self.r, self.t_max);
        self.current = (node.child_base, (inner & self.follow_inner) | node.imask);
        while leaves != 0 {
            let child = 31 - leaves.leading_zeros();
            leaves &= !(1u32 << child);
            let (block, first) = node.leaf::<WIDE>(child as usize);
            match leaf(block, first) {
                ControlFlow::Break(()) => return false,
                ControlFlow::Continue(t) => {
                    if t < self.t_max {
                        self.t_max = t;
                    }
                }
            }
        }
        true
    }
}

/// Closest-hit traversal: `visit(block, first)` tests leaf block `block` (leaf slots
/// `first ..`) and returns the distance (in the traversal ray's units) beyond which boxes may be
/// culled from now on, or `+∞` for no change.
#[inline(always)]
pub(crate) fn closest<const WIDE: bool>(
    nodes: &[WideNode],
    ray: &Ray,
    mut visit: impl FnMut(usize, usize) -> f32,
) {
    traverse::<WIDE>(nodes, ray, |block, first| ControlFlow::Continue(visit(block, first)));
}

/// Any-hit traversal: stops as soon as `visit(block, first)` returns `true`; returns whether it
/// did.
#[inline(always)]
pub(crate) fn any<const WIDE: bool>(
    nodes: &[WideNode],
    ray: &Ray,
    mut visit: impl FnMut(usize, usize) -> bool,
) -> bool {
    let mut found = false;
    traverse::<WIDE>(nodes, ray, |block, first| {
        if visit(block, first) {
            found = true;
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(f32::INFINITY)
        }
    });
    found
}

/// Node groups [`traverse`] keeps in its fixed array before spilling to the heap (obvhs's
/// CWBVH stack size; the test scenes and glTF samples stay well below it).
const STACK: usize = 32;

/// The number of set bits of `byte` (< 256): `count_ones` where the code is compiled for AVX2
/// CPUs (`WIDE`; they all have `popcnt`, one instruction), else a table, as baseline x86-64 has
/// no `popcnt` and `count_ones` would be a dozen instructions.
#[inline(always)]
fn popcount8<const WIDE: bool>(byte: u32) -> u32 {
    if WIDE { byte.count_ones() } else { u32::from(POPCOUNT_8[byte as usize & 0xff]) }
}

/// The number of set bits of every byte.
const POPCOUNT_8: [u8; 256] = {
    let mut table = [0u8; 256];
    let mut i = 0;
    while i < 256 {
        table[i] = (i as u32).count_ones() as u8;
        i += 1;
    }
    table
};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::triangle::intersect_triangle;
    use glam::Vec3;

    /// A hand-built chain of `levels` CWBVH nodes (the tree of
    /// `tests/tests/traversal_parity.rs`'s deep-tree test): chain node k has two inner children
    /// whose boxes cover the whole scene, a leaf holder with triangles 3k..3k+3 and chain node
    /// k + 1. Rays whose octant visits the chain child first push one group per level, so the
    /// stack reaches `levels` groups; a fixed 32-entry stack that overwrote its top entry would
    /// lose the holders' triangles from there on.
    fn chain(levels: usize, tris: &[[Vec3; 3]]) -> (Vec<WideNode>, Vec<Tri4>) {
        let (lo, hi) = tris
            .iter()
            .flatten()
            .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(l, h), v| (l.min(*v), h.max(*v)));
        // Grid cell 2^(e − 127), so that 255 cells cover the scene.
        let cell = ((hi - lo).max_element() / 255.0).log2().ceil() as i32;
        let e = (127 + cell) as u8;
        let full = [255u8, 255, 0, 0, 0, 0, 0, 0];
        let internal = |slot: u8| (1u8 << 5) | (24 + slot);
        let node = |imask: u8, child_base_idx: u32, primitive_base_idx: u32, child_meta: [u8; 8]| CwBvhNode {
            p: lo,
            e: [e; 3],
            imask,
            child_base_idx,
            primitive_base_idx,
            child_meta,
            child_min_x: [0; 8],
            child_max_x: full,
            child_min_y: [0; 8],
            child_max_y: full,
            child_min_z: [0; 8],
            child_max_z: full,
        };
        let mut nodes = Vec::new();
        for k in 0..levels {
            // Chain node k at 2k; its children at 2k + 1 (holder, slot 0) and 2k + 2 (chain,
            // slot 1).
            let last = k + 1 == levels;
            let meta = [internal(0), if last { 0 } else { internal(1) }, 0, 0, 0, 0, 0, 0];
            nodes.push(node(if last { 0b01 } else { 0b11 }, 2 * k as u32 + 1, 0, meta));
            // Holder k: one leaf of 3 triangles (unary count 0b111) at offset 0 from 3k.
            nodes.push(node(0, 0, 3 * k as u32, [0b111 << 5, 0, 0, 0, 0, 0, 0, 0]));
        }
        wide_tree(&nodes, |slot| tris[slot])
    }

    /// The 8-lane AVX node test gives the same masks as the two 4-lane halves, bit for bit, on
    /// random nodes and rays: random plane bytes and grids (cells from 2⁻³⁰ to 2³⁰), origins
    /// inside and far outside the node, directions with zero, `-0.0` and tiny components (their
    /// clamped reciprocals reach 2¹⁰⁰ and give infinite and NaN slab distances, where `maxps`
    /// and `minps`'s operand order matters), `t_max` finite, zero and infinite.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn eight_lane_node_test_matches_two_halves() {
        if !std::is_x86_feature_detected!("avx") {
            // The AVX test cannot run here; the traversal never takes it on such CPUs.
            eprintln!("eight_lane_node_test_matches_two_halves: no AVX on this CPU, not run");
            return;
        }
        let mut r = furnace_tests::Rng::new(0x5eed_a5e5_0000_0008);
        let (mut hits, mut misses) = (0, 0);
        for case in 0..200_000 {
            let mut q = || std::array::from_fn::<u8, 8, _>(|_| r.below(256) as u8);
            let mut planes = [q(), q(), q(), q(), q(), q()];
            // Mostly proper boxes (min ≤ max), every fourth node as random bytes (empty boxes).
            if case % 4 != 0 {
                for pair in planes.chunks_exact_mut(2) {
                    let [min, max] = pair else { unreachable!() };
                    for (a, b) in min.iter_mut().zip(max.iter_mut()) {
                        (*a, *b) = ((*a).min(*b), (*a).max(*b));
                    }
                }
            }
            let imask = r.below(256) as u8;
            let node = CwBvhNode {
                p: Vec3::ZERO,
                e: [127; 3],
                imask,
                child_base_idx: 0,
                primitive_base_idx: 0,
                // Inner child i in slot 24 + i (as obvhs places them), leaves of one triangle.
                child_meta: std::array::from_fn(|i| {
                    if imask & (1 << i) != 0 { 0b0010_0000 | (24 + i as u8) } else { 0b0010_0000 }
                }),
                child_min_x: planes[0],
                child_max_x: planes[1],
                child_min_y: planes[2],
                child_max_y: planes[3],
                child_min_z: planes[4],
                child_max_z: planes[5],
            };
            let mut wide = WideNode::from_cwbvh(&node, 0);
            // Grid cells of 2^-30 .. 2^30 (every other case), or near 1.
            let (lo, hi) = if case % 2 == 0 { (-30, 30) } else { (-2, 2) };
            let mut cell = || 2f32.powi(lo + r.below((hi - lo + 1) as u32) as i32);
            wide.extent = Vec3A::new(cell(), cell(), cell());
            let size = wide.extent * 255.0;
            wide.origin = Vec3A::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0)) * size;
            let reach = if case % 3 == 0 { 4.0 } else { 1.2 };
            let o = wide.origin
                + Vec3A::new(r.range(-0.2, reach), r.range(-0.2, reach), r.range(-0.2, reach)) * size;
            // Every other ray aimed at a random point of the node's grid.
            let mut d = if case % 2 == 0 {
                let target = Vec3A::new(r.f32(), r.f32(), r.f32()) * size + wide.origin;
                (target - o).normalize_or(Vec3A::X)
            } else {
                Vec3A::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0))
            };
            match case % 7 {
                0 => d.x = 0.0,
                1 => d.y = -0.0,
                2 => d.z = 1e-35,
                _ => {}
            }
            // `Bvh::obvhs_ray`'s reciprocal: ±2^100 below 2^-100.
            let inv = |x: f32| if x.abs() < 7.888_609e-31 { 1.267_650_6e30f32.copysign(x) } else { 1.0 / x };
            let inv_direction = Vec3A::new(inv(d.x), inv(d.y), inv(d.z));
            let ray = Ray { origin: o, direction: d, inv_direction, tmin: 0.0, tmax: 0.0 };
            let node_ray = NodeRay::new(&ray);
            let t_max = match case % 5 {
                0 => f32::INFINITY,
                1 => 0.0,
                _ => r.range(0.0, 3.0) * size.max_element(),
            };
            let four = wide.intersect(&node_ray, t_max);
            // SAFETY: AVX was detected above.
            #[allow(unsafe_code)]
            let eight = unsafe { wide.intersect8(&node_ray, t_max) };
            assert_eq!(eight, four, "case {case}: origin {o}, direction {d}, t_max {t_max}");
            if four.0 | four.1 != 0 { hits += 1 } else { misses += 1 }
        }
        // Both outcomes must be common for the comparison to mean something.
        assert!(hits > 30_000 && misses > 30_000, "{hits} hits, {misses} misses");
        eprintln!("eight_lane_node_test_matches_two_halves: {hits} hits, {misses} misses, all equal");
    }

    #[test]
    fn deep_chain_loses_no_hits() {
        const LEVELS: usize = 100;
        // Nested triangles at increasing z: many hits per ray, one closest (0.01 apart in z, so
        // no near ties for box culling to get wrong).
        let tris: Vec<[Vec3; 3]> = (0..3 * LEVELS)
            .map(|k| {
                let s = 1.0 + 0.01 * k as f32;
                let z = k as f32 * 1e-2;
                [Vec3::new(-s, -s, z), Vec3::new(s, -s * 0.5, z), Vec3::new(0.0, s, z)]
            })
            .collect();
        let (nodes, blocks) = chain(LEVELS, &tris);
        let mut rng = furnace_tests::Rng::new(0x9e37_79b9_7f4a_7c15);
        let (mut hits, mut deep) = (0, 0);
        for _ in 0..4096 {
            let o = Vec3::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0), rng.range(-1.0, 4.0));
            let d = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            if d.length_squared() < 1e-4 {
                continue;
            }
            let ray = Ray {
                origin: o.into(),
                direction: d.into(),
                inv_direction: Vec3A::ONE / Vec3A::from(d),
                tmin: 0.0,
                tmax: f32::INFINITY,
            };
            let brute = tris.iter().enumerate().fold(None, |best: Option<(usize, f32)>, (i, t)| {
                match intersect_triangle(o, d, *t, best.map_or(f32::INFINITY, |b| b.1)) {
                    Some(h) => Some((i, h.t)),
                    None => best,
                }
            });
            let mut got: Option<(usize, f32)> = None;
            closest::<false>(&nodes, &ray, |block, first| {
                let hits = blocks[block].intersect(o.into(), d.into(), got.map_or(f32::INFINITY, |b| b.1));
                let mut cull = f32::INFINITY;
                for lane in (0..4).rev() {
                    if hits.mask & (1 << lane) != 0 && hits.t[lane] < got.map_or(f32::INFINITY, |b| b.1) {
                        got = Some((first + lane, hits.t[lane]));
                        // Cull slightly beyond the hit, as `Bvh` does.
                        cull = hits.t[lane] * crate::bvh::CULL_SLACK;
                    }
                }
                cull
            });
            assert_eq!(got, brute, "closest hit, ray {o} {d}");
            // Any-hit up to a distance short of and past the closest hit.
            for t_any in [1.0f32, 3.0] {
                let brute_any = tris.iter().any(|t| intersect_triangle(o, d, *t, t_any).is_some());
                let any_ray = Ray { tmax: t_any * crate::bvh::CULL_SLACK, ..ray };
                let got_any = any::<false>(&nodes, &any_ray, |block, _| {
                    blocks[block].intersect(o.into(), d.into(), t_any).mask != 0
                });
                assert_eq!(got_any, brute_any, "any hit, ray {o} {d} t_max {t_any}");
            }
            if let Some((slot, _)) = brute {
                hits += 1;
                deep += usize::from(slot >= 3 * STACK);
            }
        }
        // The test means something only if many closest hits lie below the fixed stack.
        assert!(hits > 1000 && deep > 300, "{hits} hits, {deep} below level {STACK}");
    }
}
