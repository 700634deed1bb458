//! Trees deeper than obvhs's 32-level limits: building never panics (obvhs's debug-build
//! validator asserted a CWBVH depth below 32), and queries agree with brute force.

use crate::common;

use common::*;
use furnace_accel::{BuildOptions, BuildQuality, Bvh, Layout, intersect_triangle};
use glam::Vec3;

/// `n` concentric, coplanar, similar triangles growing linearly: every box contains the previous
/// one and all share a centroid, so PLOC peels them off nearly one at a time (a CWBVH of several
/// hundred levels at n = 4000; obvhs's validator panicked on every preset).
fn concentric(n: usize) -> Vec<Tri> {
    (0..n)
        .map(|k| {
            let s = 1.0 + k as f32;
            [Vec3::new(-s, -s, 0.0), Vec3::new(s, -s, 0.0), Vec3::new(0.0, s, 0.0)]
        })
        .collect()
}

/// The CWBVH's number of levels, from the GPU node buffer.
fn cwbvh_levels(bvh: &Bvh) -> usize {
    let nodes = bvh.gpu_nodes();
    let (mut level, mut levels) = (vec![0u32], 0);
    while !level.is_empty() {
        levels += 1;
        level = level
            .iter()
            .flat_map(|&i| {
                let n = &nodes[i as usize];
                (0..n.imask.count_ones()).map(move |c| n.child_base_idx + c)
            })
            .collect();
    }
    levels
}

#[test]
fn four_thousand_concentric_triangles_build_and_trace_exactly() {
    let tris = concentric(4000);
    let mut rng = Rng::new(11);
    // Rays from both sides of the plane z = 0, most of them through it; every closest hit is
    // a tie between all triangles containing the point, so only `t` and a valid triangle are
    // compared.
    let rays: Vec<(Vec3, Vec3)> = (0..300)
        .map(|_| {
            let o = Vec3::new(rng.range(-50.0, 50.0), rng.range(-50.0, 50.0), rng.range(-5.0, 5.0));
            let target = Vec3::new(rng.range(-4000.0, 4000.0), rng.range(-4000.0, 4000.0), 0.0);
            (o, (target - o).normalize())
        })
        .collect();
    for layout in [Layout::Cwbvh, Layout::Bvh2] {
        for quality in BuildQuality::ALL {
            let bvh = Bvh::build_with(&tris, BuildOptions { layout, quality: Some(quality) });
            if layout == Layout::Cwbvh {
                let levels = cwbvh_levels(&bvh);
                assert!(levels > 32, "{quality:?}: only {levels} levels, the test needs a deep tree");
            }
            for &(o, d) in &rays {
                let brute = tris
                    .iter()
                    .filter_map(|t| intersect_triangle(o, d, *t, f32::INFINITY))
                    .map(|h| h.t)
                    .reduce(f32::min);
                let got = bvh.closest_hit(o, d, f32::INFINITY);
                assert_eq!(got.map(|h| h.t), brute, "{layout:?} {quality:?}: ray {o} {d}");
                if let Some(h) = got {
                    let again = intersect_triangle(o, d, tris[h.triangle as usize], f32::INFINITY);
                    assert_eq!(again.map(|a| a.t), Some(h.t), "{layout:?} {quality:?}: ray {o} {d}");
                }
                for t_max in [1.0f32, 100.0] {
                    let brute_any = tris.iter().any(|t| intersect_triangle(o, d, *t, t_max).is_some());
                    assert_eq!(
                        bvh.occluded(o, d, t_max),
                        brute_any,
                        "{layout:?} {quality:?}: ray {o} {d} {t_max}"
                    );
                }
            }
        }
    }
}
