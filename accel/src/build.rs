//! The tree builds behind [`crate::Bvh`]: obvhs's PLOC, reinsertion and leaf collapse, step for
//! step as its helpers run them, the CWBVH conversion (in parallel for a large tree:
//! [`crate::convert`]), and the depth checks that keep obvhs's validators and traversal where
//! they hold.

use obvhs::{
    BvhBuildParams,
    bvh2::{Bvh2, leaf_collapser::collapse, reinsertion::ReinsertionOptimizer},
    cwbvh::CwBvh,
    ploc::PlocBuilder,
    splits::split_aabbs_preset,
    triangle::Triangle,
};

/// The BVH2 both layouts start from: obvhs's `build_*_from_tris` helpers up to their shared
/// point (optional spatial pre-splits, PLOC, reinsertion), step for step, so that trees are
/// the same as the helpers'.
///
/// The helpers are not called because in builds with debug assertions (`cargo test`) they end
/// with obvhs's validators, which assert that a CWBVH is less than 32 levels deep
/// (`CwBvh::validate`; obvhs's traversal stack size): a valid but deep tree, such as the one over
/// a few thousand concentric triangles, would panic there. [`validate_if_shallow`] runs the same
/// validators where they hold.
pub(crate) fn build_ploc(triangles: &[Triangle], config: &BvhBuildParams) -> Bvh2 {
    let mut bvh2 = if config.pre_split {
        let mut largest_half_area = 0.0f32;
        let mut avg_area = 0.0f32;
        let mut aabbs: Vec<_> = triangles
            .iter()
            .map(|tri| {
                let aabb = tri.aabb();
                let half_area = aabb.half_area();
                largest_half_area = half_area.max(largest_half_area);
                avg_area += half_area;
                aabb
            })
            .collect();
        let mut indices: Vec<u32> = (0..triangles.len() as u32).collect();
        avg_area /= triangles.len() as f32;
        split_aabbs_preset(&mut aabbs, &mut indices, triangles, avg_area, largest_half_area);
        PlocBuilder::with_capacity(aabbs.len()).build(
            config.ploc_search_distance,
            &aabbs,
            indices,
            config.sort_precision,
            config.search_depth_threshold,
        )
    } else {
        PlocBuilder::with_capacity(triangles.len()).build(
            config.ploc_search_distance,
            triangles,
            (0..triangles.len() as u32).collect(),
            config.sort_precision,
            config.search_depth_threshold,
        )
    };
    bvh2.uses_spatial_splits = config.pre_split;
    bvh2
}

/// obvhs's `build_cwbvh_from_tris` without its debug-build validation (see [`build_ploc`]).
pub(crate) fn build_cwbvh(triangles: &[Triangle], config: BvhBuildParams) -> CwBvh {
    let mut bvh2 = build_ploc(triangles, &config);
    ReinsertionOptimizer::default().run(&mut bvh2, config.reinsertion_batch_ratio, None);
    let cwbvh = crate::convert::to_cwbvh(&bvh2, config.max_prims_per_leaf.clamp(1, 3));
    validate_if_shallow(triangles, &config, &mut bvh2, Some(&cwbvh));
    cwbvh
}

/// obvhs's `build_bvh2_from_tris` without its debug-build validation (see [`build_ploc`]), and
/// with `max_depth` (the size of obvhs's BVH2 traversal stack) made to cover the final tree.
pub(crate) fn build_bvh2(triangles: &[Triangle], config: BvhBuildParams) -> Bvh2 {
    let mut bvh2 = build_ploc(triangles, &config);
    let mut reinsertion = ReinsertionOptimizer::default();
    reinsertion.run(&mut bvh2, config.reinsertion_batch_ratio, None);
    collapse(&mut bvh2, config.max_prims_per_leaf.clamp(1, 255), config.collapse_traversal_cost);
    reinsertion.run(
        &mut bvh2,
        config.reinsertion_batch_ratio * config.post_collapse_reinsertion_batch_ratio_multiplier,
        None,
    );
    validate_if_shallow(triangles, &config, &mut bvh2, None);
    bvh2
}

/// Makes `bvh2.max_depth` cover the tree, then, in builds with debug assertions, runs obvhs's
/// validators as its builder helpers do, where their depth assertion holds: on a CWBVH of
/// fewer than [`OBVHS_STACK`] levels (and its BVH2), the CWBVH one only where its absolute
/// tolerance holds (coordinates within ±2¹⁶). Deeper trees are valid input and are
/// traversed correctly; they are only not checked by obvhs's recursive validators.
fn validate_if_shallow(
    triangles: &[Triangle],
    config: &BvhBuildParams,
    bvh2: &mut Bvh2,
    cwbvh: Option<&CwBvh>,
) {
    // obvhs sizes the BVH2 traversal stack (`fast_stack!`) from `max_depth`, and its validator
    // asserts `depth < max_depth`; PLOC sets it, but reinsertion can deepen the tree.
    let depth = bvh2_depth(bvh2);
    bvh2.max_depth = bvh2.max_depth.max(depth + 1);
    if cfg!(debug_assertions) && cwbvh.is_none_or(|c| cwbvh_depth(c) < OBVHS_STACK) {
        bvh2.validate(triangles, false, config.pre_split);
        // The CWBVH validator compares quantisation origins with their parent's bounds to an
        // absolute 1e-5, which f32 rounding exceeds once coordinates reach ~2^20 in a tree that
        // also holds small boxes (measured: a triangle of 2^20 among 300 of size 0.2 failed it
        // in 5 of 72 builds, of 2^24 in 48; `tests/degenerate.rs::huge_triangles_are_skipped_not_a_panic`
        // checks such trees against brute force instead).
        let within = |t: &Triangle| [t.v0, t.v1, t.v2].iter().all(|v| v.abs().max_element() <= 65_536.0);
        if let Some(c) = cwbvh
            && triangles.iter().all(within)
        {
            c.validate(triangles, false);
        }
    }
}

/// The number of node levels of a BVH2 (a lone leaf root: 1), without recursion.
pub(crate) fn bvh2_depth(bvh2: &Bvh2) -> usize {
    bvh2_depth_below(bvh2, 0, 1)
}

/// The depth of the subtree at `index` (at depth `depth`): its top levels' subtrees in
/// parallel, each below them with a stack (no recursion in the deep, unbalanced parts).
fn bvh2_depth_below(bvh2: &Bvh2, index: usize, depth: usize) -> usize {
    const PARALLEL_LEVELS: usize = 8;
    match bvh2.nodes.get(index) {
        Some(node) if depth <= PARALLEL_LEVELS && !node.is_leaf() => {
            let first = node.first_index as usize;
            let (a, b) = rayon::join(
                || bvh2_depth_below(bvh2, first, depth + 1),
                || bvh2_depth_below(bvh2, first + 1, depth + 1),
            );
            a.max(b)
        }
        _ => {
            let mut deepest = 0;
            let mut stack = vec![(index, depth)];
            while let Some((index, depth)) = stack.pop() {
                let Some(node) = bvh2.nodes.get(index) else { continue };
                deepest = deepest.max(depth);
                if !node.is_leaf() {
                    let first = node.first_index as usize;
                    stack.push((first, depth + 1));
                    stack.push((first + 1, depth + 1));
                }
            }
            deepest
        }
    }
}

/// The number of node levels of a CWBVH (a root with only leaf children: 1), without recursion.
pub(crate) fn cwbvh_depth(cwbvh: &CwBvh) -> usize {
    let mut deepest = 0;
    let mut stack = vec![(0usize, 1usize)];
    while let Some((index, depth)) = stack.pop() {
        let Some(node) = cwbvh.nodes.get(index) else { continue };
        deepest = deepest.max(depth);
        for k in 0..node.imask.count_ones() as usize {
            stack.push((node.child_base_idx as usize + k, depth + 1));
        }
    }
    deepest
}

/// obvhs's CWBVH traversal stack size (`cwbvh::TRAVERSAL_STACK_SIZE`): its validator asserts a
/// depth below it, and its traversal loses hits in trees deeper than it.
pub(crate) const OBVHS_STACK: usize = 32;
