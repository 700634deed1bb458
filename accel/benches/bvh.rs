//! BVH build time and ray throughput.
//!
//! `cargo bench -p furnace-accel` prints a Markdown table (quoted in `BENCHMARKS.md`). Scenes:
//! the built-in reference Cornell box (`furnace_scene::builtin::cornell_box()`), and Khronos'
//! DamagedHelmet and MetalRoughSpheresNoTextures from the repository's `tests/data/scenes/`,
//! loaded with `furnace_scene::Scene::load`. For each layout (CWBVH, BVH2; preset chosen by
//! triangle count): build time (median of 3), then Mrays/s for
//!
//! * coherent closest-hit rays: the scene's default camera, 256×256 pixels, one jittered ray per
//!   pixel, in scanline order;
//! * incoherent closest-hit rays: from a random point on a random triangle (origin moved off the
//!   surface with `offset_ray_origin`) in a direction uniform on the sphere;
//! * incoherent shadow rays: any-hit between two such surface points (`t_max = 1`);
//!
//! on one thread and on a 2-thread rayon pool; each the best of 5 passes over 65 536 rays.
//!
//! Flags: `--quick` (64×64 rays, one pass), `--scene NAME` (only scenes whose name contains
//! NAME), `--cwbvh` (CWBVH only), `--variants` (also time obvhs's own traversal and triangle
//! test on the same tree, and print traversal statistics: see `BENCHMARKS.md`).

#[path = "../tests/common/mod.rs"]
mod common;

use common::Rng;
use furnace_accel::{BuildOptions, Bvh, Layout, offset_ray_origin};
use furnace_scene::Scene;
use glam::{Vec2, Vec3, Vec3A};
use rayon::prelude::*;
use std::hint::black_box;
use std::time::Instant;

fn cpu_name() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

/// (origin, direction, t_max) triples.
type Rays = Vec<(Vec3, Vec3, f32)>;

fn camera_rays(scene: &Scene, res: u32, seed: u64) -> Rays {
    let cam = scene.default_camera();
    let mut rng = Rng::new(seed);
    let mut rays = Vec::with_capacity((res * res) as usize);
    for y in 0..res {
        for x in 0..res {
            let pixel = Vec2::new(x as f32 + rng.f32(), y as f32 + rng.f32());
            let r = cam.generate_ray(pixel, res, res);
            rays.push((r.origin, r.direction, f32::INFINITY));
        }
    }
    rays
}

/// A uniformly random point on a uniformly random (non-degenerate) triangle, and its normal.
fn surface_point(tris: &[[Vec3; 3]], rng: &mut Rng) -> (Vec3, Vec3) {
    loop {
        let [a, b, c] = tris[rng.index(tris.len())];
        let n = (b - a).cross(c - a);
        if !(n.length_squared() > 0.0) || !n.is_finite() {
            continue;
        }
        let (mut u, mut v) = (rng.f32(), rng.f32());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        return (a + (b - a) * u + (c - a) * v, n.normalize());
    }
}

fn random_rays(tris: &[[Vec3; 3]], n: usize, seed: u64) -> Rays {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            let (p, nrm) = surface_point(tris, &mut rng);
            let d = rng.unit_vector();
            let side = if nrm.dot(d) >= 0.0 { nrm } else { -nrm };
            (offset_ray_origin(p, side), d, f32::INFINITY)
        })
        .collect()
}

fn shadow_rays(tris: &[[Vec3; 3]], n: usize, seed: u64) -> Rays {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            let (p, np) = surface_point(tris, &mut rng);
            let (q, nq) = surface_point(tris, &mut rng);
            let d = q - p;
            let o = offset_ray_origin(p, if np.dot(d) >= 0.0 { np } else { -np });
            let t = offset_ray_origin(q, if nq.dot(d) <= 0.0 { nq } else { -nq });
            (o, t - o, 1.0)
        })
        .collect()
}

/// Best-of-`passes` throughput of `trace` over `rays`, in Mrays/s.
fn mrays<F>(rays: &Rays, trace: F, threads: Option<&rayon::ThreadPool>, passes: usize) -> f64
where
    F: Fn(&(Vec3, Vec3, f32)) -> u32 + Sync,
{
    let mut best = f64::INFINITY;
    for _ in 0..passes {
        let start = Instant::now();
        let acc: u32 = match threads {
            None => rays.iter().map(&trace).fold(0, u32::wrapping_add),
            Some(pool) => {
                pool.install(|| rays.par_iter().with_min_len(256).map(&trace).reduce(|| 0, u32::wrapping_add))
            }
        };
        black_box(acc);
        best = best.min(start.elapsed().as_secs_f64());
    }
    rays.len() as f64 / best / 1e6
}

fn closest(bvh: &Bvh) -> impl Fn(&(Vec3, Vec3, f32)) -> u32 + Sync + '_ {
    |&(o, d, t)| bvh.closest_hit(o, d, t).map_or(0, |h| h.triangle & 1)
}

fn shadow(bvh: &Bvh) -> impl Fn(&(Vec3, Vec3, f32)) -> u32 + Sync + '_ {
    |&(o, d, t)| bvh.occluded(o, d, t) as u32
}

/// `--variants`: obvhs's own traversal (`CwBvh::ray_traverse`) and triangle test on an obvhs
/// tree of the same preset, for comparison with the wrapper; plus per-ray statistics.
mod variants {
    use super::*;
    use furnace_accel::intersect_triangle;
    use obvhs::{
        cwbvh::{CwBvh, builder::build_cwbvh_from_tris},
        ray::{Ray, RayHit},
        triangle::Triangle,
    };
    use std::time::Duration;

    pub struct Raw {
        bvh: CwBvh,
        tris: Vec<Triangle>,
        plain: Vec<[Vec3; 3]>,
    }

    pub fn build(tris: &[[Vec3; 3]], bvh: &Bvh) -> Raw {
        let input: Vec<Triangle> =
            tris.iter().map(|t| Triangle { v0: t[0].into(), v1: t[1].into(), v2: t[2].into() }).collect();
        let params = bvh.quality().expect("non-empty").params();
        let cw = build_cwbvh_from_tris(&input, params, &mut Duration::default());
        let leaf: Vec<Triangle> = cw.primitive_indices.iter().map(|&i| input[i as usize]).collect();
        let plain = leaf.iter().map(|t| [t.v0.into(), t.v1.into(), t.v2.into()]).collect();
        Raw { bvh: cw, tris: leaf, plain }
    }

    fn ray(o: Vec3, d: Vec3, t: f32) -> Ray {
        Ray::new(Vec3A::from(o), Vec3A::from(d), 0.0, t)
    }

    /// obvhs traversal + obvhs's Möller–Trumbore (`Triangle::intersect`).
    pub fn obvhs_closest(raw: &Raw) -> impl Fn(&(Vec3, Vec3, f32)) -> u32 + Sync + '_ {
        |&(o, d, t)| {
            let mut hit = RayHit::none();
            raw.bvh.ray_traverse(ray(o, d, t), &mut hit, |r, i| raw.tris[i].intersect(r));
            hit.primitive_id & 1
        }
    }

    /// obvhs traversal + this crate's `intersect_triangle`, no direction scaling.
    pub fn obvhs_ours(raw: &Raw) -> impl Fn(&(Vec3, Vec3, f32)) -> u32 + Sync + '_ {
        |&(o, d, t)| {
            let mut hit = RayHit::none();
            raw.bvh.ray_traverse(ray(o, d, t), &mut hit, |r, i| {
                intersect_triangle(o, d, raw.plain[i], r.tmax).map_or(f32::INFINITY, |h| h.t)
            });
            hit.primitive_id & 1
        }
    }

    /// obvhs's traversal loop (its `traverse!` macro, what `CwBvh::ray_traverse` expands to)
    /// with nodes visited and triangles tested counted: (nodes, tests) per ray, one thread.
    pub fn stats(raw: &Raw, rays: &Rays) -> (f64, f64) {
        use glam::UVec2;
        let (mut nodes, mut tests) = (0u64, 0u64);
        for &(o, d, t) in rays {
            let mut r = ray(o, d, t);
            let mut state = raw.bvh.new_traversal(r.direction);
            let mut node;
            obvhs::traverse!(
                raw.bvh,
                node,
                state,
                {
                    nodes += 1;
                    node.intersect_ray(&r, state.oct_inv4)
                },
                {
                    tests += 1;
                    let h = raw.tris[state.primitive_id as usize].intersect(&r);
                    if h < r.tmax {
                        r.tmax = h;
                    }
                }
            );
        }
        let n = rays.len() as f64;
        (nodes as f64 / n, tests as f64 / n)
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let quick = args.iter().any(|a| a == "--quick");
    let with_variants = args.iter().any(|a| a == "--variants");
    let cwbvh_only = args.iter().any(|a| a == "--cwbvh");
    let filter = args.iter().position(|a| a == "--scene").and_then(|i| args.get(i + 1)).cloned();
    let (res, passes) = if quick { (64u32, 1) } else { (256u32, 5) };
    let n = (res * res) as usize;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("rayon pool");

    let mut scenes: Vec<(String, Scene)> = Vec::new();
    match furnace_scene::builtin::cornell_box() {
        Ok(s) => scenes.push(("cbox (builtin)".into(), s)),
        Err(e) => eprintln!("skipping the built-in Cornell box: {e}"),
    }
    for (name, file) in [
        ("DamagedHelmet", "DamagedHelmet/glTF-Binary/DamagedHelmet.glb"),
        (
            "MetalRoughSpheresNoTextures",
            "MetalRoughSpheresNoTextures/glTF-Binary/MetalRoughSpheresNoTextures.glb",
        ),
    ] {
        let path = furnace_tests::data::scene(file);
        match Scene::load(&path) {
            Ok(s) => scenes.push((name.into(), s)),
            Err(e) => eprintln!("skipping {name}: {e}"),
        }
    }
    if let Some(f) = &filter {
        scenes.retain(|(name, _)| name.contains(f.as_str()));
    }

    println!(
        "furnace-accel, {} ({} threads available), {res}×{res} rays per measurement, best of {passes}\n",
        cpu_name(),
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    println!(
        "| scene | triangles | layout | preset | build ms (1 thread) | coherent closest 1T / 2T | incoherent closest 1T / 2T | incoherent shadow 1T / 2T |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let mut notes = Vec::new();
    for (name, scene) in &scenes {
        let g = &scene.geometry;
        let tris: Vec<[Vec3; 3]> = (0..g.triangle_count()).filter_map(|t| g.triangle(t)).collect();
        let cam = camera_rays(scene, res, 1);
        let inc = random_rays(&tris, n, 2);
        let sh = shadow_rays(&tris, n, 3);
        let layouts: &[Layout] = if cwbvh_only { &[Layout::Cwbvh] } else { &[Layout::Cwbvh, Layout::Bvh2] };
        for &layout in layouts {
            let opts = BuildOptions { layout, quality: None };
            let mut times = Vec::new();
            let mut bvh = None;
            for _ in 0..if quick { 1 } else { 3 } {
                let start = Instant::now();
                let b = Bvh::build_with(&tris, opts);
                times.push(start.elapsed().as_secs_f64() * 1e3);
                bvh = Some(b);
            }
            times.sort_by(f64::total_cmp);
            let bvh = bvh.expect("built");
            let both = |rays: &Rays, sh: bool| {
                let (a, b) = if sh {
                    (mrays(rays, shadow(&bvh), None, passes), mrays(rays, shadow(&bvh), Some(&pool), passes))
                } else {
                    (
                        mrays(rays, closest(&bvh), None, passes),
                        mrays(rays, closest(&bvh), Some(&pool), passes),
                    )
                };
                format!("{a:.1} / {b:.1}")
            };
            println!(
                "| {name} | {} | {layout:?} | {:?} | {:.0} | {} | {} | {} |",
                tris.len(),
                bvh.quality().expect("non-empty"),
                times[times.len() / 2],
                both(&cam, false),
                both(&inc, false),
                both(&sh, true)
            );
            if with_variants && layout == Layout::Cwbvh {
                let raw = variants::build(&tris, &bvh);
                for (what, rays) in [("coherent", &cam), ("incoherent", &inc)] {
                    let ours = mrays(rays, closest(&bvh), None, passes);
                    let obvhs = mrays(rays, variants::obvhs_closest(&raw), None, passes);
                    let mixed = mrays(rays, variants::obvhs_ours(&raw), None, passes);
                    let (nodes, tests) = variants::stats(&raw, rays);
                    notes.push(format!(
                        "{name} {what} closest 1T: furnace {ours:.2}, obvhs traversal + obvhs triangle {obvhs:.2}, \
                         obvhs traversal + furnace triangle {mixed:.2} Mrays/s; {nodes:.1} nodes visited, {tests:.1} triangle tests per ray"
                    ));
                }
            }
        }
    }
    for n in notes {
        println!("\n{n}");
    }
}
