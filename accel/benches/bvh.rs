//! BVH build time and ray throughput.
//!
//! `cargo bench -p furnace-accel` prints a Markdown table (quoted in `BENCHMARKS.md`). Scenes:
//! a generated ~19k-triangle box room (always), and, when the files exist,
//! `/work/shared/scenes/{CornellBox-nvpro, DamagedHelmet, MetalRoughSpheresNoTextures}` with
//! node transforms flattened. For each layout (CWBVH, BVH2; preset chosen by triangle count):
//! build time (median of 3), then Mrays/s for coherent camera rays (a 512×512 pinhole image
//! looking at the scene), incoherent rays (origins uniform in the bounds, directions uniform on
//! the sphere), closest-hit and shadow (any-hit, towards a random point in the bounds), on one
//! thread and on a 2-thread rayon pool; each the best of 3 passes. `--quick` runs 128×128 rays,
//! one pass.

#[path = "../tests/common/mod.rs"]
mod common;

use common::*;
use furnace_accel::{BuildOptions, Bvh, Layout};
use glam::Vec3;
use rayon::prelude::*;
use std::hint::black_box;
use std::path::Path;
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

fn camera_rays(lo: Vec3, hi: Vec3, res: usize) -> Rays {
    let c = (lo + hi) * 0.5;
    let r = (hi - lo).length() * 0.5;
    let eye = c + Vec3::new(0.1, 0.15, 1.0).normalize() * r * 1.6;
    let fwd = (c - eye).normalize();
    let right = fwd.cross(Vec3::Y).normalize();
    let up = right.cross(fwd);
    let tan = (30f32).to_radians().tan();
    let mut rays = Vec::with_capacity(res * res);
    for y in 0..res {
        for x in 0..res {
            let sx = ((x as f32 + 0.5) / res as f32 * 2.0 - 1.0) * tan;
            let sy = (1.0 - (y as f32 + 0.5) / res as f32 * 2.0) * tan;
            rays.push((eye, (fwd + right * sx + up * sy).normalize(), f32::INFINITY));
        }
    }
    rays
}

fn random_rays(lo: Vec3, hi: Vec3, n: usize, seed: u64) -> Rays {
    let mut rng = Rng::new(seed);
    (0..n).map(|_| (rng.vec3(lo, hi), rng.unit_vector(), f32::INFINITY)).collect()
}

fn shadow_rays(lo: Vec3, hi: Vec3, n: usize, seed: u64) -> Rays {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            let o = rng.vec3(lo, hi);
            let target = rng.vec3(lo, hi);
            (o, target - o, 1.0)
        })
        .collect()
}

fn mrays(bvh: &Bvh, rays: &Rays, shadow: bool, threads: Option<&rayon::ThreadPool>, passes: usize) -> f64 {
    let trace = |&(o, d, t): &(Vec3, Vec3, f32)| -> u32 {
        if shadow {
            bvh.occluded(o, d, t) as u32
        } else {
            bvh.closest_hit(o, d, t).map_or(0, |h| h.triangle & 1)
        }
    };
    let mut best = f64::INFINITY;
    for _ in 0..passes {
        let start = Instant::now();
        let acc: u32 = match threads {
            None => rays.iter().map(trace).fold(0, u32::wrapping_add),
            Some(pool) => {
                pool.install(|| rays.par_iter().with_min_len(256).map(trace).reduce(|| 0, u32::wrapping_add))
            }
        };
        black_box(acc);
        best = best.min(start.elapsed().as_secs_f64());
    }
    rays.len() as f64 / best / 1e6
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let (res, passes) = if quick { (128, 1) } else { (512, 3) };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("rayon pool");
    let mut scenes: Vec<(String, Vec<Tri>)> = vec![("generated box room".into(), box_scene(32, 8))];
    let shared = Path::new("/work/shared/scenes");
    for (name, file) in [
        ("CornellBox-nvpro", "CornellBox-nvpro/cornellBox.gltf"),
        ("DamagedHelmet", "DamagedHelmet/glTF/DamagedHelmet.gltf"),
        ("MetalRoughSpheresNoTextures", "MetalRoughSpheresNoTextures/glTF/MetalRoughSpheresNoTextures.gltf"),
    ] {
        let path = shared.join(file);
        if path.exists() {
            match load_gltf(&path) {
                Ok(t) => scenes.push((name.into(), t)),
                Err(e) => eprintln!("skipping {name}: {e}"),
            }
        } else {
            eprintln!("skipping {name}: {} not found", path.display());
        }
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
    for (name, tris) in &scenes {
        let (lo, hi) = bounds(tris);
        let cam = camera_rays(lo, hi, res);
        let inc = random_rays(lo, hi, res * res, 1);
        let sh = shadow_rays(lo, hi, res * res, 2);
        for layout in [Layout::Cwbvh, Layout::Bvh2] {
            let opts = BuildOptions { layout, quality: None };
            let mut times = Vec::new();
            let mut bvh = None;
            for _ in 0..if quick { 1 } else { 3 } {
                let start = Instant::now();
                let b = Bvh::build_with(tris, opts);
                times.push(start.elapsed().as_secs_f64() * 1e3);
                bvh = Some(b);
            }
            times.sort_by(f64::total_cmp);
            let bvh = bvh.expect("built");
            let m = |rays: &Rays, shadow| {
                format!(
                    "{:.1} / {:.1}",
                    mrays(&bvh, rays, shadow, None, passes),
                    mrays(&bvh, rays, shadow, Some(&pool), passes)
                )
            };
            println!(
                "| {name} | {} | {layout:?} | {:?} | {:.0} | {} | {} | {} |",
                tris.len(),
                bvh.quality().expect("non-empty"),
                times[times.len() / 2],
                m(&cam, false),
                m(&inc, false),
                m(&sh, true)
            );
        }
    }
}
