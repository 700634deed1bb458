//! Shared by the integration tests and the benchmark: generated meshes, a glTF
//! flattener, ray generators and brute-force references.
#![allow(dead_code)] // each test binary uses a different subset

use furnace_accel::{Hit, intersect_triangle};
use glam::{DMat4, DVec3, Mat4, Vec2, Vec3};
use std::path::{Path, PathBuf};

pub type Tri = [Vec3; 3];

pub use furnace_tests::Rng;

/// `n` random triangles in the unit cube, edge lengths up to `size`.
pub fn random_soup(n: usize, size: f32, seed: u64) -> Vec<Tri> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            let c = rng.vec3(Vec3::ZERO, Vec3::ONE);
            [
                c,
                c + rng.unit_vector() * rng.range(0.1, 1.0) * size,
                c + rng.unit_vector() * rng.range(0.1, 1.0) * size,
            ]
        })
        .collect()
}

/// Unit sphere at the origin: an octahedron subdivided `levels` times, 8·4^levels triangles.
pub fn sphere(levels: u32) -> Vec<Tri> {
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let mut tris: Vec<Tri> = Vec::new();
    for sx in [-1.0f32, 1.0] {
        for sy in [-1.0f32, 1.0] {
            for sz in [-1.0f32, 1.0] {
                let t = [x * sx, y * sy, z * sz];
                // Keep outward winding.
                if sx * sy * sz > 0.0 {
                    tris.push(t);
                } else {
                    tris.push([t[0], t[2], t[1]]);
                }
            }
        }
    }
    for _ in 0..levels {
        tris = tris
            .iter()
            .flat_map(|&[a, b, c]| {
                let ab = (a + b).normalize();
                let bc = (b + c).normalize();
                let ca = (c + a).normalize();
                [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            })
            .collect();
    }
    tris
}

/// Two triangles for the quad `o, o+u, o+u+v, o+v`.
pub fn quad(o: Vec3, u: Vec3, v: Vec3) -> [Tri; 2] {
    [[o, o + u, o + u + v], [o, o + u + v, o + v]]
}

/// An axis-aligned box as 12 triangles.
pub fn cuboid(min: Vec3, max: Vec3) -> Vec<Tri> {
    let d = max - min;
    let (dx, dy, dz) = (Vec3::X * d.x, Vec3::Y * d.y, Vec3::Z * d.z);
    let mut t = Vec::new();
    t.extend(quad(min, dy, dx));
    t.extend(quad(min + dz, dx, dy));
    t.extend(quad(min, dz, dy));
    t.extend(quad(min + dx, dy, dz));
    t.extend(quad(min, dx, dz));
    t.extend(quad(min + dy, dz, dx));
    t
}

/// A Cornell-box-like room of size 1 (floor, ceiling, three walls, a light quad just below the
/// ceiling, two boxes, each wall tessellated `n × n`).
pub fn cornell_room(n: usize) -> Vec<Tri> {
    let mut t = Vec::new();
    let s = 1.0 / n as f32;
    let walls = [
        (Vec3::ZERO, Vec3::X, Vec3::Z), // floor
        (Vec3::Y, Vec3::Z, Vec3::X),    // ceiling
        (Vec3::Z, Vec3::X, Vec3::Y),    // back
        (Vec3::ZERO, Vec3::Y, Vec3::Z), // left
        (Vec3::X, Vec3::Z, Vec3::Y),    // right
    ];
    for (o, u, v) in walls {
        for i in 0..n {
            for j in 0..n {
                t.extend(quad(o + u * (i as f32 * s) + v * (j as f32 * s), u * s, v * s));
            }
        }
    }
    t.extend(quad(Vec3::new(0.4, 0.999, 0.4), Vec3::Z * 0.2, Vec3::X * 0.2));
    t.extend(cuboid(Vec3::new(0.15, 0.0, 0.55), Vec3::new(0.45, 0.6, 0.85)));
    t.extend(cuboid(Vec3::new(0.55, 0.0, 0.15), Vec3::new(0.85, 0.3, 0.45)));
    t
}

/// A box room of `n`×`n` tessellated walls with `k`×`k` cubes on the floor: the benchmark's
/// generated ~20k-triangle scene (n = 32, k = 8: 10 266 room + 64 × 140 cube-and-sphere = 19 226).
pub fn box_scene(n: usize, k: usize) -> Vec<Tri> {
    let mut t = cornell_room(n);
    let step = 1.0 / k as f32;
    for i in 0..k {
        for j in 0..k {
            let lo = Vec3::new((i as f32 + 0.2) * step, 0.0, (j as f32 + 0.2) * step);
            let h = 0.05 + 0.3 * (((i * 7 + j * 3) % 5) as f32 / 5.0);
            t.extend(sphere_at(lo + Vec3::new(0.3 * step, h + 0.25 * step, 0.3 * step), 0.25 * step, 2));
            t.extend(cuboid(lo, lo + Vec3::new(0.6 * step, h, 0.6 * step)));
        }
    }
    t
}

fn sphere_at(c: Vec3, r: f32, levels: u32) -> Vec<Tri> {
    sphere(levels).into_iter().map(|t| t.map(|v| c + v * r)).collect()
}

pub fn scale_mesh(tris: &[Tri], s: f32) -> Vec<Tri> {
    tris.iter().map(|t| t.map(|v| v * s)).collect()
}

pub fn bounds(tris: &[Tri]) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for t in tris {
        for v in t {
            if v.is_finite() {
                lo = lo.min(*v);
                hi = hi.max(*v);
            }
        }
    }
    (lo, hi)
}

/// Every triangle of the default scene of a glTF file, node transforms applied (flattened).
pub fn load_gltf(path: &Path) -> Result<Vec<Tri>, String> {
    // Without validation: CornellBox-nvpro has an out-of-range texture source, irrelevant here.
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let gltf =
        gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    let buffers = gltf::import_buffers(&gltf.document, path.parent(), gltf.blob.clone())
        .map_err(|e| format!("{}: {e}", path.display()))?;
    let mut out = Vec::new();
    let scene = gltf
        .document
        .default_scene()
        .or_else(|| gltf.document.scenes().next())
        .ok_or_else(|| format!("{}: no scene", path.display()))?;
    fn walk(node: gltf::Node, parent: DMat4, buffers: &[gltf::buffer::Data], out: &mut Vec<Tri>) {
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if let Some(mesh) = node.mesh() {
            let m = Mat4::from_cols_array(&world.to_cols_array().map(|x| x as f32));
            for prim in mesh.primitives() {
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    continue;
                }
                let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                let Some(pos) = reader.read_positions() else {
                    continue;
                };
                let pos: Vec<Vec3> = pos.map(|p| m.transform_point3(Vec3::from(p))).collect();
                let idx: Vec<u32> = match reader.read_indices() {
                    Some(i) => i.into_u32().collect(),
                    None => (0..pos.len() as u32).collect(),
                };
                for c in idx.chunks_exact(3) {
                    out.push([c[0], c[1], c[2]].map(|i| pos[i as usize]));
                }
            }
        }
        for child in node.children() {
            walk(child, world, buffers, out);
        }
    }
    for node in scene.nodes() {
        walk(node, DMat4::IDENTITY, &buffers, &mut out);
    }
    Ok(out)
}

/// The test scenes of the workspace (`tests/data/scenes/`).
pub fn data_dir() -> PathBuf {
    furnace_tests::data::scene("")
}

/// Where failing or reporting tests write their tables.
pub fn output_dir() -> PathBuf {
    furnace_tests::data::output_dir("accel")
}

/// A mix of rays for a mesh with bounds `(lo, hi)`: half start inside the (slightly grown)
/// bounds in uniform directions, half start outside and aim at a random point inside.
pub fn random_rays(lo: Vec3, hi: Vec3, n: usize, seed: u64) -> Vec<(Vec3, Vec3)> {
    let mut rng = Rng::new(seed);
    let c = (lo + hi) * 0.5;
    let r = (hi - lo).length().max(f32::MIN_POSITIVE);
    (0..n)
        .map(|i| {
            if i % 2 == 0 {
                let o = rng.vec3(lo - (hi - lo) * 0.05, hi + (hi - lo) * 0.05);
                (o, rng.unit_vector())
            } else {
                let o = c + rng.unit_vector() * r * 1.5;
                let target = rng.vec3(lo, hi);
                (o, (target - o).normalize())
            }
        })
        .collect()
}

/// Brute-force closest hit with the crate's own f32 test: the bit-exact reference.
pub fn brute_f32(
    tris: &[Tri],
    o: Vec3,
    d: Vec3,
    t_max: f32,
    mut mask: impl FnMut(u32, Vec2) -> bool,
) -> Option<Hit> {
    let mut best: Option<Hit> = None;
    let mut cur = t_max;
    for (i, t) in tris.iter().enumerate() {
        if !t.iter().all(|v| v.is_finite()) {
            continue;
        }
        if let Some(h) = intersect_triangle(o, d, *t, cur)
            && mask(i as u32, h.barycentrics)
        {
            cur = h.t;
            best = Some(Hit { triangle: i as u32, t: h.t, barycentrics: h.barycentrics });
        }
    }
    best
}

/// Independent reference: Möller–Trumbore in f64 on the same (f32) vertices.
pub fn brute_f64(tris: &[Tri], o: Vec3, d: Vec3) -> Option<(u32, f64)> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let mut best: Option<(u32, f64)> = None;
    for (i, t) in tris.iter().enumerate() {
        let [v0, v1, v2]: [DVec3; 3] = t.map(|v| v.as_dvec3());
        let e1 = v1 - v0;
        let e2 = v2 - v0;
        let p = d.cross(e2);
        let det = e1.dot(p);
        if !(det != 0.0) || !det.is_finite() {
            continue;
        }
        let s = o - v0;
        let u = s.dot(p) / det;
        let q = s.cross(e1);
        let v = d.dot(q) / det;
        let tt = e2.dot(q) / det;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && tt > 0.0 && best.is_none_or(|b| tt < b.1) {
            best = Some((i as u32, tt));
        }
    }
    best
}
