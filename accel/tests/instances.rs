//! The two-level structure ([`TwoLevel`]) against brute force over the same triangles placed in
//! world space, and ray offsets across instance transforms.

use crate::common;

use common::*;
use furnace_accel::{TwoLevel, intersect_triangle, offset_ray_origin};
use glam::{Affine3A, Quat, Vec2, Vec3};
use std::fmt::Write as _;

/// An indexed store: world triangles first, then each mesh's, with their ranges.
struct Store {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    world: std::ops::Range<u32>,
    meshes: Vec<std::ops::Range<u32>>,
}

fn store(world: &[Tri], meshes: &[Vec<Tri>]) -> Store {
    let mut s = Store { positions: Vec::new(), triangles: Vec::new(), world: 0..0, meshes: Vec::new() };
    let mut add = |tris: &[Tri]| {
        let start = s.triangles.len() as u32;
        for t in tris {
            let base = s.positions.len() as u32;
            s.positions.extend_from_slice(t);
            s.triangles.push([base, base + 1, base + 2]);
        }
        start..s.triangles.len() as u32
    };
    let world = add(world);
    let ranges: Vec<_> = meshes.iter().map(|m| add(m)).collect();
    s.world = world;
    s.meshes = ranges;
    s
}

/// A random placement: rotation, per-axis scale in `[1, ratio]` (mirrored on one axis in a
/// quarter of them), translation within ±`reach`.
fn placement(rng: &mut Rng, ratio: f32, reach: f32) -> Affine3A {
    let axis = rng.unit_vector();
    let rotation = Quat::from_axis_angle(axis, rng.range(0.0, std::f32::consts::TAU));
    let mut scale = Vec3::new(rng.range(1.0, ratio), rng.range(1.0, ratio), rng.range(1.0, ratio));
    if rng.chance(0.25) {
        scale.y = -scale.y;
    }
    let translation = rng.vec3(Vec3::splat(-reach), Vec3::splat(reach));
    Affine3A::from_scale_rotation_translation(scale, rotation, translation)
}

/// The world-space triangles of every instance (and the world ones), with the (instance,
/// triangle id) each came from, for brute force.
fn flattened(s: &Store, instances: &[(u32, Affine3A)]) -> Vec<(Tri, Option<u32>, u32)> {
    let tri = |t: u32| s.triangles[t as usize].map(|v| s.positions[v as usize]);
    let mut out: Vec<_> = s.world.clone().map(|t| (tri(t), None, t)).collect();
    for (i, &(mesh, a)) in instances.iter().enumerate() {
        for t in s.meshes[mesh as usize].clone() {
            out.push((tri(t).map(|v| a.transform_point3(v)), Some(i as u32), t));
        }
    }
    out
}

/// Barycentric distance of a hit to its triangle's border (hits this close to an edge may go
/// either way between the object-space and the world-space test).
fn edge_distance(b: Vec2) -> f32 {
    b.x.min(b.y).min(1.0 - b.x - b.y)
}

/// Closest hits and occlusion of 20 000 random rays through 80 placements of three meshes
/// (rotated, scaled up to 8× per axis, a quarter mirrored) among world triangles agree with
/// brute force over the placed triangles: the same triangle of the same instance at the same
/// point (within 1e-5 of the coordinates' magnitude: the object-space test and the transforms
/// round differently, by some ULPs of it), except where the reference's hit lies within 1e-4
/// (barycentric) of an edge of its triangle, or two candidates are within that tolerance of
/// each other: rounding decides those. Masks filter in both.
#[test]
fn two_level_queries_match_brute_force() {
    let mut rng = Rng::new(0x5eed_1234);
    let meshes = vec![sphere(2), random_soup(150, 0.3, 7), cuboid(Vec3::splat(-0.5), Vec3::splat(0.5))];
    let world: Vec<Tri> = random_soup(200, 2.0, 11).iter().map(|t| t.map(|v| v * 20.0 - 10.0)).collect();
    let s = store(&world, &meshes);
    let instances: Vec<(u32, Affine3A)> =
        (0..80).map(|_| (rng.below(3), placement(&mut rng, 8.0, 12.0))).collect();
    let two = TwoLevel::build(&s.positions, &s.triangles, s.world.clone(), &s.meshes, &instances);
    let placed = flattened(&s, &instances);
    let mask =
        |instance: Option<u32>, t: u32| !(instance.unwrap_or(1).is_multiple_of(2) && t.is_multiple_of(3));
    let (mut checked, mut hits, mut close_calls) = (0, 0, 0);
    for k in 0..20_000 {
        let origin = rng.vec3(Vec3::splat(-15.0), Vec3::splat(15.0));
        let dir = if k % 2 == 0 {
            let (_, a) = instances[rng.index(instances.len())];
            a.translation.into()
        } else {
            rng.unit_vector()
        } - origin * (k % 2 == 0) as u32 as f32;
        let masked = k % 3 == 0;
        let t_max = if k % 5 == 0 { 10.0 } else { f32::INFINITY };
        let mut candidates: Vec<(f32, Option<u32>, u32, Vec2)> = placed
            .iter()
            .filter(|(_, i, t)| !masked || mask(*i, *t))
            .filter_map(|&(tri, i, t)| {
                intersect_triangle(origin, dir, tri, t_max).map(|h| (h.t, i, t, h.barycentrics))
            })
            .collect();
        candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
        let got = if masked {
            two.closest_hit_masked(origin, dir, t_max, |i, t, _| mask((i != u32::MAX).then_some(i), t))
        } else {
            two.closest_hit(origin, dir, t_max)
        };
        let occluded = if masked {
            two.occluded_masked(origin, dir, t_max, |i, t, _| mask((i != u32::MAX).then_some(i), t))
        } else {
            two.occluded(origin, dir, t_max)
        };
        checked += 1;
        // The tolerance of a distance along the ray: 1e-5 of the coordinates' magnitude there.
        let len = dir.length();
        let tolerance = |t: f32| 1e-5 * (origin.abs().max_element() + t * len).max(1.0) / len;
        let ambiguous = |c: &[(f32, Option<u32>, u32, Vec2)]| {
            c.first().is_some_and(|f| edge_distance(f.3) < 1e-4 || (f.0 - t_max).abs() < tolerance(f.0))
                || c.get(1).is_some_and(|s| (s.0 - c[0].0) <= tolerance(c[0].0))
        };
        if ambiguous(&candidates) {
            close_calls += 1;
            continue;
        }
        match (candidates.first(), got) {
            (None, None) => assert!(!occluded, "ray {origin} {dir}: occluded without a hit"),
            (Some(&(t, i, tri, _)), Some(h)) => {
                hits += 1;
                assert_eq!((h.instance, h.hit.triangle), (i, tri), "ray {origin} {dir}: {h:?} vs t {t}");
                assert!((h.hit.t - t).abs() <= tolerance(t), "ray {origin} {dir}: t {} vs {t}", h.hit.t);
                assert!(occluded, "ray {origin} {dir}: a hit but not occluded");
            }
            (reference, got) => panic!("ray {origin} {dir}: brute force {reference:?}, two-level {got:?}"),
        }
    }
    println!("{checked} rays, {hits} hits compared, {close_calls} too close to call");
    // The comparison means something only if many rays hit and few are set aside.
    assert!(hits > checked / 5, "{hits} hits of {checked}");
    assert!(close_calls < checked / 100, "{close_calls} close calls of {checked}");
}

/// Rays leaving a placed sphere at 89.9° from its normal, their origins offset in world space,
/// never hit the triangle they leave: for placements whose scales differ by up to 16× per axis,
/// translated up to 10⁴ away, at scene scales 10⁻² to 10³. The hit point is placed as an
/// integrator places it (barycentric interpolation in object space, then the transform), the
/// normal is the world triangle's. The table goes to
/// `target/test-output/accel/instance_offsets.md`.
#[test]
fn offsets_hold_across_instance_transforms() {
    let mesh = sphere(3);
    let s = store(&[], std::slice::from_ref(&mesh));
    let mut table = String::from(
        "Self-hits of 20 000 rays at 89.9° from the normal leaving instances of a sphere\n\n\
         | scale ratio | translation | scene scale | self-hits |\n|---|---|---|---|\n",
    );
    let mut total = 0;
    let (cos, sin) = (89.9f32.to_radians().cos(), 89.9f32.to_radians().sin());
    for (k, &(ratio, reach, scale)) in [
        (1.0f32, 0.0f32, 1.0f32),
        (4.0, 100.0, 1.0),
        (16.0, 100.0, 1.0),
        (4.0, 1e4, 1.0),
        (16.0, 1e4, 1e-2),
        (16.0, 1e4, 1e3),
    ]
    .iter()
    .enumerate()
    {
        let mut rng = Rng::new(900 + k as u64);
        let instances: Vec<(u32, Affine3A)> = (0..16)
            .map(|_| {
                let a = placement(&mut rng, ratio, reach);
                (0, Affine3A::from_scale(Vec3::splat(scale)) * a)
            })
            .collect();
        let two = TwoLevel::build(&s.positions, &s.triangles, 0..0, &s.meshes, &instances);
        let mut self_hits = 0;
        for _ in 0..20_000 {
            let i = rng.index(instances.len());
            let a = instances[i].1;
            let id = rng.index(mesh.len());
            let [p0, p1, p2] = mesh[id];
            let (mut u, mut v) = (rng.f32(), rng.f32());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let p = a.transform_point3(p0 * (1.0 - u - v) + p1 * u + p2 * v);
            let [w0, w1, w2] = [p0, p1, p2].map(|q| a.transform_point3(q));
            let mut n = (w1 - w0).cross(w2 - w0).normalize();
            if rng.chance(0.5) {
                n = -n;
            }
            let r = rng.unit_vector();
            let dir = n * cos + (r - n * r.dot(n)).normalize() * sin;
            let hit = two.closest_hit(offset_ray_origin(p, n), dir, f32::INFINITY);
            self_hits +=
                usize::from(hit.is_some_and(|h| h.instance == Some(i as u32) && h.hit.triangle == id as u32));
        }
        writeln!(table, "| {ratio} | {reach:e} | {scale:e} | {self_hits} |").unwrap();
        total += self_hits;
    }
    let path = output_dir().join("instance_offsets.md");
    std::fs::write(&path, &table).unwrap();
    println!("{table}\n(written to {})", path.display());
    assert_eq!(total, 0, "offset rays hit their own triangle:\n{table}");
}
