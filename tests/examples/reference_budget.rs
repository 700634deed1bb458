//! How many samples, in how many batches, does the CPU half of `tests/mitsuba.rs` need to meet its bar
//! (per-channel image-mean ratio within ±0.5%, per-pixel z std in [0.9, 1.15]) reliably?
//!
//! ```sh
//! cargo run --release -p furnace-tests --example reference_budget -- --bounces 4 --seeds 3 --max-spp 2048
//! ```
//!
//! Renders the built-in Cornell box at 256² (Mitsuba's model, random sampler, seeds
//! `--first-seed` (100), 101, …) once per seed with `--max-spp` samples per pixel and evaluates, from that
//! one render, every prefix N ∈ {64, 128, …, max} with the standard error estimated from
//! batches of b ∈ {1, 2, 4, …} consecutive samples (b = 1: the per-sample variance; N/b
//! batches, at least 4). Prints a Markdown table (z statistics against the reference of that
//! bounce count) and writes it as CSV to `target/reference_budget.csv`.

use furnace_brdf::SpecularOptions;
use furnace_cpu::CpuRenderer;
use furnace_render::RenderSettings;
use furnace_sampling::SamplerKind;
use furnace_tests::cbox::{self, BatchEstimator, Estimate, Image, Reference};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::time::Instant;

const BATCHES: [u32; 10] = [1, 2, 4, 8, 16, 32, 64, 128, 256, 512];

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let flag = |name: &str, default: u32| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .and_then(|s| s.parse().ok())
            .unwrap_or(default)
    };
    let (bounces, seeds, max_spp) = (flag("--bounces", 4), flag("--seeds", 1), flag("--max-spp", 1024));
    let min_batches = flag("--min-batches", 4);
    let first_seed = flag("--first-seed", 100);
    let stem = if bounces == 1 { "cbox_ref_direct" } else { "cbox_ref_bounces4" };
    assert!(bounces == 1 || bounces == 4, "references exist for 1 and 4 bounces");
    let reference = Reference::load(stem);
    let (w, h) = (reference.mean.width, reference.mean.height);
    let checkpoints: Vec<u32> = (6..=20).map(|k| 1u32 << k).filter(|&n| n <= max_spp).collect();
    let configs: Vec<(u32, u32)> = checkpoints
        .iter()
        .flat_map(|&n| BATCHES.iter().filter(move |&&b| n / b >= min_batches).map(move |&b| (n, b)))
        .collect();
    let mut table = String::new();
    let mut csv =
        String::from("bounces,seed,spp,batch,batches,ratio_r,ratio_g,ratio_b,z_mean,z_std,z_over_3,z_max\n");
    println!("{stem} ({bounces} bounces), 256², mean rel. stderr of the reference: see its JSON");
    println!(
        "| seed | spp | batch | batches | ratio R, G, B | z mean | z std | \\|z\\|>3 | max \\|z\\| (pixel) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for seed in first_seed..first_seed + seeds {
        let settings = RenderSettings {
            width: w as u32,
            height: h as u32,
            bounces,
            sampler: SamplerKind::Random,
            seed,
            specular: SpecularOptions::mitsuba(),
            ..Default::default()
        };
        let scene = furnace_scene::builtin::cornell_box().expect("the built-in Cornell box");
        let renderer = CpuRenderer::with_default_camera(scene, settings).expect("a progressive sampler");
        let start = Instant::now();
        // For each pixel, (mean, se) of every config, in `configs` order.
        let per_pixel: Vec<Vec<(Vec3, Vec3)>> = (0..w * h)
            .into_par_iter()
            .map(|i| {
                let (x, y) = ((i % w) as u32, (i / w) as u32);
                let mut estimators: Vec<BatchEstimator> =
                    BATCHES.iter().map(|&b| BatchEstimator::new(b)).collect();
                let mut out = Vec::with_capacity(configs.len());
                let mut next = 0;
                for index in 0..max_spp {
                    let v = renderer.sample(x, y, index).as_dvec3();
                    estimators.iter_mut().for_each(|e| e.push(v));
                    while next < configs.len() && configs[next].0 == index + 1 {
                        let b = configs[next].1;
                        let (m, s) = estimators[BATCHES.iter().position(|&x| x == b).unwrap()].estimate();
                        out.push((m.as_vec3(), s.as_vec3()));
                        next += 1;
                    }
                }
                out
            })
            .collect();
        let seconds = start.elapsed().as_secs_f64();
        eprintln!(
            "seed {seed}: {max_spp} spp in {seconds:.1} s ({:.2} Msamples/s)",
            (w * h) as f64 * f64::from(max_spp) / seconds / 1e6
        );
        for (k, &(n, b)) in configs.iter().enumerate() {
            let image = |f: &dyn Fn(&(Vec3, Vec3)) -> Vec3| Image {
                width: w,
                height: h,
                pixels: per_pixel.iter().map(|p| f(&p[k]).as_dvec3()).collect::<Vec<DVec3>>(),
            };
            let estimate = Estimate { mean: image(&|p| p.0), stderr: image(&|p| p.1) };
            let c = cbox::compare(&estimate, &reference);
            let r = c.ratio();
            writeln!(
                table,
                "| {seed} | {n} | {b} | {} | {:.4}, {:.4}, {:.4} | {:+.3} | {:.3} | {:.4} | {:.1} ({}, {}) |",
                n / b,
                r.x,
                r.y,
                r.z,
                c.z_mean,
                c.z_std,
                c.z_over_3,
                c.z_max.0,
                c.z_max.1,
                c.z_max.2
            )
            .unwrap();
            writeln!(
                csv,
                "{bounces},{seed},{n},{b},{},{},{},{},{},{},{},{}",
                n / b,
                r.x,
                r.y,
                r.z,
                c.z_mean,
                c.z_std,
                c.z_over_3,
                c.z_max.0
            )
            .unwrap();
        }
        print!("{table}");
        table.clear();
    }
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(format!("../target/reference_budget_b{bounces}.csv"));
    std::fs::write(&path, csv).expect("writing the CSV");
    eprintln!("CSV: {}", path.display());
}
