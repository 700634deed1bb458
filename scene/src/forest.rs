//! [`forest`]: a seeded forest of instanced plants on rolling terrain, the instancing stress
//! scene (`forest:N` on the command line).

use crate::builtin::lambert;
use crate::geometry::{Geometry, oct_encode};
use crate::{Camera, Instance, Instancing, Light, Material, Scene, Sky, Sun};
use glam::{Mat4, Quat, Vec3};
use std::f32::consts::{PI, TAU};

/// Trees per square metre of terrain: one per 36 m² (a managed forest's density).
const AREA_PER_TREE: f32 = 36.0;

/// Terrain cells per side.
const TERRAIN_CELLS: u32 = 256;

/// A forest of `instances` plants (at least 1) on square rolling terrain whose area grows with
/// them (36 m² a plant), lit by a sun low in the sky and a pale blue sky. Three plant meshes,
/// each stored once: a conifer (trunk and five cones, about 2·10⁴ triangles), a broadleaf tree
/// (trunk and a lumpy crown, about 10⁵) and a bush (about 10⁴); each instance picks one, a turn
/// about the vertical and a scale of 0.7–1.3, from a hash of `seed` and its index. The terrain
/// (131 072 triangles) is in world space. Deterministic: the same arguments give the same scene.
pub fn forest(instances: u32, seed: u64) -> Scene {
    let instances = instances.max(1);
    let half = 0.5 * (instances as f32 * AREA_PER_TREE).sqrt().max(20.0);
    let mut g = Geometry::default();
    // Terrain: gentle hills of a few metres.
    let height = |x: f32, z: f32| {
        let k = 1.0 / half.max(50.0);
        2.5 * (x * 0.031 + 1.3).sin() * (z * 0.027 - 0.4).cos()
            + 1.2 * (x * 0.11 + z * 0.07).sin()
            + 40.0 * k * (x * k * 3.0).sin() * (z * k * 2.0).cos()
    };
    let n = TERRAIN_CELLS;
    surface(&mut g, n, n, 0, |u, v| {
        let (x, z) = (-half + 2.0 * half * u, -half + 2.0 * half * v);
        (Vec3::new(x, height(x, z), z), Vec3::Y)
    });
    let world = g.triangle_count() as u32;

    let mut meshes = Vec::new();
    let mut mesh = |g: &mut Geometry, build: &dyn Fn(&mut Geometry)| {
        let start = g.triangle_count() as u32;
        build(g);
        meshes.push(start..g.triangle_count() as u32);
    };
    // Conifer: a trunk and five stacked cones, 5 m tall.
    mesh(&mut g, &|g| {
        trunk(g, 0.18, 1.6);
        for k in 0..5 {
            let (y0, r) = (1.0 + 0.75 * k as f32, 1.5 - 0.25 * k as f32);
            surface(g, 64, 30, 2, |u, v| {
                let phi = TAU * u;
                let p = Vec3::new(r * (1.0 - v) * phi.cos(), y0 + 1.6 * v, r * (1.0 - v) * phi.sin());
                (p, Vec3::new(p.x, 0.4, p.z))
            });
        }
    });
    // Broadleaf: a trunk and a lumpy crown, 6 m tall.
    mesh(&mut g, &|g| {
        trunk(g, 0.22, 3.2);
        let centre = Vec3::new(0.0, 4.0, 0.0);
        surface(g, 316, 158, 2, |u, v| {
            let (phi, theta) = (TAU * u, PI * v);
            let d = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            // Both lumps vanish at the poles (sin 4θ, sin θ), where every column meets in one
            // point: lumps there would fold the crown's top into slivers facing inwards.
            let lumps = 1.0
                + 0.12 * (5.0 * phi).sin() * (4.0 * theta).sin()
                + 0.06 * (13.0 * phi + 9.0 * theta).sin() * theta.sin();
            (centre + d * Vec3::new(2.2, 1.8, 2.2) * lumps, d)
        });
    });
    // Bush: a squashed lumpy sphere, 1 m tall.
    mesh(&mut g, &|g| {
        let centre = Vec3::new(0.0, 0.45, 0.0);
        surface(g, 100, 50, 3, |u, v| {
            let (phi, theta) = (TAU * u, PI * v);
            let d = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            let lumps = 1.0 + 0.1 * (7.0 * phi).sin() * (5.0 * theta).sin();
            (centre + d * Vec3::new(0.9, 0.55, 0.9) * lumps, d)
        });
    });

    let placed: Vec<Instance> = (0..instances)
        .filter_map(|i| {
            let h = |k: u64| unit(hash(seed, u64::from(i), k));
            let (x, z) = (-half + 2.0 * half * h(0), -half + 2.0 * half * h(1));
            let mesh = (h(2) * 3.0) as u32 % 3;
            let turn = Quat::from_rotation_y(TAU * h(3));
            let scale = 0.7 + 0.6 * h(4);
            let at = Vec3::new(x, height(x, z) - 0.05, z);
            Instance::new(mesh, Mat4::from_scale_rotation_translation(Vec3::splat(scale), turn, at))
        })
        .collect();
    let materials = vec![
        lambert(Vec3::new(0.22, 0.26, 0.10)),
        lambert(Vec3::new(0.25, 0.16, 0.09)),
        lambert(Vec3::new(0.07, 0.28, 0.06)),
        lambert(Vec3::new(0.16, 0.36, 0.08)),
        Material::default(),
    ];
    // From just outside the forest's corner, above the trees.
    let eye = Vec3::new(-half * 1.02, height(-half * 1.02, -half * 1.02) + 10.0, -half * 1.02);
    let target = Vec3::new(0.0, height(0.0, 0.0), 0.0);
    let name = format!("<built-in forest, {instances} instances, seed {seed}>");
    Scene {
        name,
        geometry: g,
        instancing: Instancing { world_triangles: world, meshes, instances: placed },
        materials,
        textures: Vec::new(),
        images: Vec::new(),
        cameras: vec![Camera::look_at(eye, target, Vec3::Y, 0.9)],
        lights: vec![
            Light::Sun(Sun::delta(Vec3::new(0.6, -0.45, 0.65), Vec3::new(3.0, 2.75, 2.35))),
            Light::Sky(Sky { radiance: Vec3::new(0.18, 0.25, 0.38) }),
        ],
        warnings: Vec::new(),
        dropped_triangles: 0,
        extensions: Vec::new(),
        variants: Vec::new(),
        animations: Vec::new(),
        posed_by: None,
    }
}

/// A cylinder of radius `r` from the ground to `height`, material 1 (bark).
fn trunk(g: &mut Geometry, r: f32, height: f32) {
    surface(g, 24, 4, 1, |u, v| {
        let phi = TAU * u;
        let p = Vec3::new(r * phi.cos(), height * v - 0.2, r * phi.sin());
        (p, Vec3::new(p.x, 0.0, p.z))
    });
}

/// A parametric surface of `cols × rows` quads (two triangles each) of `material`: `at(u, v)`
/// for u, v in [0, 1] gives a point and a direction its side faces (each triangle is wound so
/// that its normal faces it). Vertex normals are the area-weighted face normals.
fn surface(g: &mut Geometry, cols: u32, rows: u32, material: u32, at: impl Fn(f32, f32) -> (Vec3, Vec3)) {
    let base = g.positions.len() as u32;
    let mut outward = Vec::new();
    for j in 0..=rows {
        for i in 0..=cols {
            let (p, o) = at(i as f32 / cols as f32, j as f32 / rows as f32);
            g.positions.push(p);
            outward.push(o);
        }
    }
    let idx = |i: u32, j: u32| base + j * (cols + 1) + i;
    let mut normals = vec![Vec3::ZERO; outward.len()];
    for j in 0..rows {
        for i in 0..cols {
            for mut t in
                [[idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)], [idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]]
            {
                let p = t.map(|v| g.positions[v as usize]);
                let mut n = (p[1] - p[0]).cross(p[2] - p[0]);
                let facing: Vec3 = t.iter().map(|&v| outward[(v - base) as usize]).sum();
                if n.dot(facing) < 0.0 {
                    t.swap(1, 2);
                    n = -n;
                }
                for &v in &t {
                    normals[(v - base) as usize] += n;
                }
                g.triangles.push(t);
                g.triangle_materials.push(material);
            }
        }
    }
    for (n, o) in normals.iter().zip(&outward) {
        g.normals.push(oct_encode(n.try_normalize().unwrap_or(o.normalize_or(Vec3::Y))));
    }
}

/// A 64-bit hash of the seed, an index and a stream (SplitMix64's finaliser over their mix).
fn hash(seed: u64, i: u64, k: u64) -> u64 {
    let mut z = seed ^ i.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ k.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The top 24 bits of `h` as a number in [0, 1).
fn unit(h: u64) -> f32 {
    (h >> 40) as f32 / (1u64 << 24) as f32
}
