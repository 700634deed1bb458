//! Closest-hit, any-hit and alpha-masked queries against brute force, on generated and real
//! meshes, for both layouts and every build preset.
//!
//! The reference is the crate's own `f32` Möller–Trumbore run over every triangle, so the BVH
//! must agree **bit for bit** (same `t`; the same triangle, or one hit at exactly the same `t`
//! — a ray through a shared edge). An independent `f64` reference measures how far that `f32`
//! test is from the exact answer; its statistics go to
//! `target/test-output/accel/agreement.md`.

use crate::common;

use common::*;
use furnace_accel::{BuildOptions, BuildQuality, Bvh, Hit, Layout, intersect_triangle};
use glam::{Vec2, Vec3};
use std::fmt::Write as _;

const RAYS: usize = 2000;

fn meshes() -> Vec<(&'static str, Vec<Tri>)> {
    let data = data_dir();
    vec![
        ("random soup 3k", random_soup(3000, 0.15, 1)),
        ("sphere 8k", sphere(5)),
        ("cornell room", cornell_room(8)),
        ("Box.glb", load_gltf(&data.join("Box/glTF-Binary/Box.glb")).expect("Box.glb")),
        ("CornellBox-cetra", load_gltf(&data.join("CornellBox-cetra/cornell_box.gltf")).expect("cetra")),
    ]
}

/// Masks exercised: every third triangle cut out entirely, and half of each triangle cut out
/// by its barycentrics (as an alpha texture would).
fn mask_by_id(id: u32, _: Vec2) -> bool {
    !id.is_multiple_of(3)
}
fn mask_by_uv(_: u32, uv: Vec2) -> bool {
    uv.x + uv.y < 0.5
}

/// True if `got` is an exact answer that `reference` would also give.
fn same(tris: &[Tri], o: Vec3, d: Vec3, got: Option<Hit>, reference: Option<Hit>) -> bool {
    match (got, reference) {
        (None, None) => true,
        (Some(g), Some(r)) => {
            g.t == r.t
                && (g.triangle == r.triangle
                    || intersect_triangle(o, d, tris[g.triangle as usize], f32::INFINITY)
                        .is_some_and(|h| h.t == r.t && h.barycentrics == g.barycentrics))
                && (g.triangle != r.triangle || g.barycentrics == r.barycentrics)
        }
        _ => false,
    }
}

struct Reference {
    ray: (Vec3, Vec3),
    closest: Option<Hit>,
    closest_id_masked: Option<Hit>,
    closest_uv_masked: Option<Hit>,
    /// A shadow-ray length and whether anything lies closer than it.
    shadow: (f32, bool),
}

#[test]
fn queries_match_brute_force_for_every_layout_and_preset() {
    let mut report = String::from(
        "| mesh | triangles | rays | f32 hits | f64 agrees (same triangle, abs. t err ≤ 1e-6 · max(t, ‖o‖)) | hit/miss differs from f64 | other triangle | max t err / max(t, ‖o‖) |\n|---|---|---|---|---|---|---|---|\n",
    );
    let mut failures = Vec::new();
    for (name, tris) in meshes() {
        let (lo, hi) = bounds(&tris);
        let rays = random_rays(lo, hi, RAYS, 7);
        let mut rng = Rng::new(11);
        let refs: Vec<Reference> = rays
            .iter()
            .map(|&(o, d)| {
                let closest = brute_f32(&tris, o, d, f32::INFINITY, |_, _| true);
                let len = closest.map_or(f32::INFINITY, |h| h.t * rng.range(0.5, 1.5));
                let shadow = (len, brute_f32(&tris, o, d, len, |_, _| true).is_some());
                Reference {
                    ray: (o, d),
                    closest,
                    closest_id_masked: brute_f32(&tris, o, d, f32::INFINITY, mask_by_id),
                    closest_uv_masked: brute_f32(&tris, o, d, f32::INFINITY, mask_by_uv),
                    shadow,
                }
            })
            .collect();

        // Independent f64 check of the f32 triangle test itself (layout-independent).
        let (mut hits, mut agree, mut hit_miss, mut other, mut max_rel) = (0, 0, 0, 0, 0.0f64);
        for r in &refs {
            let (o, d) = r.ray;
            match (r.closest, brute_f64(&tris, o, d)) {
                (Some(h), Some((id, t))) => {
                    hits += 1;
                    let rel = (h.t as f64 - t).abs() / t.max(o.length() as f64);
                    if id == h.triangle {
                        max_rel = max_rel.max(rel);
                        if rel <= 1e-6 {
                            agree += 1;
                        }
                    } else if rel <= 1e-6 {
                        agree += 1; // a shared edge: same t, either triangle is right
                    } else {
                        other += 1;
                    }
                }
                (None, None) => {}
                _ => hit_miss += 1,
            }
        }
        writeln!(
            report,
            "| {name} | {} | {RAYS} | {hits} | {agree} | {hit_miss} | {other} | {max_rel:.2e} |",
            tris.len()
        )
        .unwrap();

        for layout in [Layout::Cwbvh, Layout::Bvh2] {
            for quality in BuildQuality::ALL {
                let bvh = Bvh::build_with(&tris, BuildOptions { layout, quality: Some(quality) });
                let mut bad = 0;
                for (i, r) in refs.iter().enumerate() {
                    let (o, d) = r.ray;
                    let checks = [
                        ("closest", same(&tris, o, d, bvh.closest_hit(o, d, f32::INFINITY), r.closest)),
                        (
                            "closest, id mask",
                            same(
                                &tris,
                                o,
                                d,
                                bvh.closest_hit_masked(o, d, f32::INFINITY, mask_by_id),
                                r.closest_id_masked,
                            ),
                        ),
                        (
                            "closest, uv mask",
                            same(
                                &tris,
                                o,
                                d,
                                bvh.closest_hit_masked(o, d, f32::INFINITY, mask_by_uv),
                                r.closest_uv_masked,
                            ),
                        ),
                        ("occluded", bvh.occluded(o, d, r.shadow.0) == r.shadow.1),
                        (
                            "occluded, id mask",
                            bvh.occluded_masked(o, d, f32::INFINITY, mask_by_id)
                                == r.closest_id_masked.is_some(),
                        ),
                        (
                            "occluded, uv mask",
                            bvh.occluded_masked(o, d, f32::INFINITY, mask_by_uv)
                                == r.closest_uv_masked.is_some(),
                        ),
                    ];
                    for (what, ok) in checks {
                        if !ok {
                            bad += 1;
                            if failures.len() < 20 {
                                failures.push(format!(
                                    "{name} {layout:?} {quality:?} ray {i} (o = {o}, d = {d}) {what}: bvh {:?} vs brute {:?}",
                                    bvh.closest_hit(o, d, f32::INFINITY),
                                    r.closest
                                ));
                            }
                        }
                    }
                }
                if bad > 0 {
                    failures.push(format!("{name} {layout:?} {quality:?}: {bad} disagreements"));
                }
            }
        }
    }
    let path = output_dir().join("agreement.md");
    std::fs::write(&path, &report).unwrap();
    println!("{report}\n(written to {})", path.display());
    assert!(failures.is_empty(), "BVH disagrees with brute force:\n{}", failures.join("\n"));
}

/// The f32 test against an f64 one on the same vertices: the closest triangle and its `t`.
///
/// An `f32` hit point is only as precise as the coordinates around it, so the error is measured
/// relative to `max(t, |o|)` (the ray's length scale), not to `t` alone: a ray starting a
/// millimetre from the surface at |o| = 1 cannot have `t` to 1e-6 of a millimetre.
#[test]
fn f32_triangle_test_agrees_with_f64() {
    let tris = sphere(4);
    let (lo, hi) = bounds(&tris);
    let rays = random_rays(lo, hi, 20_000, 3);
    let bvh = Bvh::build(&tris);
    let (mut n, mut within, mut worst, mut other) = (0, 0, 0.0f64, Vec::new());
    for (o, d) in rays {
        let got = bvh.closest_hit(o, d, f32::INFINITY);
        let exact = brute_f64(&tris, o, d);
        if let (Some(g), Some((id, t))) = (got, exact) {
            n += 1;
            let rel = (g.t as f64 - t).abs() / t.max(o.length() as f64);
            worst = worst.max(rel);
            if rel <= 1e-6 {
                within += 1;
            }
            if g.triangle != id && rel > 1e-6 {
                other.push(format!("o = {o}, d = {d}: f32 ({}, {}) vs f64 ({id}, {t})", g.triangle, g.t));
            }
        }
    }
    println!("{within} of {n} hits within 1e-6 relative; worst {worst:.2e}");
    assert!(n > 10_000, "too few hits ({n}) for the statistic to mean anything");
    assert!(other.is_empty(), "a different triangle, not at a tie:\n{}", other.join("\n"));
    // 1e-6 is ~8 f32 ULPs; 99.9% of hits must meet it, and every hit 1e-5 (grazing rays
    // amplify the rounding of e1·(d×e2) by 1/cos θ).
    assert!(within as f64 >= 0.999 * n as f64, "only {within} of {n} hits within 1e-6");
    assert!(worst <= 1e-5, "worst relative t error {worst:.2e}");
}

/// Trees of more than 16,384 CWBVH nodes keep obvhs's compact nodes and its own box test (the
/// small-tree path converts them to float boxes, see `WIDE_NODE_LIMIT`); the meshes above are
/// all below that. This covers the large path with one 200k-triangle soup, fewer rays (brute
/// force costs 2·10⁵ tests a ray), the same bit-exact criterion.
#[test]
fn large_trees_match_brute_force() {
    let tris = random_soup(200_000, 0.02, 7);
    let bvh = Bvh::build(&tris);
    assert!(bvh.gpu_nodes().len() > 16_384, "only {} nodes: not the large-tree path", bvh.gpu_nodes().len());
    let (lo, hi) = bounds(&tris);
    let mut mismatches = Vec::new();
    for (k, (o, d)) in random_rays(lo, hi, 300, 11).into_iter().enumerate() {
        let reference = brute_f32(&tris, o, d, f32::INFINITY, |_, _| true);
        let got = bvh.closest_hit(o, d, f32::INFINITY);
        if !same(&tris, o, d, got, reference) {
            mismatches.push(format!("ray {k}: closest {got:?} vs {reference:?}"));
        }
        let masked_ref = brute_f32(&tris, o, d, f32::INFINITY, mask_by_id);
        let masked = bvh.closest_hit_masked(o, d, f32::INFINITY, mask_by_id);
        if !same(&tris, o, d, masked, masked_ref) {
            mismatches.push(format!("ray {k}: masked {masked:?} vs {masked_ref:?}"));
        }
        if let Some(r) = reference {
            // A shadow ray just short of and just past the closest hit.
            if bvh.occluded(o, d, r.t * 0.999) || !bvh.occluded(o, d, r.t * 1.001) {
                mismatches.push(format!("ray {k}: occlusion disagrees around t = {}", r.t));
            }
        }
    }
    assert!(mismatches.is_empty(), "{} mismatches:\n{}", mismatches.len(), mismatches.join("\n"));
}
