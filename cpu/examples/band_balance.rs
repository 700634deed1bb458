//! How evenly a render splits among N devices by image region: the CPU reference's time per
//! row of a scene (its paths' cost, a proxy for a GPU's), then the slowest share against the
//! mean for N contiguous horizontal bands, and for bands of 16 rows dealt round-robin. A device
//! given a share of every pass's samples instead (furnace's `--gpus`) renders every pixel: its
//! share is even by construction. The figures in `BENCHMARKS.md` ("Several GPUs") came from it.
//!
//! ```sh
//! cargo run --release -p furnace-cpu --example band_balance -- SCENE WIDTH HEIGHT SPP BOUNCES
//! ```
//!
//! `SCENE`: `cbox` (the built-in box), `interior:N` (the sunlit interior of about N triangles)
//! or a glTF path.

use furnace_cpu::CpuRenderer;
use furnace_render::RenderSettings;
use furnace_sampling::SamplerKind;
use rayon::prelude::*;
use std::time::Instant;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, w, h, spp, bounces] = &args[..] else {
        return Err("usage: band_balance SCENE WIDTH HEIGHT SPP BOUNCES".into());
    };
    let number = |s: &str| s.parse::<u32>().map_err(|_| format!("'{s}' is not a whole number"));
    let (w, h, spp, bounces) = (number(w)?, number(h)?, number(spp)?, number(bounces)?);
    let loaded = match scene.as_str() {
        "cbox" => furnace_scene::builtin::cornell_box().map_err(|e| e.to_string())?,
        s if s.starts_with("interior:") => {
            let n: f64 = s["interior:".len()..].parse().map_err(|_| format!("'{s}': interior:N"))?;
            furnace_scene::builtin::sunlit_interior(n as u32)
        }
        path => furnace_scene::Scene::load(std::path::Path::new(path)).map_err(|e| e.to_string())?,
    };
    let settings = RenderSettings {
        width: w,
        height: h,
        bounces,
        sampler: SamplerKind::Random,
        ..RenderSettings::default()
    };
    let r = CpuRenderer::with_default_camera(loaded, settings).map_err(|e| e.to_string())?;
    // Each row timed alone (rows in parallel, so the figures are the rows' own costs).
    let rows: Vec<f64> = (0..h)
        .into_par_iter()
        .map(|y| {
            let t = Instant::now();
            let mut sum = 0.0f32;
            for x in 0..w {
                for i in 0..spp {
                    sum += r.sample(x, y, i).x;
                }
            }
            std::hint::black_box(sum);
            t.elapsed().as_secs_f64()
        })
        .collect();
    let total: f64 = rows.iter().sum();
    for n in [2usize, 4, 8] {
        let mean = total / n as f64;
        let band = |k: usize| rows[k * rows.len() / n..(k + 1) * rows.len() / n].iter().sum::<f64>();
        let contiguous = (0..n).map(band).fold(0.0, f64::max) / mean;
        let dealt = |k: usize| {
            rows.iter().enumerate().filter(|(y, _)| (y / 16) % n == k).map(|(_, t)| t).sum::<f64>()
        };
        let round_robin = (0..n).map(dealt).fold(0.0, f64::max) / mean;
        println!(
            "{scene} {w}×{h}, {n} devices: slowest share / mean: contiguous bands {contiguous:.3}, 16-row bands round-robin {round_robin:.3}"
        );
    }
    Ok(())
}
