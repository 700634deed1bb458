//! Building the BVH over a triangle soup and tracing rays through it.

use glam::{Vec2, Vec3, Vec3A};
use obvhs::{
    BvhBuildParams,
    bvh2::Bvh2,
    cwbvh::CwBvh,
    ray::{Ray, RayHit},
    triangle::Triangle,
};
use rayon::prelude::*;

use crate::build::{OBVHS_STACK, build_bvh2, build_cwbvh, bvh2_depth, cwbvh_depth};
use crate::gpu::{GpuCwbvhNode, GpuTriangle};
use crate::traverse::{self, WideNode};
use crate::triangle::{Tri4, TriangleHit, intersect_triangle};

/// Which tree obvhs builds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Layout {
    /// Compressed wide BVH8 (Ylitie et al. 2017): 80-byte nodes, 8 quantised child boxes each,
    /// ≤ 3 triangles per leaf. The GPU layout, and on the CPU the faster one for incoherent
    /// rays (obvhs tests 4 children per SSE instruction; 1.2–2× BVH2 in `BENCHMARKS.md`).
    #[default]
    Cwbvh,
    /// Binary BVH with collapsed leaves (≤ 8 triangles). CPU only: [`Bvh::gpu_nodes`] is empty.
    /// Measured within ±20% of CWBVH for coherent camera rays, slower for incoherent ones.
    Bvh2,
}

/// The build presets of obvhs ([`BvhBuildParams`]), from fastest build to best tree.
///
/// All run PLOC (Meister & Bittner 2018) over Morton-sorted boxes, then reinsertion
/// (Meister & Bittner 2017) on a fraction of the nodes; `Slow` and `VerySlow` also pre-split large
/// triangles into several boxes (a triangle may then sit in several leaves).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BuildQuality {
    /// PLOC search radius 1, no reinsertion.
    Fastest,
    /// Radius 1, reinsertion on 1% of nodes.
    VeryFast,
    /// Radius 6, reinsertion on 2%.
    Fast,
    /// Radius 14, reinsertion on 5% ("around Embree's build time", obvhs says).
    Medium,
    /// Radius 24, reinsertion on 20%, spatial pre-splits, 128-bit Morton codes.
    Slow,
    /// Radius 14, reinsertion on 100%, spatial pre-splits, 128-bit Morton codes.
    VerySlow,
}

impl BuildQuality {
    /// Every preset, fastest build first.
    pub const ALL: [BuildQuality; 6] = [
        BuildQuality::Fastest,
        BuildQuality::VeryFast,
        BuildQuality::Fast,
        BuildQuality::Medium,
        BuildQuality::Slow,
        BuildQuality::VerySlow,
    ];

    /// The preset chosen when none is given, by triangle count `n`:
    ///
    /// * `n ≤ 300 000` → [`VerySlow`](Self::VerySlow): reinsertion on every node. On the
    ///   procedural interiors (a room of furniture and large walls) its trees render much
    ///   faster than `Slow`'s (20% of the nodes reinserted), on the GPU and on the CPU, and the
    ///   reference boxes no slower; it builds in about twice `Slow`'s time (obvhs builds on the
    ///   current rayon pool; `BENCHMARKS.md`): paid once, against renders of seconds to
    ///   minutes.
    /// * `n ≤ 3 000 000` → [`Medium`](Self::Medium): builds 1.04 M triangles in 0.9 s on one
    ///   core (`BENCHMARKS.md`); `Slow` adds spatial splits and 128-bit Morton codes on top, a
    ///   cost that grows with the scene while the first frame does not. (`VerySlow` takes ~5 s
    ///   on two cores at 1 M triangles for 1.6× the speed: a trade for the user, not for a
    ///   threshold.)
    /// * larger → [`Fast`](Self::Fast).
    ///
    /// The thresholds come from `cargo bench -p furnace-accel` (build time against Mrays/s)
    /// and `furnace bench` (samples/s, time to first frame), quoted in `BENCHMARKS.md`.
    pub fn for_triangle_count(n: usize) -> Self {
        if n <= 300_000 {
            BuildQuality::VerySlow
        } else if n <= 3_000_000 {
            BuildQuality::Medium
        } else {
            BuildQuality::Fast
        }
    }

    /// The obvhs parameters of this preset.
    pub fn params(self) -> BvhBuildParams {
        match self {
            BuildQuality::Fastest => BvhBuildParams::fastest_build(),
            BuildQuality::VeryFast => BvhBuildParams::very_fast_build(),
            BuildQuality::Fast => BvhBuildParams::fast_build(),
            BuildQuality::Medium => BvhBuildParams::medium_build(),
            BuildQuality::Slow => BvhBuildParams::slow_build(),
            BuildQuality::VerySlow => BvhBuildParams::very_slow_build(),
        }
    }
}

/// How to build a [`Bvh`]; `Default` is a CWBVH with the preset picked by
/// [`BuildQuality::for_triangle_count`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BuildOptions {
    /// Tree layout.
    pub layout: Layout,
    /// Build preset; `None` chooses by triangle count.
    pub quality: Option<BuildQuality>,
}

/// The largest coordinate magnitude of a triangle the tree takes: 2⁵⁶ ≈ 7.2e16.
///
/// obvhs builds with `f32` surface areas; a box of extent ~1e19 has an area beyond `f32::MAX`,
/// and one such triangle among ordinary ones made its CWBVH conversion panic
/// (`distribute_left < 7`, `tests/degenerate.rs::huge_triangles_are_skipped_not_a_panic`).
/// At 2⁵⁶ a box's half area is at most 3·2¹¹⁴ ≈ 6e34, four orders of magnitude below
/// `f32::MAX`. Nothing renderable is lost: the `f32` ray–triangle test already overflows for
/// scenes beyond ~1e13 (`furnace-tests`' `tests/stability.rs`).
pub const MAX_BUILD_COORDINATE: f32 = 72_057_594_037_927_936.0;

/// The closest intersection found by [`Bvh::closest_hit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Index of the triangle in the builder's input.
    pub triangle: u32,
    /// Ray parameter: the hit point is `origin + t · dir`.
    pub t: f32,
    /// Barycentrics `(u, v)`: the point is `(1 − u − v)·v0 + u·v1 + v·v2`.
    pub barycentrics: Vec2,
}

enum Tree {
    Empty,
    /// obvhs's tree (its nodes are the GPU buffer) and the same nodes decoded for the CPU
    /// traversal, or no decoded nodes (traverse with obvhs's own node test) above
    /// [`WIDE_NODE_LIMIT`] nodes.
    Cwbvh(CwBvh, Vec<WideNode>),
    Bvh2(Bvh2),
}

/// A bounding volume hierarchy over a triangle soup, with closest-hit and any-hit queries.
///
/// Triangles keep the index they had in the input. Triangles with a non-finite vertex, a
/// coordinate beyond [`MAX_BUILD_COORDINATE`], or an exactly zero cross product (zero area in
/// `f32`) are left out of the tree, so no ray hits them; [`Bvh::skipped_count`] says how many.
pub struct Bvh {
    tree: Tree,
    /// Triangles in leaf order (direct layout).
    triangles: Vec<GpuTriangle>,
    /// `triangles[i].id`, as its own buffer.
    ids: Vec<u32>,
    /// The leaf children's triangles with their edges formed, 4 lanes per leaf child, for the
    /// CPU traversal over [`WideNode`]s (empty where the tree has none: large trees are
    /// memory-bound and keep 48 bytes per triangle).
    blocks: Vec<Tri4>,
    /// `2^-m`: obvhs traverses with `dir · dir_scale`, see [`Bvh::obvhs_ray`].
    dir_scale: f32,
    /// Whether the CPU has the features the queries' AVX2 versions are compiled for
    /// ([`wide_node_test_available`]).
    avx2: bool,
    input_count: usize,
    skipped: usize,
    quality: Option<BuildQuality>,
    layout: Layout,
}

impl Bvh {
    /// Builds a CWBVH over `triangles` with the preset chosen by triangle count.
    pub fn build(triangles: &[[Vec3; 3]]) -> Self {
        Self::build_with(triangles, BuildOptions::default())
    }

    /// Builds over an indexed mesh: triangle `i` is `positions[indices[i][k]]`. A triangle with an
    /// index out of range is skipped like a degenerate one (it keeps its id `i`).
    pub fn from_indexed(positions: &[Vec3], indices: &[[u32; 3]], options: BuildOptions) -> Self {
        let nan = Vec3::splat(f32::NAN);
        let soup: Vec<[Vec3; 3]> = indices
            .par_iter()
            .map(|tri| tri.map(|i| positions.get(i as usize).copied().unwrap_or(nan)))
            .collect();
        Self::build_with(&soup, options)
    }

    /// Builds over `triangles` with explicit options.
    ///
    /// # Panics
    ///
    /// If there are 2^32 triangles or more (ids are `u32`).
    pub fn build_with(triangles: &[[Vec3; 3]], options: BuildOptions) -> Self {
        assert!(u32::try_from(triangles.len()).is_ok(), "furnace-accel: at most 2^32 - 1 triangles");
        // In parallel, as are obvhs's PLOC build and every step below but its CWBVH conversion:
        // serial, these loops took a tenth of a 10⁷-triangle build on two cores.
        let (valid_ids, valid): (Vec<u32>, Vec<Triangle>) = triangles
            .par_iter()
            .enumerate()
            .filter(|(_, t)| {
                // `max_element` ignores NaN, hence `is_finite` too.
                t.iter().all(|v| v.is_finite() && v.abs().max_element() <= MAX_BUILD_COORDINATE)
                    && (t[1] - t[0]).cross(t[2] - t[0]) != Vec3::ZERO
            })
            .map(|(i, t)| {
                (i as u32, Triangle { v0: Vec3A::from(t[0]), v1: Vec3A::from(t[1]), v2: Vec3A::from(t[2]) })
            })
            .unzip();
        let max_abs = valid
            .par_iter()
            .map(|t| t.v0.abs().max(t.v1.abs()).max(t.v2.abs()).max_element())
            .reduce(|| 0.0, f32::max);
        let skipped = triangles.len() - valid.len();
        let quality = options.quality.unwrap_or_else(|| BuildQuality::for_triangle_count(valid.len()));
        let mut tree = if valid.is_empty() {
            Tree::Empty
        } else {
            match options.layout {
                Layout::Cwbvh => {
                    let b = build_cwbvh(&valid, quality.params());
                    // Its CPU form is added below, once the triangles are in leaf order.
                    Tree::Cwbvh(b, Vec::new())
                }
                Layout::Bvh2 => Tree::Bvh2(build_bvh2(&valid, quality.params())),
            }
        };
        let primitive_indices: &[u32] = match &tree {
            Tree::Empty => &[],
            Tree::Cwbvh(b, _) => &b.primitive_indices,
            Tree::Bvh2(b) => &b.primitive_indices,
        };
        let gpu: Vec<GpuTriangle> = primitive_indices
            .par_iter()
            .map(|&k| {
                let id = valid_ids[k as usize];
                let [v0, v1, v2] = triangles[id as usize];
                GpuTriangle {
                    v0: v0.to_array(),
                    id,
                    v1: v1.to_array(),
                    reserved1: 0,
                    v2: v2.to_array(),
                    reserved2: 0,
                }
            })
            .collect();
        let ids = gpu.par_iter().map(|t| t.id).collect();
        let mut blocks = Vec::new();
        if let Tree::Cwbvh(b, wide) = &mut tree
            && (b.nodes.len() <= WIDE_NODE_LIMIT || cwbvh_depth(b) >= OBVHS_STACK)
        {
            // obvhs's own traversal (used above the limit) has a fixed 32-entry stack that
            // overwrites its top entry when full and so loses hits below that depth; a tree
            // that deep is traversed by `traverse`, whose stack spills.
            (*wide, blocks) = traverse::wide_tree(&b.nodes, |slot| gpu[slot].vertices());
        }
        Bvh {
            tree,
            triangles: gpu,
            ids,
            blocks,
            dir_scale: direction_scale(max_abs),
            avx2: wide_node_test_available(),
            input_count: triangles.len(),
            skipped,
            quality: if valid.is_empty() { None } else { Some(quality) },
            layout: options.layout,
        }
    }

    /// The bounds of the triangles in the tree (`None` when it holds none).
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut it = self.triangles.iter().flat_map(|t| t.vertices());
        let first = it.next()?;
        Some(it.fold((first, first), |(lo, hi), v| (lo.min(v), hi.max(v))))
    }

    /// Host bytes held for the queries: nodes (as built, and decoded for the CPU traversal
    /// where they are), triangles in leaf order with their ids, and the CPU's leaf blocks.
    pub fn bytes(&self) -> usize {
        let nodes = match &self.tree {
            Tree::Empty => 0,
            Tree::Cwbvh(b, wide) => {
                b.nodes.len() * size_of::<GpuCwbvhNode>() + wide.len() * size_of::<WideNode>()
            }
            Tree::Bvh2(b) => b.nodes.len() * size_of::<obvhs::bvh2::node::Bvh2Node>(),
        };
        nodes + self.triangles.len() * (size_of::<GpuTriangle>() + 4) + self.blocks.len() * size_of::<Tri4>()
    }

    /// Bytes of the tree as a GPU uploads it: the CWBVH nodes and the triangles in leaf order.
    pub fn gpu_bytes(&self) -> usize {
        let nodes = match &self.tree {
            Tree::Cwbvh(b, _) => b.nodes.len(),
            Tree::Empty | Tree::Bvh2(_) => 0,
        };
        nodes * size_of::<GpuCwbvhNode>() + self.triangles.len() * size_of::<GpuTriangle>()
    }

    /// Number of triangles given to the builder (including skipped ones).
    pub fn input_count(&self) -> usize {
        self.input_count
    }

    /// Number of input triangles left out as degenerate, non-finite or beyond
    /// [`MAX_BUILD_COORDINATE`].
    pub fn skipped_count(&self) -> usize {
        self.skipped
    }

    /// The preset the tree was built with (`None` when no triangle was valid).
    pub fn quality(&self) -> Option<BuildQuality> {
        self.quality
    }

    /// The tree layout.
    pub fn layout(&self) -> Layout {
        self.layout
    }

    /// The number of node levels of the tree: 0 for an empty tree, 1 for a root whose children
    /// are all leaves. A stack traversal that pushes one node group per level below the root
    /// (furnace-gpu's) needs `depth() - 1` entries at most.
    pub fn depth(&self) -> usize {
        match &self.tree {
            Tree::Empty => 0,
            Tree::Cwbvh(b, _) => cwbvh_depth(b),
            Tree::Bvh2(b) => bvh2_depth(b),
        }
    }

    /// CWBVH nodes for the GPU, root first ([`GpuCwbvhNode`]); empty for [`Layout::Bvh2`] and
    /// for an empty tree.
    pub fn gpu_nodes(&self) -> &[GpuCwbvhNode] {
        match &self.tree {
            Tree::Cwbvh(b, _) => bytemuck::cast_slice(&b.nodes),
            _ => &[],
        }
    }

    /// Triangles in leaf order ([`GpuTriangle`]): leaf slots index this slice directly.
    pub fn gpu_triangles(&self) -> &[GpuTriangle] {
        &self.triangles
    }

    /// The input id of each leaf slot (`gpu_triangles()[i].id`, as its own `u32` buffer).
    pub fn triangle_ids(&self) -> &[u32] {
        &self.ids
    }

    /// The closest triangle hit by the ray `origin + t · dir`, `0 < t < t_max`.
    ///
    /// `dir` need not be normalised (`t` is in units of its length). A non-finite origin or
    /// direction, or a zero direction, hits nothing. To start a ray on a surface, move its origin
    /// with [`crate::offset_ray_origin`] rather than raising a minimum `t`.
    #[inline]
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<Hit> {
        self.closest_hit_masked(origin, dir, t_max, |_, _| true)
    }

    /// [`closest_hit`](Self::closest_hit) where a candidate counts only if
    /// `mask(triangle, barycentrics)` returns `true` (alpha-masked materials: look up the
    /// texture at the interpolated UV and compare with the cutoff).
    ///
    /// The mask is called only for candidates closer than the closest accepted hit so far, in
    /// no particular order, possibly more than once per triangle.
    #[inline]
    pub fn closest_hit_masked(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mask: impl FnMut(u32, Vec2) -> bool,
    ) -> Option<Hit> {
        // The query proper takes 16-byte vectors: built here in the caller's registers, they
        // reach it as whole 16-byte stores that its 16-byte loads forward from. `Vec3`
        // arguments were stored as 8 + 4 bytes and read back as 4 + 8, a store-forwarding
        // stall at every query.
        self.closest_hit_a(origin.into(), dir.into(), t_max, mask)
    }

    /// [`closest_hit_masked`](Self::closest_hit_masked) on `Vec3A`s.
    fn closest_hit_a(
        &self,
        o: Vec3A,
        d: Vec3A,
        t_max: f32,
        mask: impl FnMut(u32, Vec2) -> bool,
    ) -> Option<Hit> {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is true only where the CPU has every feature `closest_hit_avx2` is
            // compiled for (`wide_node_test_available`).
            #[allow(unsafe_code)]
            return unsafe { self.closest_hit_avx2(o, d, t_max, mask) };
        }
        self.closest_hit_with::<false>(o, d, t_max, mask)
    }

    /// [`closest_hit_with`](Self::closest_hit_with) compiled for AVX2, with the 8-lane node test.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    fn closest_hit_avx2(
        &self,
        o: Vec3A,
        d: Vec3A,
        t_max: f32,
        mask: impl FnMut(u32, Vec2) -> bool,
    ) -> Option<Hit> {
        self.closest_hit_with::<true>(o, d, t_max, mask)
    }

    /// The closest-hit query; `WIDE` picks the node test (`traverse::traverse`).
    #[inline(always)]
    fn closest_hit_with<const WIDE: bool>(
        &self,
        o: Vec3A,
        d: Vec3A,
        t_max: f32,
        mut mask: impl FnMut(u32, Vec2) -> bool,
    ) -> Option<Hit> {
        let (origin, dir) = (Vec3::from(o), Vec3::from(d));
        let ray = self.obvhs_ray(o, d, t_max)?;
        let cull_scale = CULL_SLACK / self.dir_scale;
        if let Tree::Cwbvh(_, wide) = &self.tree
            && !wide.is_empty()
        {
            // The CPU's own traversal, over the leaf blocks.
            let mut best: Option<(usize, TriangleHit)> = None;
            let mut current = t_max;
            traverse::closest::<WIDE>(wide, &ray, |block, first| {
                self.closest_leaf(block, first, o, d, (&mut best, &mut current), cull_scale, &mut mask)
            });
            return self.hit_of(best);
        }
        let mut best: Option<(u32, TriangleHit)> = None;
        let mut current = t_max;
        let mut visit = |_: &Ray, slot: usize| -> f32 {
            let tri = &self.triangles[slot];
            match intersect_triangle(origin, dir, tri.vertices(), current) {
                Some(h) if mask(tri.id, h.barycentrics) => {
                    best = Some((tri.id, h));
                    current = h.t;
                    // obvhs culls boxes entered beyond this: slightly beyond the hit, see
                    // CULL_SLACK.
                    h.t * cull_scale
                }
                _ => f32::INFINITY,
            }
        };
        match &self.tree {
            Tree::Empty => {}
            Tree::Cwbvh(b, _) => {
                b.ray_traverse(ray, &mut RayHit::none(), &mut visit);
            }
            Tree::Bvh2(b) => {
                b.ray_traverse(ray, &mut RayHit::none(), &mut visit);
            }
        }
        best.map(|(triangle, h)| Hit { triangle, t: h.t, barycentrics: h.barycentrics })
    }

    /// Whether any triangle intersects the ray `origin + t · dir` at `0 < t < t_max` (a shadow
    /// ray: pass the distance to the light, in units of `dir`, as `t_max`). Stops at the first
    /// hit found.
    #[inline]
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        self.occluded_masked(origin, dir, t_max, |_, _| true)
    }

    /// [`occluded`](Self::occluded) where a hit counts only if `mask(triangle, barycentrics)`
    /// returns `true`.
    #[inline]
    pub fn occluded_masked(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mask: impl FnMut(u32, Vec2) -> bool,
    ) -> bool {
        // As `closest_hit_masked`: 16-byte vectors to the query proper.
        self.occluded_a(origin.into(), dir.into(), t_max, mask)
    }

    /// [`occluded_masked`](Self::occluded_masked) on `Vec3A`s.
    fn occluded_a(&self, o: Vec3A, d: Vec3A, t_max: f32, mask: impl FnMut(u32, Vec2) -> bool) -> bool {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: as in `closest_hit_a`.
            #[allow(unsafe_code)]
            return unsafe { self.occluded_avx2(o, d, t_max, mask) };
        }
        self.occluded_with::<false>(o, d, t_max, mask)
    }

    /// [`occluded_with`](Self::occluded_with) compiled for AVX2, with the 8-lane node test.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    fn occluded_avx2(&self, o: Vec3A, d: Vec3A, t_max: f32, mask: impl FnMut(u32, Vec2) -> bool) -> bool {
        self.occluded_with::<true>(o, d, t_max, mask)
    }

    /// The any-hit query; `WIDE` picks the node test.
    #[inline(always)]
    fn occluded_with<const WIDE: bool>(
        &self,
        o: Vec3A,
        d: Vec3A,
        t_max: f32,
        mut mask: impl FnMut(u32, Vec2) -> bool,
    ) -> bool {
        let (origin, dir) = (Vec3::from(o), Vec3::from(d));
        let Some(ray) = self.obvhs_ray(o, d, t_max) else {
            return false;
        };
        if let Tree::Cwbvh(_, wide) = &self.tree
            && !wide.is_empty()
        {
            return traverse::any::<WIDE>(wide, &ray, |block, first| {
                self.any_leaf(block, first, o, d, t_max, &mut mask)
            });
        }
        let visit = |_: &Ray, slot: usize| -> f32 {
            let tri = &self.triangles[slot];
            match intersect_triangle(origin, dir, tri.vertices(), t_max) {
                // Any finite t below the scaled t_max stops traversal; 0 always is.
                Some(h) if mask(tri.id, h.barycentrics) => 0.0,
                _ => f32::INFINITY,
            }
        };
        match &self.tree {
            Tree::Empty => false,
            Tree::Cwbvh(b, _) => !b.ray_traverse_miss(ray, visit),
            Tree::Bvh2(b) => !b.ray_traverse_miss(ray, visit),
        }
    }

    /// A closest-hit query's test of leaf block `block` (leaf slots `first ..`): its hit lanes
    /// from the highest down, each against the best hit so far (`state`: that hit and its
    /// `t`), which is the order and test of one triangle at a time. Returns the new box cull
    /// distance (`+∞`: unchanged).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn closest_leaf(
        &self,
        block: usize,
        first: usize,
        o: Vec3A,
        d: Vec3A,
        (best, current): (&mut Option<(usize, TriangleHit)>, &mut f32),
        cull_scale: f32,
        mask: &mut impl FnMut(u32, Vec2) -> bool,
    ) -> f32 {
        let hits = self.blocks[block].intersect(o, d, *current);
        let mut cull = f32::INFINITY;
        let mut lanes = hits.mask;
        while lanes != 0 {
            let lane = (31 - lanes.leading_zeros()) as usize;
            lanes &= !(1 << lane);
            let (t, uv) = (hits.t[lane], Vec2::new(hits.u[lane], hits.v[lane]));
            if t < *current && mask(self.ids[first + lane], uv) {
                *best = Some((first + lane, TriangleHit { t, barycentrics: uv }));
                *current = t;
                // Cull boxes entered slightly beyond the hit, see CULL_SLACK.
                cull = t * cull_scale;
            }
        }
        cull
    }

    /// An any-hit query's test of leaf block `block` (leaf slots `first ..`): whether some
    /// lane hits at `t < t_max` and passes `mask`.
    #[inline(always)]
    fn any_leaf(
        &self,
        block: usize,
        first: usize,
        o: Vec3A,
        d: Vec3A,
        t_max: f32,
        mask: &mut impl FnMut(u32, Vec2) -> bool,
    ) -> bool {
        let hits = self.blocks[block].intersect(o, d, t_max);
        let mut lanes = hits.mask;
        while lanes != 0 {
            let lane = (31 - lanes.leading_zeros()) as usize;
            lanes &= !(1 << lane);
            if mask(self.ids[first + lane], Vec2::new(hits.u[lane], hits.v[lane])) {
                return true;
            }
        }
        false
    }

    /// The [`Hit`] of a closest-hit query's best leaf slot.
    #[inline(always)]
    fn hit_of(&self, best: Option<(usize, TriangleHit)>) -> Option<Hit> {
        best.map(|(slot, h)| Hit { triangle: self.ids[slot], t: h.t, barycentrics: h.barycentrics })
    }

    /// The ray obvhs traverses: the direction scaled by `dir_scale = 2^-m`, so that obvhs's
    /// ray parameter is `t' = t · 2^m`, and `tmax` loosened by [`CULL_SLACK`].
    ///
    /// obvhs's CWBVH node test clamps the entry distance to an absolute `1e-4`
    /// (`cwbvh::node::EPSILON`) and ignores `Ray::tmin`, so a child box the ray leaves before
    /// `t = 1e-4` is skipped — every hit closer than 1e-4 is lost, which in a millimetre-sized
    /// scene is most of them. Scaling the direction by a power of two is exact, changes no
    /// box decision except that cut-off, and moves the cut-off to `t = 1e-4 · 2^-m`, below
    /// `2^-40` of the scene's largest coordinate. Triangles are still intersected with the
    /// caller's unscaled ray, so results do not depend on `m`.
    ///
    /// obvhs's `Ray::new` also clamps `1/d` to `±1/f32::EPSILON` (≈ 8.4e6) for tiny
    /// components; that would be wrong for the scaled direction, so the inverse is formed here
    /// with a clamp at `2^100`.
    #[inline(always)]
    fn obvhs_ray(&self, origin: Vec3A, dir: Vec3A, t_max: f32) -> Option<Ray> {
        if !(origin.is_finite() && dir.is_finite() && dir != Vec3A::ZERO && t_max > 0.0) {
            return None;
        }
        let d = dir * self.dir_scale;
        Some(Ray {
            origin,
            direction: d,
            inv_direction: safe_recip3(d),
            tmin: 0.0,
            tmax: t_max * (CULL_SLACK / self.dir_scale),
        })
    }
}

/// Whether this CPU can run the queries' AVX2 versions (8-lane node test; the features LLVM may
/// use in them: AVX2 and the bit instructions every AVX2 CPU has). Films do not depend on it:
/// both node tests give the same masks.
fn wide_node_test_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("avx2")
            && std::is_x86_feature_detected!("bmi1")
            && std::is_x86_feature_detected!("bmi2")
            && std::is_x86_feature_detected!("lzcnt")
            && std::is_x86_feature_detected!("popcnt")
    }
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// Largest CWBVH (in nodes) traversed with decoded [`WideNode`]s (256 bytes each, so 4 MiB
/// here); larger trees keep obvhs's 80-byte nodes and node test. Decoding cuts the node test's
/// instructions about threefold, but triples the bytes a ray touches: it pays on trees of a few
/// thousand nodes (15–20 k triangles) and costs on trees of ~10⁵ nodes (the 1 M-triangle
/// MetalRoughSpheres, 27 MB decoded; `BENCHMARKS.md`). The limit sits between the two.
const WIDE_NODE_LIMIT: usize = 16_384;

/// Factor on the distance beyond which obvhs may cull a box (`1 + 2^-12`).
///
/// obvhs's box tests round `(min − o) · (1/d)` like any slab test, and the `f32` triangle test
/// rounds its `t` too, so a triangle whose computed `t` is a few ULPs below the best hit so far
/// can sit in a box whose computed entry is a few ULPs *above* it: with `tmax = t_best` that box
/// is culled and a near-tie (two faces meeting at an edge) resolved to the wrong, farther face.
/// BVH2 did this on ~0.3% of rays into a room with boxes standing on the floor; CWBVH's
/// outward-rounded 8-bit boxes hid it. Culling only beyond `t_best · (1 + 2^-12)` covers both
/// roundings (the triangle test's `t` is good to ~1e-5 relative even near grazing angles,
/// `tests/queries.rs`) and visits a negligible number of extra boxes; the hit itself is still
/// decided by exact comparisons of the triangle test's `t`.
pub const CULL_SLACK: f32 = 1.0 + 1.0 / 4096.0;

/// The scalar form of `safe_recip3`, which the traversal uses; kept as its test reference.
#[cfg(test)]
fn safe_recip(x: f32) -> f32 {
    const TINY: f32 = 7.888_609e-31; // 2^-100
    const HUGE: f32 = 1.267_650_6e30; // 2^100
    if x.abs() < TINY { HUGE.copysign(x) } else { 1.0 / x }
}

/// `1/x` per component, `|x| < 2^-100` (including ±0) mapped to `±2^100`, so that slab tests
/// never see `0 · ∞ = NaN` (`2^100` times any box extent and quantisation step stays finite in
/// `f32`); one vector division (the same IEEE quotient per lane).
#[inline(always)]
pub(crate) fn safe_recip3(d: Vec3A) -> Vec3A {
    const TINY: f32 = 7.888_609e-31; // 2^-100
    const HUGE: f32 = 1.267_650_6e30; // 2^100
    let tiny = d.abs().cmplt(Vec3A::splat(TINY));
    Vec3A::select(tiny, Vec3A::splat(HUGE).copysign(d), Vec3A::ONE / d)
}

/// `2^-m` with `m ∈ [0, 64]` the smallest integer such that obvhs's `1e-4` cut-off becomes
/// `1e-4 · 2^-m ≤ 2^-40 · max_abs` (see [`Bvh::obvhs_ray`]).
fn direction_scale(max_abs: f32) -> f32 {
    let extent = max_abs.max(f32::MIN_POSITIVE);
    let need = 1e-4 * (2.0f64).powi(40) / extent as f64;
    let m = need.log2().ceil().clamp(0.0, 64.0) as i32;
    (2.0f32).powi(-m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn direction_scale_is_a_power_of_two_in_range() {
        for &e in &[0.0f32, 1e-30, 1e-3, 1.0, 1e5, 1e30] {
            let s = direction_scale(e);
            assert!(s > 0.0 && s <= 1.0, "{e}: {s}");
            assert_eq!(s.to_bits() & 0x007f_ffff, 0, "{e}: {s} not a power of two");
            if e > 1e-20 && e < 1e10 {
                assert!(1e-4 * s <= e * (2.0f32).powi(-40), "{e}: {s}");
            }
        }
    }

    #[test]
    fn safe_recip_is_finite_and_signed() {
        assert_eq!(safe_recip(0.0), 1.267_650_6e30);
        assert_eq!(safe_recip(-0.0), -1.267_650_6e30);
        assert_eq!(safe_recip(0.5), 2.0);
        for x in [0.0f32, -0.0, 0.5, -3.0, 1e-31, -1e-29, 7.888_609e-31, f32::MAX, 1e-45] {
            let v = safe_recip3(Vec3A::new(x, -x, 1.0));
            assert_eq!(
                v.to_array().map(f32::to_bits),
                [safe_recip(x), safe_recip(-x), 1.0].map(f32::to_bits)
            );
        }
    }

    /// The queries give the same hits, bit for bit, with either node test: on this CPU's
    /// choice (`closest_hit`, `occluded`: the AVX2 versions where the CPU has it) and with the
    /// 4-lane test forced, over a soup of 3 000 random triangles (scales from 1e-3 to 1e3) and
    /// 20 000 rays from inside and outside it, some with zero and `-0.0` components. On a CPU
    /// without AVX2 both sides are the 4-lane test (it says so).
    #[test]
    fn node_tests_give_the_same_hits() {
        if !wide_node_test_available() {
            eprintln!("node_tests_give_the_same_hits: no AVX2 here, both sides take the 4-lane test");
        }
        let mut r = furnace_tests::Rng::new(0x8_1a2e);
        for scale in [1e-3f32, 1.0, 1e3] {
            let p = |r: &mut furnace_tests::Rng| r.vec3(Vec3::splat(-1.0), Vec3::ONE) * scale;
            let soup: Vec<[Vec3; 3]> = (0..3000)
                .map(|_| {
                    let c = p(&mut r);
                    [c, c + 0.1 * p(&mut r), c + 0.1 * p(&mut r)]
                })
                .collect();
            let bvh = Bvh::build(&soup);
            let (mut hits, mut blocked) = (0, 0);
            for i in 0..20_000 {
                let o = p(&mut r) * if i % 2 == 0 { 1.0 } else { 3.0 };
                let mut d = r.vec3(Vec3::splat(-1.0), Vec3::ONE);
                match i % 5 {
                    0 => d.x = 0.0,
                    1 => d.z = -0.0,
                    _ => {}
                }
                let t_max = if i % 3 == 0 { f32::INFINITY } else { r.range(0.0, 2.0) * scale };
                let (o, d) = (Vec3A::from(o), Vec3A::from(d));
                let chosen = bvh.closest_hit_a(o, d, t_max, |_, _| true);
                let four = bvh.closest_hit_with::<false>(o, d, t_max, |_, _| true);
                assert_eq!(chosen, four, "scale {scale}, ray {i}: {o} {d} {t_max}");
                let chosen = bvh.occluded_a(o, d, t_max, |_, _| true);
                assert_eq!(chosen, bvh.occluded_with::<false>(o, d, t_max, |_, _| true), "ray {i}");
                hits += usize::from(four.is_some());
                blocked += usize::from(chosen);
            }
            assert!(hits > 2000 && blocked > 2000, "scale {scale}: {hits} hits, {blocked} blocked");
        }
    }

    #[test]
    fn negative_zero_direction_components_hit() {
        // A direction component of -0.0 has the reciprocal -2^100: the box test must treat it
        // as negative (it once took the near plane from `d < 0` and missed every box).
        let floor = [[Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0)]];
        let bvh = Bvh::build(&floor);
        for dir in [Vec3::new(-0.0, -1.0, -0.0), Vec3::new(0.0, -1.0, -0.0), Vec3::new(-0.0, -1.0, 0.0)] {
            let hit = bvh.closest_hit(Vec3::new(0.1, 1.0, 0.1), dir, f32::INFINITY);
            assert_eq!(hit.map(|h| h.t), Some(1.0), "{dir:?}");
            assert!(bvh.occluded(Vec3::new(0.1, 1.0, 0.1), dir, f32::INFINITY), "{dir:?}");
        }
    }
}
